// vecat::testing as a user sees it: a virtual segment brought up, driven in simulated time, faults by
// their text commands, telemetry recorded in-process, and the veth mode with the project's master as the
// "user's own" master on the other end.
#include <gtest/gtest.h>

#include <cstdlib>

#include "net/raw_socket.hpp"
#include "protocol/cia402.hpp"
#include "testing/virtual_segment.hpp"

namespace cia = vecat::protocol::cia402;

namespace vecat::testing {
namespace {

TEST(VirtualSegment, BringsTheDrivesToOpAndEnablesThem) {
    VirtualSegment vs({.drives = 2});
    ASSERT_EQ(vs.size(), 2u);
    ASSERT_EQ(vs.master().slaves().size(), 2u);
    for (std::size_t i = 0; i < 2; ++i)
        EXPECT_EQ(vs.master().read_al_status(vs.station(i)).state(), protocol::AlState::Op);
    EXPECT_TRUE(vs.cycles(10));
    EXPECT_EQ(vs.last_wkc(), vs.master().expected_wkc());
    const std::uint64_t t0 = vs.now_ns();
    ASSERT_TRUE(vs.enable(0));
    EXPECT_GT(vs.now_ns(), t0);  // enabling took simulated cycles
    EXPECT_EQ(cia::decode_state(vs.statusword(0)), cia::State::OperationEnabled);
    EXPECT_NE(vs.drive(1).cia402_state(), cia402::State::OperationEnabled);
    // A CSP set-point is followed.
    const std::int32_t p0 = vs.position(0);
    for (int k = 1; k <= 200; ++k) {
        vs.set_target_position(0, p0 + 50 * k);
        ASSERT_TRUE(vs.cycle());
    }
    vs.cycles(20);
    EXPECT_NEAR(vs.position(0), p0 + 10000, 50);
}

TEST(VirtualSegment, FaultsByTextCommandsAsTheMasterSeesThem) {
    VirtualSegment vs({.drives = 3});
    ASSERT_TRUE(vs.cycles(5));
    const std::string r = vs.fault("inject link_down slave=1 port=1 id=cut");
    ASSERT_EQ(r.rfind("ok", 0), 0u) << r;
    EXPECT_NE(vs.fault("list").find("cut"), std::string::npos);
    // The third drive is behind the cut: the LRW working counter lacks its share.
    EXPECT_FALSE(vs.cycle());
    EXPECT_LT(vs.last_wkc(), vs.master().expected_wkc());
    EXPECT_EQ(vs.master().count_slaves(), 2);
    EXPECT_EQ(vs.fault("clear cut").rfind("ok", 0), 0u);
    EXPECT_EQ(vs.master().count_slaves(), 3);
    EXPECT_EQ(vs.fault("inject no_such_fault").rfind("error", 0), 0u);
}

TEST(VirtualSegment, TwinsyncPresetAndRecording) {
    VirtualSegment vs({.drives = 2, .twinsync = cia402::TwinsyncPreset::Gantry});
    vs.cycles(50);
    ASSERT_NE(vs.drive(1).twinsync_status(), nullptr);
    EXPECT_TRUE(vs.drive(1).twinsync_status()->synchronised);
    vs.start_recording();
    ASSERT_TRUE(vs.enable(0));
    vs.cycles(10);
    EXPECT_EQ(vs.drive(1).cia402_state(), cia402::State::OperationEnabled);  // followed the master drive
    const telemetry::Recording rec = vs.stop_recording();
    ASSERT_FALSE(rec.axes.empty());
    EXPECT_FALSE(rec.events.empty());  // the CiA 402 state changes
    EXPECT_EQ(rec.axes.back().cia402_state, static_cast<std::uint8_t>(cia402::State::OperationEnabled));
    EXPECT_FALSE(vs.recording());
}

TEST(VirtualSegment, RefusesWhatCannotWork) {
    EXPECT_THROW(VirtualSegment({.drives = 0}), std::invalid_argument);
    EXPECT_THROW(VirtualSegment({.drives = 1, .twinsync = cia402::TwinsyncPreset::Gantry}),
                 std::invalid_argument);
}

// Veth mode: moves this test process into a private network namespace (the last test of the binary,
// and only when root).
TEST(VethSegment, AMasterOnTheOtherEndFindsTheDrives) {
    if (!veth_available()) GTEST_SKIP() << "needs root for a private network namespace";
    VethSegment vs({.segment = {.drives = 2}});
    net::RawSocket sock(vs.master_interface());
    master::Master m(sock);
    std::string why;
    ASSERT_TRUE(m.startup(protocol::AlState::Op, &why)) << why;
    EXPECT_EQ(m.slaves().size(), 2u);
    for (int i = 0; i < 50; ++i)
        ASSERT_EQ(m.exchange_process_data().value_or(0), m.expected_wkc());
    const std::string r = vs.fault("inject link_down slave=0 port=1 id=cut");
    ASSERT_EQ(r.rfind("ok", 0), 0u) << r;
    EXPECT_EQ(m.count_slaves(), 1);
    EXPECT_GT(vs.frames_received(), 50u);
    vs.stop();
}

}  // namespace
}  // namespace vecat::testing
