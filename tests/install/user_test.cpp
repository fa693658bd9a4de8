// What a user writes against the installed package: a virtual line of two drives, one enabled and moved
// in CSP, a cable break injected and seen by the master.
#include <gtest/gtest.h>

#include "testing/virtual_segment.hpp"

TEST(UserTest, EnableMoveAndBreakTheCable) {
    vecat::testing::VirtualSegment vs({.drives = 2});
    ASSERT_TRUE(vs.enable(0));
    const std::int32_t p0 = vs.position(0);
    for (int k = 1; k <= 100; ++k) {
        vs.set_target_position(0, p0 + 20 * k);
        ASSERT_TRUE(vs.cycle());
    }
    vs.cycles(20);
    EXPECT_NEAR(vs.position(0), p0 + 2000, 20);
    ASSERT_EQ(vs.fault("inject link_down slave=0 port=1").rfind("ok", 0), 0u);
    EXPECT_EQ(vs.master().count_slaves(), 1);
}
