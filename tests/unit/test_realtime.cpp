// Real-time helpers of the transport: pinning takes effect, bad requests are refused with a reason.
#include <gtest/gtest.h>
#include <sched.h>

#include <thread>

#include "net/realtime.hpp"

using namespace vecat;

TEST(Realtime, PinningMovesTheThreadAndRefusesCpusThatDoNotExist) {
    std::string why;
    bool pinned = false;
    int cpu = -2;
    std::thread t([&] {
        pinned = net::pin_current_thread(0, &why);
        cpu = sched_getcpu();
    });
    t.join();
    ASSERT_TRUE(pinned) << why;
    EXPECT_EQ(cpu, 0);
    EXPECT_FALSE(net::pin_current_thread(-1, &why));
    EXPECT_FALSE(why.empty());
    why.clear();
    EXPECT_FALSE(net::pin_current_thread(CPU_SETSIZE - 1, &why));  // no machine here has 1024 CPUs
    EXPECT_FALSE(why.empty());
}

TEST(Realtime, FifoPriorityOutOfRangeIsRefused) {
    std::string why;
    bool ok = true;
    std::thread t([&] { ok = net::set_current_thread_fifo(1000, &why); });
    t.join();
    EXPECT_FALSE(ok);
    EXPECT_NE(why.find("SCHED_FIFO"), std::string::npos);
}
