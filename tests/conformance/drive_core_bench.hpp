// A drive core alone on a hand-filled DriveIo, for the conformance tests of the seed documents: enabled
// through the controlword as a master does (CiA 402 transitions 2, 3, 4), stepped in milliseconds.
#pragma once

#include <gtest/gtest.h>

#include "cia402/drive_core.hpp"
#include "protocol/cia402.hpp"

namespace vecat::cia402::conformance {

namespace cmd = protocol::cia402::cmd;
namespace cw = protocol::cia402::cw;

struct DriveCoreBench : ::testing::Test {
    static constexpr std::int32_t kRev = 1 << 20;  // user units per motor revolution (defaults)
    DriveIo io;
    DriveCore core{MotorParameters{}};
    void SetUp() override {
        io.parameters.profile_velocity = 2 * kRev;
        io.parameters.profile_acceleration = 20 * kRev;
        io.parameters.profile_deceleration = 20 * kRev;
        io.parameters.quick_stop_deceleration = 40 * kRev;
        io.parameters.position_window = 100;
        io.parameters.software_limit_min = 0;
        io.parameters.software_limit_max = 0;
        core.configure(io);
        core.start(io);
    }
    void run_ms(double ms) {
        for (int i = 0; i < static_cast<int>(ms * 4); ++i)
            core.step(io);
    }
    void enable(Mode m) {
        io.command.mode = static_cast<std::int8_t>(m);
        for (std::uint16_t c : {cmd::Shutdown, cmd::SwitchOn, cmd::EnableOperation}) {
            io.command.controlword = c;
            run_ms(1);
        }
        ASSERT_EQ(core.state(), State::OperationEnabled);
    }
    bool target_reached() const { return io.feedback.statusword & sw::TargetReached; }
};

}  // namespace vecat::cia402::conformance
