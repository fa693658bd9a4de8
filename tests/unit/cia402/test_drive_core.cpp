// The drive core alone, without EtherCAT: a DriveIo filled by hand, as another fieldbus or a test would.
// The CoE adapter (cia402::Drive) is tested through the dictionary in test_drive.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "cia402/drive_core.hpp"
#include "drive_core_test_io.hpp"
#include "protocol/cia402.hpp"
#include "twinsync/mapping.hpp"
#include "twinsync/telegram.hpp"

namespace vecat::cia402 {
namespace {

namespace cmd = protocol::cia402::cmd;

struct DriveCoreTest : ::testing::Test {
    DriveIo io;
    DriveCore core{MotorParameters{}};
    void SetUp() override {
        set_test_profile(io);
        core.configure(io);
        core.start(io);
    }
    void run_ms(int ms) {
        for (int i = 0; i < ms * 4; ++i)
            core.step(io);
    }
    void enable(Mode m) {
        io.command.mode = static_cast<std::int8_t>(m);
        for (std::uint16_t c : {cmd::Shutdown, cmd::SwitchOn, cmd::EnableOperation}) {
            io.command.controlword = c;
            run_ms(1);
        }
    }
};

TEST_F(DriveCoreTest, EnablesThroughTheControlwordAndShowsTheStateInTheStatusword) {
    EXPECT_EQ(protocol::cia402::decode_state(io.feedback.statusword), State::NotReadyToSwitchOn);
    enable(Mode::ProfilePosition);
    EXPECT_EQ(core.state(), State::OperationEnabled);
    EXPECT_EQ(protocol::cia402::decode_state(io.feedback.statusword), State::OperationEnabled);
    EXPECT_EQ(io.feedback.mode_display, static_cast<std::int8_t>(Mode::ProfilePosition));
}

TEST_F(DriveCoreTest, ProfilePositionMovesToTheTargetWithTheHandshake) {
    enable(Mode::ProfilePosition);
    io.command.target_position = 1 << 19;
    io.command.controlword = cmd::EnableOperation | protocol::cia402::cw::NewSetpoint;
    run_ms(1);
    EXPECT_TRUE(io.feedback.statusword & sw::Bit12);  // set-point acknowledged
    io.command.controlword = cmd::EnableOperation;
    run_ms(2000);
    EXPECT_TRUE(io.feedback.statusword & sw::TargetReached);
    EXPECT_NEAR(io.feedback.position_actual, 1 << 19, 100);
}

TEST_F(DriveCoreTest, AnInjectedFaultIsRaisedOnceAndClearedByAFaultReset) {
    enable(Mode::CyclicVelocity);
    io.parameters.simulated_fault = fault::FollowingError;
    core.step(io);
    ASSERT_TRUE(io.feedback.raised);
    EXPECT_EQ(io.feedback.raised->code, fault::FollowingError);
    core.step(io);
    EXPECT_FALSE(io.feedback.raised);  // raised once, until it is reset
    run_ms(100);
    EXPECT_EQ(core.state(), State::Fault);
    io.parameters.simulated_fault = 0;
    io.command.controlword = cmd::FaultReset;
    core.step(io);
    EXPECT_TRUE(io.feedback.cleared);
    EXPECT_EQ(core.state(), State::SwitchOnDisabled);
}

// An encoder fault (0x7305) at speed: the drive cannot know the motion any more. 0x6063/0x6064 stay at the
// last measured position and 0x606C reads 0 while the simulated motor coasts on (src/cia402/README.md,
// "Fault reaction without an encoder"); cleared and reset, the encoder is read again, with the reference
// it had: the actual values are the motor's true position and motion.
TEST_F(DriveCoreTest, AnEncoderFaultFreezesTheActualValuesUntilTheFaultReset) {
    constexpr double kRev = 1 << 20;
    auto true_position = [&] { return core.mechanics().position() / (2 * std::numbers::pi) * kRev; };
    auto true_velocity = [&] { return core.mechanics().velocity() / (2 * std::numbers::pi) * kRev; };
    enable(Mode::ProfileVelocity);
    io.command.target_velocity = 1 << 20;  // one revolution per second
    run_ms(500);
    ASSERT_NEAR(io.feedback.velocity_actual, kRev, kRev / 50);
    io.parameters.simulated_fault = fault::Encoder;
    core.step(io);
    const std::int32_t frozen = io.feedback.position_actual;
    const std::int32_t frozen_internal = io.feedback.position_internal;
    EXPECT_EQ(io.feedback.velocity_actual, 0);
    EXPECT_GT(true_velocity(), 0.5 * kRev) << "the motor coasts on (friction stops it in a few ms)";
    run_ms(20);
    EXPECT_EQ(core.state(), State::Fault);
    EXPECT_GT(true_position() - frozen, 100.0);
    EXPECT_EQ(io.feedback.position_actual, frozen);
    EXPECT_EQ(io.feedback.position_internal, frozen_internal);
    EXPECT_EQ(io.feedback.velocity_actual, 0);
    // The cause gone, the drive still in FAULT: nothing is measured until the fault reset.
    io.parameters.simulated_fault = 0;
    run_ms(1);
    EXPECT_EQ(io.feedback.position_actual, frozen);
    io.command.controlword = cmd::FaultReset;
    core.step(io);
    ASSERT_EQ(core.state(), State::SwitchOnDisabled);
    EXPECT_NEAR(io.feedback.position_actual, true_position(), 1.0);
    EXPECT_NEAR(io.feedback.velocity_actual, true_velocity(), 1.0);
    EXPECT_GT(io.feedback.position_actual - frozen, 100);
    // And measured from then on: the axis can be enabled again and moves.
    io.command.controlword = 0;
    run_ms(3000);  // friction stops the coasting motor
    enable(Mode::ProfileVelocity);
    run_ms(500);
    EXPECT_NEAR(io.feedback.velocity_actual, kRev, kRev / 50);
}

// TWINsync REFPOS slave (specification 6.2.10) on hand-filled TwinsyncInputs: a jump of the master's
// position set-point while the master homes (P2611 StartHoming) is a new reference, which the slave takes
// without moving; without StartHoming it is a set-point the slave follows (absolute synchronisation).
TEST_F(DriveCoreTest, RefposSlaveTakesTheMastersReferenceOnlyWhileTheMasterHomes) {
    enable(Mode::CyclicPosition);
    TwinsyncInputs& t = io.twinsync;
    t.active = t.follows = t.has_data = t.fresh = t.link_ok = true;
    t.role = twinsync::Role::Slave;
    t.mode = twinsync::mode_info(static_cast<std::uint8_t>(twinsync::Setting::PconRefposSlave));
    t.remote_speed_reference = 5000;
    t.remote_ref_pos = 0;
    run_ms(5);  // coupled at standstill
    t.received_control_word = twinsync::control::StartHoming;
    run_ms(1);
    const double machine = core.mechanics().position();
    t.remote_ref_pos = 100'000;
    run_ms(5);
    EXPECT_NEAR(core.position_demand(), 100'000, 1);
    EXPECT_NEAR(core.position_actual(), 100'000, 50);
    EXPECT_NEAR(core.mechanics().position(), machine, 1e-3) << "no motion";
    EXPECT_TRUE(core.twinsync_local(0, false).homed);
    t.received_control_word = 0;
    t.remote_ref_pos = 110'000;
    run_ms(50);
    EXPECT_NEAR(core.position_demand(), 110'000, 1);
    EXPECT_GT(core.mechanics().position() - machine, 0.03) << "a jump without homing is a motion";
}

// The servo period follows set_period_ns (the TWIN sampling time): at 125 us a millisecond of CSV takes
// eight periods, and the axis moves as far as at 250 us.
TEST_F(DriveCoreTest, ThePeriodIsTheSamplingTime) {
    core.set_period_ns(125'000);
    EXPECT_EQ(core.period_ns(), 125'000u);
    enable(Mode::CyclicVelocity);
    io.command.target_velocity = 1 << 20;  // one revolution per second
    const auto steps = core.steps();
    for (int i = 0; i < 8 * 500; ++i)
        core.step(io);
    EXPECT_EQ(core.steps() - steps, 4000u);
    const double start = core.position_actual();
    for (int i = 0; i < 8 * 500; ++i)
        core.step(io);
    EXPECT_NEAR(core.position_actual() - start, (1 << 20) / 2.0, (1 << 20) / 100.0) << "0.5 s at 1 rev/s";
}

}  // namespace
}  // namespace vecat::cia402
