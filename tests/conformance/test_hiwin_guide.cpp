// Conformance to the HIWIN D1/D1-N/D2 Drive User Guide with EtherCAT (CoE) interface
// (../shared/seeds/004_938c11eaa867f7ff.txt): one test per behaviour, named after the guide's section.
// The vecat drive keeps its own identity; the first tests are the CiA 402 behaviours the guide describes for
// any CoE drive, those of the HiwinD2 fixture the HIWIN D2's own (its strategies, cia402/drive_variant.hpp,
// on the same drive core). The D2 as a CoE slave scanned by a master: test_hiwin_d2_device.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "cia402/drive_variant.hpp"
#include "drive_core_bench.hpp"

namespace vecat::cia402::conformance {
namespace {

using Hiwin = DriveCoreBench;

// 9.1.1 Profile position, controlword bit 8 "Halt: 1 stop the movement of motor, 0 not stop": released,
// the move goes on to its target (CiA 402 6.5: bit 8 = 0 executes the positioning), and bit 10 "motor in
// position" comes at the target, not where the halt stopped the axis.
TEST_F(Hiwin, Hiwin_9_1_1_HaltResumes) {
    enable(Mode::ProfilePosition);
    const std::int32_t target = 4 * kRev;
    io.command.target_position = target;
    io.command.controlword = cmd::EnableOperation | cw::NewSetpoint;
    run_ms(2);
    io.command.controlword = cmd::EnableOperation;
    run_ms(300);  // under way
    ASSERT_GT(io.feedback.position_actual, kRev / 4);
    ASSERT_LT(io.feedback.position_actual, target / 2);
    io.command.controlword = cmd::EnableOperation | cw::Halt;
    run_ms(300);  // stopped by the halt ramp (0x605D = 1: profile deceleration)
    EXPECT_LT(std::abs(io.feedback.velocity_actual), 1000);
    EXPECT_TRUE(target_reached()) << "9.1.1: bit 10 also when the halt has stopped the motor";
    const std::int32_t halted_at = io.feedback.position_actual;
    ASSERT_LT(halted_at, target - kRev);
    io.command.controlword = cmd::EnableOperation;  // halt released
    run_ms(50);
    EXPECT_FALSE(target_reached()) << "moving again";
    EXPECT_GT(io.feedback.position_actual, halted_at + 1000);
    run_ms(3000);
    EXPECT_NEAR(io.feedback.position_actual, target, 100);
    EXPECT_TRUE(target_reached());
}

// 9.1.1 with a halt released before the axis stopped: the move turns back into the profile towards the
// target without waiting for standstill.
TEST_F(Hiwin, Hiwin_9_1_1_HaltReleasedWhileBrakingResumes) {
    enable(Mode::ProfilePosition);
    const std::int32_t target = 3 * kRev;
    io.command.target_position = target;
    io.command.controlword = cmd::EnableOperation | cw::NewSetpoint;
    run_ms(2);
    io.command.controlword = cmd::EnableOperation;
    run_ms(300);
    io.command.controlword = cmd::EnableOperation | cw::Halt;
    run_ms(20);  // braking, not yet stopped
    ASSERT_GT(std::abs(io.feedback.velocity_actual), kRev / 2);
    io.command.controlword = cmd::EnableOperation;
    run_ms(3000);
    EXPECT_NEAR(io.feedback.position_actual, target, 100);
    EXPECT_TRUE(target_reached());
}

// 6 State machine of CiA402: "Fault reaction active: drive occurs error and activates corresponding
// motion"; "Fault: the drive has de-magnetized the motor". An encoder fault (0x7305) at speed in profile
// velocity leaves the drive without a measured speed: the fault reaction still ends, in FAULT, and the
// motor does not run away (vecat's reaction without an encoder: src/cia402/README.md).
TEST_F(Hiwin, Hiwin_6_EncoderFaultAtSpeedEndsInFault) {
    enable(Mode::ProfileVelocity);
    io.command.target_velocity = 2 * kRev;
    run_ms(500);
    ASSERT_NEAR(io.feedback.velocity_actual, 2 * kRev, kRev / 50);
    io.parameters.simulated_fault = fault::Encoder;
    // The drive no longer measures the motion (0x606C reads 0): the motor's true velocity shows it.
    auto motor_velocity = [&] { return core.mechanics().velocity() / (2 * std::numbers::pi) * kRev; };
    double fastest = 0;
    for (int ms = 0; ms < 2000 && core.state() != State::Fault; ++ms) {
        run_ms(1);
        fastest = std::max(fastest, std::abs(motor_velocity()));
    }
    EXPECT_EQ(core.state(), State::Fault);
    EXPECT_LE(fastest, 2.1 * kRev) << "the motor must not run away";
    EXPECT_EQ(protocol::cia402::decode_state(io.feedback.statusword), State::Fault);
    // In FAULT the power stage is off: the motor coasts to rest and stays there.
    run_ms(3000);
    EXPECT_EQ(core.mechanics().mode(), LoopMode::Off);
    EXPECT_LT(std::abs(motor_velocity()), 1.0);
    // The fault stays while the encoder is faulty, and a fault reset clears it once it is back.
    io.command.controlword = cmd::FaultReset;
    run_ms(1);
    EXPECT_EQ(core.state(), State::Fault);
    io.parameters.simulated_fault = 0;
    io.command.controlword = 0;
    run_ms(1);
    io.command.controlword = cmd::FaultReset;
    run_ms(1);
    EXPECT_EQ(core.state(), State::SwitchOnDisabled);
}

// ---- The HIWIN D2's own behaviour: the core with the D2's strategies and simulated machine (limit switches
// at -/+20 revolutions, a home switch dog from 3 to 4 revolutions, the index a quarter revolution into each).
struct HiwinD2 : DriveCoreBench {
    void SetUp() override {
        io.parameters.strategy = drive_strategy(device::DriveVariant::HiwinD2);
        simulated_machine(device::DriveVariant::HiwinD2, io.parameters);
        io.parameters.homing_speed_switch = 4 * kRev;
        io.parameters.homing_speed_zero = kRev / 2;
        io.parameters.homing_acceleration = 40 * kRev;
        DriveCoreBench::SetUp();
    }
    // The machine position in increments (homing does not move it).
    double machine_inc() const { return core.mechanics().position() / (2 * std::numbers::pi) * kRev; }
    // A profile position move to target (user units), to rest.
    void move_to(std::int32_t target) {
        enable(Mode::ProfilePosition);
        io.command.target_position = target;
        io.command.controlword = cmd::EnableOperation | cw::NewSetpoint;
        run_ms(2);
        io.command.controlword = cmd::EnableOperation;
        for (int ms = 0; ms < 20000 && !(target_reached() && std::abs(core.velocity_actual()) < 1); ++ms)
            run_ms(1);
        ASSERT_NEAR(io.feedback.position_actual, target, 200);
    }
    // Homing with a 0x6098 value of the D2 from where the axis stands: bit 4 until bits 10 and 12 (or 13)
    // come, at most 60 s. Returns the machine position (increments) the drive took as home: where 0x6064
    // would read the home offset 0.
    double home(int method) {
        io.parameters.homing_method = static_cast<std::int8_t>(method);
        io.command.mode = static_cast<std::int8_t>(Mode::Homing);
        io.command.controlword = cmd::EnableOperation;
        run_ms(2);
        io.command.controlword = cmd::EnableOperation | cw::HomingStart;
        for (int ms = 0; ms < 60000; ++ms) {
            run_ms(1);
            const std::uint16_t s = io.feedback.statusword;
            if ((s & sw::Bit13) || ((s & sw::Bit12) && (s & sw::TargetReached))) break;
        }
        return machine_inc() - io.feedback.position_actual;
    }
    bool attained() const {
        const std::uint16_t s = io.feedback.statusword;
        return (s & sw::Bit12) && (s & sw::TargetReached) && !(s & sw::Bit13);
    }
};

// 9.4: "0 No homing mode": bit 4 starts nothing, the axis stays, no error; the statusword shows
// "homing procedures interrupted or not initiated" (bit 10 without 12 and 13).
TEST_F(HiwinD2, Hiwin_9_4_Method0IsNoHoming) {
    enable(Mode::Homing);
    const double before = machine_inc();
    home(0);
    run_ms(200);
    EXPECT_NEAR(machine_inc(), before, 10);
    EXPECT_EQ(io.feedback.statusword & (sw::TargetReached | sw::Bit12 | sw::Bit13), sw::TargetReached);
}

// 9.4 methods 1 and 2: to the limit switch, back until it turns off, the first index signal is home.
TEST_F(HiwinD2, Hiwin_9_4_Method1NegativeLimitSwitchAndIndex) {
    enable(Mode::Homing);
    const double home_at = home(1);
    ASSERT_TRUE(attained());
    EXPECT_NEAR(home_at, -20 * kRev + kRev / 4, 2);
}
TEST_F(HiwinD2, Hiwin_9_4_Method2PositiveLimitSwitchAndIndex) {
    enable(Mode::Homing);
    const double home_at = home(2);
    ASSERT_TRUE(attained());
    EXPECT_NEAR(home_at, 19 * kRev + kRev / 4, 2);
}

// 9.4 method 3: positive to the home switch, back negative, the first index after it turns off.
TEST_F(HiwinD2, Hiwin_9_4_Method3HomeSwitchBackNegative) {
    enable(Mode::Homing);
    const double home_at = home(3);
    ASSERT_TRUE(attained());
    EXPECT_NEAR(home_at, 2 * kRev + kRev / 4, 2);
}

// 9.4 method 4: positive to the home switch, "then the motor will continuously move to the positive
// direction": through the switch, the first index after it turns off (CiA 402's method 4 would stop at
// the switch's rising edge and take the index inside it, 3.25 revolutions).
TEST_F(HiwinD2, Hiwin_9_4_Method4ContinuesThroughTheSwitch) {
    enable(Mode::Homing);
    const double home_at = home(4);
    ASSERT_TRUE(attained());
    EXPECT_NEAR(home_at, 4 * kRev + kRev / 4, 2);
}

// 9.4 method 5: negative to the home switch (the axis starts above it), back positive, the first index
// after it turns off.
TEST_F(HiwinD2, Hiwin_9_4_Method5HomeSwitchBackPositive) {
    move_to(8 * kRev);
    const double home_at = home(5);
    ASSERT_TRUE(attained());
    EXPECT_NEAR(home_at, 4 * kRev + kRev / 4, 2);
}

// 9.4 method 6: negative to the home switch, on through it, the first index after it turns off.
TEST_F(HiwinD2, Hiwin_9_4_Method6ContinuesThroughTheSwitch) {
    move_to(8 * kRev);
    const double home_at = home(6);
    ASSERT_TRUE(attained());
    EXPECT_NEAR(home_at, 2 * kRev + kRev / 4, 2);
}

// 9.4 methods 33 and 34: the first index signal in the negative / positive direction.
TEST_F(HiwinD2, Hiwin_9_4_Methods33And34FirstIndex) {
    enable(Mode::Homing);
    EXPECT_NEAR(home(33), -kRev + kRev / 4, 2);
    EXPECT_TRUE(attained());
    const double at = machine_inc();
    const double next = std::ceil((at - kRev / 4) / kRev) * kRev + kRev / 4;
    EXPECT_NEAR(home(34), next, 2);
    EXPECT_TRUE(attained());
}

// 9.4 with the home offset: "the offset between the coordinate origin and homing signal": at the home
// position 0x6064 reads the home offset.
TEST_F(HiwinD2, Hiwin_9_4_HomeOffset) {
    io.parameters.home_offset = 5000;
    enable(Mode::Homing);
    home(34);
    ASSERT_TRUE(attained());
    EXPECT_NEAR(machine_inc() - io.feedback.position_actual, kRev / 4 - 5000, 2);
}

// 9.4 "Initiate accuracy compensation" (VI, VII): after homing is completed (bits 10, 12) the master sets
// bit 0 of the input function 0x2010; the drive clears the feedback position to 0 and sets bit 15. Not
// before homing, and not without bit 0.
TEST_F(HiwinD2, Hiwin_9_4_Bit15AccuracyCompensation) {
    enable(Mode::Homing);
    io.command.input_function = 1;  // before homing: nothing
    run_ms(50);
    EXPECT_FALSE(io.feedback.statusword & kAccuracyCompensation);
    io.command.input_function = 0;
    home(34);
    ASSERT_TRUE(attained());
    run_ms(100);
    EXPECT_FALSE(io.feedback.statusword & kAccuracyCompensation);
    ASSERT_GT(std::abs(io.feedback.position_actual), 100) << "the axis braked past the index";
    io.command.input_function = 1;
    run_ms(5);
    EXPECT_TRUE(io.feedback.statusword & kAccuracyCompensation);
    EXPECT_TRUE(attained());
    EXPECT_NEAR(io.feedback.position_actual, 0, 1);
    // VIII: the master takes the feedback position as its command position and goes back to CSP.
    io.command.target_position = io.feedback.position_actual;
    io.command.mode = static_cast<std::int8_t>(Mode::CyclicPosition);
    run_ms(50);
    EXPECT_EQ(core.state(), State::OperationEnabled);
    EXPECT_NEAR(io.feedback.position_actual, 0, 5);
}

// 10: "Trigger Signal: encoder zero signal (Z-phase)": 0x60B8 = 0x0011 (enable, single, positive edge)
// latches the position of the next index into 0x60BA. The vecat drive takes 0x0011 as CiA 402 does, on its
// touch probe input 1, which stays low: nothing latched.
TEST_F(HiwinD2, Hiwin_10_TouchProbe0x0011LatchesOnTheZPhase) {
    enable(Mode::ProfileVelocity);
    io.command.probe_function = 0x0011;
    run_ms(2);
    EXPECT_EQ(io.feedback.probe_status, 0x0001) << "enabled, nothing stored";
    io.command.target_velocity = kRev;  // 1 rev/s: indexes at 0.25, 1.25 ... rev
    std::vector<std::int32_t> latched;
    for (int i = 0; i < 4 * 2500; ++i) {
        core.step(io);
        if (io.feedback.probe_latched.set[0][0]) latched.push_back(io.feedback.probe_latched.value[0][0]);
    }
    EXPECT_GT(io.feedback.position_actual, kRev + kRev / 4) << "two indexes crossed";
    EXPECT_EQ(io.feedback.probe_status, 0x0003);
    // Single trigger (0x60B8 bit 1 = 0): the first index only.
    ASSERT_EQ(latched.size(), 1u);
    EXPECT_EQ(latched[0], kRev / 4);
}

TEST_F(Hiwin, Hiwin_10_VecatDriveTakes0x0011OnItsProbeInput) {
    enable(Mode::ProfileVelocity);
    io.command.probe_function = 0x0011;
    io.command.target_velocity = kRev;
    run_ms(2000);  // two index pulses crossed
    EXPECT_EQ(io.feedback.probe_status, 0x0001) << "probe input 1 never rose";
}

// 10: the value latched on the Z phase, through the position the touch probe reports (continuous trigger,
// 0x0013: each index).
TEST_F(HiwinD2, Hiwin_10_ContinuousTriggerLatchesEachIndex) {
    enable(Mode::ProfileVelocity);
    io.command.probe_function = 0x0013;
    io.command.target_velocity = kRev;
    std::vector<std::int32_t> latched;
    for (int i = 0; i < 4 * 3000; ++i) {
        core.step(io);
        if (io.feedback.probe_latched.set[0][0]) latched.push_back(io.feedback.probe_latched.value[0][0]);
    }
    ASSERT_GE(latched.size(), 2u);
    EXPECT_EQ(latched[0], kRev / 4);
    EXPECT_EQ(latched[1], kRev + kRev / 4);
    // Probe 2 does not exist: its function bits change nothing, its status stays 0.
    io.command.probe_function = 0x1313;
    run_ms(10);
    EXPECT_EQ(io.feedback.probe_status & 0xFF00, 0);
}

// 9.1.2: "if the cycle of transmitting the target position command from the master station is 1ms, then
// the content of 0x60C2:1 shall be set to (1/0.0625)=16": one UINT16 in 62.5 us. The vecat drive reads
// 0x60C2 as CiA 402 does, value x 10^index s.
TEST(HiwinInterpolation, Hiwin_9_1_2_InterpolationPeriodIn62_5us) {
    DriveIo io;
    Axis a;
    a.io = &io;
    io.parameters.strategy = drive_strategy(device::DriveVariant::HiwinD2);
    io.parameters.interpolation_value = 16;
    EXPECT_DOUBLE_EQ(a.interpolation_period(), 1e-3);
    io.parameters.interpolation_value = 8;
    EXPECT_DOUBLE_EQ(a.interpolation_period(), 500e-6);
    io.parameters.strategy = drive_strategy(device::DriveVariant::Vecat);
    io.parameters.interpolation_value = 16;
    io.parameters.interpolation_index = -3;
    EXPECT_DOUBLE_EQ(a.interpolation_period(), 16e-3);
}

}  // namespace
}  // namespace vecat::cia402::conformance
