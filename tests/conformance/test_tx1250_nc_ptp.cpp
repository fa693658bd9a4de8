// Conformance to the Beckhoff TwinCAT 2 NC PTP manual TX1250 (../shared/seeds/002_e8a90447e16f9bd4.txt):
// the profile generator of the drive's profile modes follows the NC's master axis (chapter 2), and two
// drives coupled by TWINsync behave as its master/slave groups (chapter 3). One test per behaviour, named
// after the section it checks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "drive_core_bench.hpp"
#include "unit/cia402/twin_bench.hpp"

namespace vecat::cia402::conformance {
namespace {

struct Tx1250 : DriveCoreBench {
    // A profile position move started with the bit 4 handshake.
    void start_move(std::int32_t target, std::uint16_t extra = 0) {
        io.command.target_position = target;
        io.command.controlword = cmd::EnableOperation | cw::NewSetpoint | extra;
        run_ms(1);
        io.command.controlword = cmd::EnableOperation;
    }
    double demand_velocity() const { return io.feedback.velocity_demand; }
};

// 2.2 Override: the override scales the target velocity online (0x2110, ppm of 100 %), "reaching the new
// velocity level as quickly as possible"; back to 100 % the axis returns to V.
TEST_F(Tx1250, Tx1250_2_2_OverrideChangesTheVelocityOnline) {
    enable(Mode::ProfilePosition);
    start_move(20 * kRev);
    run_ms(300);
    EXPECT_NEAR(demand_velocity(), 2 * kRev, 1);
    io.parameters.velocity_override = 750'000;
    run_ms(300);
    EXPECT_NEAR(demand_velocity(), 1.5 * kRev, 1);
    io.parameters.velocity_override = 1'000'000;
    run_ms(300);
    EXPECT_NEAR(demand_velocity(), 2 * kRev, 1);
}

// 2.2 Stop: "stop is realized via override 0.0"; the axis stops on its braking ramp, holds, and goes on to
// its target once the override is raised again.
TEST_F(Tx1250, Tx1250_2_2_StopIsOverrideZero) {
    enable(Mode::ProfilePosition);
    const std::int32_t target = 6 * kRev;
    start_move(target);
    run_ms(300);
    io.parameters.velocity_override = 0;
    run_ms(400);
    EXPECT_EQ(demand_velocity(), 0);
    const std::int32_t held = io.feedback.position_actual;
    run_ms(200);
    EXPECT_NEAR(io.feedback.position_actual, held, 50);
    EXPECT_LT(held, target - kRev);
    io.parameters.velocity_override = 1'000'000;
    run_ms(4000);
    EXPECT_NEAR(io.feedback.position_actual, target, 100);
    EXPECT_TRUE(target_reached());
}

// 2.3 New end position: "if the axis has exceeded the new target or cannot be stopped before it, the axis
// is stopped internally and then automatically moved back to the new target position" (PP change set
// immediately, bit 5).
TEST_F(Tx1250, Tx1250_2_3_NewEndPositionBehindTheAxisStopsAndReturns) {
    enable(Mode::ProfilePosition);
    start_move(10 * kRev);
    run_ms(1200);  // at V = 2 rev/s, about 2.2 rev on
    const std::int32_t now = io.feedback.position_actual;
    ASSERT_GT(now, 2 * kRev);
    const std::int32_t new_target = kRev;
    start_move(new_target, cw::ChangeSetImmediately);
    std::int32_t furthest = now;
    for (int ms = 0; ms < 4000 && !target_reached(); ++ms) {
        run_ms(1);
        furthest = std::max(furthest, io.feedback.position_actual);
    }
    EXPECT_GT(furthest, now) << "the axis stops forward first (it cannot reverse at once)";
    EXPECT_NEAR(io.feedback.position_actual, new_target, 100);
    EXPECT_TRUE(target_reached());
}

// 2.5 Position compensation: an additional distance D within a length L of the move (0x2111); "compensation
// is complete once the distance L + D has been travelled", so the move ends at its target plus D.
TEST_F(Tx1250, Tx1250_2_5_PositionCompensationAddsTheDistance) {
    enable(Mode::ProfilePosition);
    const std::int32_t target = 8 * kRev;
    start_move(target);
    run_ms(300);
    const double d = 0.25 * kRev;
    core.compensate(d, 4.0 * kRev);
    run_ms(6000);
    EXPECT_NEAR(io.feedback.position_actual, target + d, 100);
    EXPECT_TRUE(target_reached());
}

using namespace twin_test;

struct Tx1250Group : TwinBench {
    Tx1250Group() : TwinBench(&position_line) {}
};

// 3.1 NC error handling, INSTANTANEOUS (the default): "in the event of an error in one axis, the NC
// immediately initiates an error reaction, and halts all the axes involved in the master/slave group". A
// linear slave axis (PCON, 3.2) coupled over TWINsync whose drive faults in motion halts its master drive
// (39-02, src/cia402/README.md): both axes come to rest.
TEST_F(Tx1250Group, Tx1250_3_1_AnErrorHaltsTheWholeGroup) {
    enable_gantry();  // the slave drive switched on by its master's control word (P0159 = 10)
    std::int32_t p = pos(0);
    const std::int32_t s0 = pos(1);
    for (int i = 0; i < 200; ++i)
        cycle(0x0F, p += 400);
    ASSERT_GT(pos(1) - s0, 40'000) << "the slave follows";
    e(1, 0x2101).set<std::uint16_t>(fault::FollowingError);  // the slave drive faults
    for (int i = 0; i < 20; ++i)
        cycle(0x0F, p += 400);  // the NC would go on commanding the master
    EXPECT_EQ(drive(0).twinsync_error(), twinsync::error::OtherAxis);
    for (int i = 0; i < 300; ++i)
        cycle(0x0F, p += 400);
    EXPECT_EQ(drive(0).cia402_state(), State::Fault);
    EXPECT_EQ(drive(1).cia402_state(), State::Fault);
    EXPECT_LT(std::abs(drive(0).velocity_actual()), 100);
    EXPECT_LT(std::abs(drive(1).velocity_actual()), 100);
}

}  // namespace
}  // namespace vecat::cia402::conformance
