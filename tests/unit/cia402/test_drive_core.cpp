// The drive core alone, without EtherCAT: a DriveIo filled by hand, as another fieldbus or a test would.
// The CoE adapter (cia402::Drive) is tested through the dictionary in test_drive.cpp.
#include <gtest/gtest.h>

#include <cmath>

#include "cia402/drive_core.hpp"
#include "protocol/cia402.hpp"

namespace vecat::cia402 {
namespace {

namespace cmd = protocol::cia402::cmd;

struct DriveCoreTest : ::testing::Test {
    DriveIo io;
    DriveCore core{MotorParameters{}};
    void SetUp() override {
        io.parameters.profile_velocity = 1u << 20;
        io.parameters.profile_acceleration = 10u << 20;
        io.parameters.profile_deceleration = 10u << 20;
        io.parameters.position_window = 100;
        // 0x607D as the vecat drive has it (0/0: off). Absent, the core clamps positions to 0, as the
        // adapter always did for a dictionary without the object (drive_io.hpp).
        io.parameters.software_limit_min = 0;
        io.parameters.software_limit_max = 0;
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

}  // namespace
}  // namespace vecat::cia402
