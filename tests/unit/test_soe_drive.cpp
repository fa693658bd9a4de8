// The SoE drive's axes (src/soe/soe_axis.*): the CiA 402 drive core under the SERCOS profile (the master
// control word S-0-0134 onto the core's state machine and cyclic modes, the drive status word S-0-0135, the
// feedback, the following error into the class 1 diagnostic and its reset S-0-0099), two axes (drive numbers
// 0 and 1, their MDT/AT blocks one after the other, 0x800A for the others), and the execution time of the
// procedure commands (P-0-0101: "in progress" first). The motion is physical: the tests step the host
// time millisecond by millisecond and look at where the axis got, with tolerances.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "esc/sii_image.hpp"
#include "soe_bench.hpp"

using namespace vecat;
using namespace vecat::test;
using namespace vecat::test::soe_bench;
namespace idn = soe::idn;
namespace control = soe::control;
namespace status = soe::status;

namespace {

constexpr std::uint64_t kMs = 1'000'000;
constexpr std::uint16_t kRunning = control::DriveOn | control::DriveEnable | control::Run;

std::uint16_t readiness(std::uint16_t status_word) {
    return status_word >> status::ReadyShift;
}

// A drive behind the master in OP, cycled millisecond by millisecond.
struct Running : MasterBench {
    explicit Running(unsigned axes = 1) : MasterBench(axes) {}
    void op() {
        startup(AlState::Op);
        wkc = b.master.expected_wkc();
    }
    void cycle(int ms) {
        for (int i = 0; i < ms; ++i) {
            b.advance(kMs);
            ASSERT_EQ(b.master.exchange_process_data(), wkc);
        }
    }
    Bytes out() { return b.master.outputs(0); }
    ConstBytes in() { return b.master.inputs(0); }
    std::uint16_t wkc = 0;
};

}  // namespace

// ---- The drive core under the SERCOS profile

TEST(SoeDriveCore, ControlWordBitsWalkTheStateMachine) {
    Running r;
    r.op();
    r.cycle(5);
    EXPECT_EQ(readiness(ld_le16(r.in().data())), status::LogicReady);
    st_le16(r.out().data(), control::DriveOn);  // drive on without enable: nothing is powered
    r.cycle(5);
    EXPECT_EQ(readiness(ld_le16(r.in().data())), status::LogicReady);
    st_le16(r.out().data(), control::DriveEnable);  // enable without drive on: power, no torque
    r.cycle(5);
    EXPECT_EQ(readiness(ld_le16(r.in().data())), status::PowerReady);
    EXPECT_EQ(r.drive().axis().core().state(), protocol::cia402::State::SwitchedOn);
    st_le16(r.out().data(), control::DriveOn | control::DriveEnable);  // halted, but in operation
    r.cycle(5);
    EXPECT_EQ(readiness(ld_le16(r.in().data())), status::InOperation);
    EXPECT_EQ(r.drive().axis().core().state(), protocol::cia402::State::OperationEnabled);
    st_le16(r.out().data(), kRunning);
    r.cycle(5);
    EXPECT_EQ(readiness(ld_le16(r.in().data())), status::InOperation);
    EXPECT_EQ(ld_le16(r.in().data()) & status::ModeMask, 0);  // the primary mode (bits 8-9 = 0)
    EXPECT_EQ(r.drive().axis().core().mode(), protocol::cia402::Mode::CyclicPosition);
    // Drive on off: the axis brakes, then power ready without torque; enable off: torque off, logic ready.
    st_le16(r.out().data(), control::DriveEnable | control::Run);
    r.cycle(20);
    EXPECT_EQ(readiness(ld_le16(r.in().data())), status::PowerReady);
    st_le16(r.out().data(), control::DriveOn);
    r.cycle(5);
    EXPECT_EQ(readiness(ld_le16(r.in().data())), status::LogicReady);
}

TEST(SoeDriveCore, PositionCommandIsFollowedWithTheMotorsDynamics) {
    Running r;
    r.op();
    st_le16(r.out().data(), kRunning);
    r.cycle(5);
    ASSERT_EQ(readiness(ld_le16(r.in().data())), status::InOperation);
    // A ramp of 1000 increments per ms (about 57 rpm) to 100000: the feedback lags the command (the
    // position loop and the motor), then settles on it.
    std::int32_t cmd = 0;
    std::int32_t lag_max = 0;
    for (int i = 0; i < 100; ++i) {
        cmd += 1000;
        st_le32(r.out().data() + 2, static_cast<std::uint32_t>(cmd));
        r.cycle(1);
        const auto fb = static_cast<std::int32_t>(ld_le32(r.in().data() + 2));
        lag_max = std::max(lag_max, cmd - fb);
    }
    EXPECT_GT(lag_max, 500);  // not a copy of the command
    r.cycle(200);
    const auto fb = static_cast<std::int32_t>(ld_le32(r.in().data() + 2));
    EXPECT_NEAR(fb, 100000, 100);
    EXPECT_EQ(r.drive().class1_diagnostic(), 0);
}

TEST(SoeDriveCore, FollowingErrorShutsTheDriveDownUntilS0099ResetsIt) {
    Running r;
    r.op();
    st_le16(r.out().data(), kRunning);
    st_le32(r.out().data() + 2, 1234);
    r.cycle(200);
    ASSERT_EQ(readiness(ld_le16(r.in().data())), status::InOperation);
    EXPECT_NEAR(static_cast<std::int32_t>(ld_le32(r.in().data() + 2)), 1234, 20);
    // A jump beyond the monitoring window S-0-0159 (100000): the following error shuts the drive down.
    st_le32(r.out().data() + 2, 1234 + 200000);
    r.cycle(20);
    const std::uint16_t st = ld_le16(r.in().data());
    EXPECT_EQ(readiness(st), status::NotReady);
    EXPECT_EQ(st & status::Class1Error, status::Class1Error);
    auto c = r.client();
    const auto diag = c.read(0, el::Value, idn::Class1Diagnostic);
    ASSERT_TRUE(diag.ok());
    EXPECT_EQ(ld_le16(diag.data.data()), soe::c1d::ExcessiveDeviation);
    const auto text = c.read(0, el::Value, idn::DiagnosticMessage);
    ASSERT_TRUE(text.ok());
    const std::string msg(text.data.begin() + 4, text.data.end());
    EXPECT_NE(msg.find("excessive deviation"), std::string::npos) << msg;
    // The fault reaction brakes the axis (the quick stop ramp), then the drive waits in its fault. The
    // master brings the command back to the feedback, then resets the diagnostic.
    r.cycle(500);
    ASSERT_EQ(r.drive().axis().core().state(), protocol::cia402::State::Fault);
    st_le32(r.out().data() + 2, ld_le32(r.in().data() + 2));
    r.cycle(1);
    ASSERT_TRUE(
        c.write(0, el::Value, idn::ResetClass1Diagnostic, u16(soe::command_input::SetAndEnable)).ok());
    r.cycle(10);
    EXPECT_EQ(r.drive().class1_diagnostic(), 0);
    EXPECT_EQ(readiness(ld_le16(r.in().data())), status::InOperation);
    EXPECT_EQ(ld_le16(r.in().data()) & status::CommandChange, status::CommandChange);
}

TEST(SoeDriveCore, VelocityModeOfSecondaryOperationMode1) {
    Running r;
    r.startup(AlState::PreOp);
    auto c = r.client();
    ASSERT_TRUE(c.write(0, el::Value, idn::TelegramType, u16(2)).ok());  // MDT S-0-0036, AT S-0-0040
    r.op();
    // Bits 8-9 = 1: S-0-0033 (velocity) ; 60 rpm in 0.0001 rpm.
    st_le16(r.out().data(), kRunning | (1u << control::ModeShift));
    st_le32(r.out().data() + 2, 600000);
    r.cycle(300);
    EXPECT_EQ(readiness(ld_le16(r.in().data())), status::InOperation);
    EXPECT_EQ(ld_le16(r.in().data()) & status::ModeMask, 1u << control::ModeShift);
    EXPECT_EQ(r.drive().axis().core().mode(), protocol::cia402::Mode::CyclicVelocity);
    EXPECT_NEAR(static_cast<std::int32_t>(ld_le32(r.in().data() + 2)), 600000, 6000);
    // The position feedback went on (read by mailbox: S-0-0051 is not in the AT of telegram 2): 1 rev/s.
    const auto p = c.read(0, el::Value, idn::PositionFeedback);
    ASSERT_TRUE(p.ok());
    EXPECT_GT(static_cast<std::int32_t>(ld_le32(p.data.data())), 1 << 18);
}

TEST(SoeDriveCore, TorqueModeOfSecondaryOperationMode2) {
    Running r;
    r.startup(AlState::PreOp);
    auto c = r.client();
    ASSERT_TRUE(c.write(0, el::Value, idn::TelegramType, u16(soe::kApplicationTelegram)).ok());
    ASSERT_TRUE(c.write(0, el::Value, idn::MdtConfiguration, idns({idn::TorqueCommand})).ok());
    ASSERT_TRUE(c.write(0, el::Value, idn::AtConfiguration, idns({idn::TorqueFeedback})).ok());
    r.op();
    st_le16(r.out().data(), kRunning | (2u << control::ModeShift));
    st_le16(r.out().data() + 2, 50);  // 5.0 % of the rated torque
    r.cycle(50);
    EXPECT_EQ(r.drive().axis().core().mode(), protocol::cia402::Mode::CyclicTorque);
    EXPECT_NEAR(static_cast<std::int16_t>(ld_le16(r.in().data() + 2)), 50, 5);
}

// ---- Two axes (AX5206-like)

TEST(SoeTwoAxes, SiiDeclaresTwoChannelsAndTheSyncManagersHoldBothBlocks) {
    const auto d = device::soe_drive(2);
    EXPECT_EQ(d.identity.product_code, device::kSoeDrive2Product);
    EXPECT_EQ(d.soe_channels, 2);
    const auto sii = protocol::parse_sii(esc::build_sii_image(d));
    EXPECT_EQ(sii.mailbox_protocols, 0x0010);
    EXPECT_EQ(d.sync_managers.at(2).length, 12);
    EXPECT_EQ(d.sync_managers.at(3).length, 12);
}

TEST(SoeTwoAxes, EachDriveNumberHasItsOwnIdnsAndOthersAnswer0x800A) {
    DriveBench d(AlState::PreOp, 2);
    EXPECT_EQ(d.drive.drives(), 2u);
    ASSERT_EQ(d.write(el::Value, idn::MonitoringWindow, u32(5000), 1).error_code(), std::nullopt);
    EXPECT_EQ(ld_le32(d.read(el::Value, idn::MonitoringWindow, 1).data.data()), 5000u);
    EXPECT_EQ(ld_le32(d.read(el::Value, idn::MonitoringWindow, 0).data.data()), 100000u);
    for (std::uint8_t n = 2; n < 8; ++n) {
        const auto m = d.read(el::Value, idn::TelegramType, n);
        EXPECT_EQ(m.error_code(), code(SoeError::InvalidDriveNumber)) << int(n);
        EXPECT_EQ(m.drive, n);
    }
    // A telegram of drive 1 changes only drive 1's block.
    ASSERT_EQ(d.write(el::Value, idn::TelegramType, u16(5), 1).error_code(), std::nullopt);
    EXPECT_EQ(d.drive.axis(0).mdt_bytes(), 6u);
    EXPECT_EQ(d.drive.axis(1).mdt_bytes(), 10u);
    EXPECT_EQ(d.drive.output_bytes(), 16u);
    EXPECT_EQ(d.drive.input_bytes(), 16u);
}

TEST(SoeTwoAxes, MasterSumsBothDrivesAndEachAxisMovesOnItsBlock) {
    Running r(2);
    r.op();
    EXPECT_EQ(r.b.master.slaves()[0].out_bytes, 12u);  // (control word + S-0-0047) x 2
    EXPECT_EQ(r.b.master.slaves()[0].in_bytes, 12u);   // (status word + S-0-0051) x 2
    st_le16(r.out().data(), kRunning);
    st_le16(r.out().data() + 6, kRunning);
    r.cycle(5);
    // Axis 1 ramps to 50000, axis 0 stays.
    for (int i = 1; i <= 50; ++i) {
        st_le32(r.out().data() + 8, static_cast<std::uint32_t>(i * 1000));
        r.cycle(1);
    }
    r.cycle(200);
    EXPECT_EQ(readiness(ld_le16(r.in().data())), status::InOperation);
    EXPECT_EQ(readiness(ld_le16(r.in().data() + 6)), status::InOperation);
    EXPECT_NEAR(static_cast<std::int32_t>(ld_le32(r.in().data() + 2)), 0, 20);
    EXPECT_NEAR(static_cast<std::int32_t>(ld_le32(r.in().data() + 8)), 50000, 100);
    // Axis 0 off: axis 1 stays in operation.
    st_le16(r.out().data(), 0);
    r.cycle(5);
    EXPECT_EQ(readiness(ld_le16(r.in().data())), status::LogicReady);
    EXPECT_EQ(readiness(ld_le16(r.in().data() + 6)), status::InOperation);
    // Bad drive numbers in OP: answered, the process data goes on.
    auto c = r.client();
    for (std::uint8_t n = 0; n < 8; ++n) {
        const auto m = c.read(n, el::Value, idn::PositionFeedback);
        EXPECT_TRUE(m.transport_ok);
        EXPECT_EQ(m.ok(), n < 2) << int(n);
        r.cycle(1);
    }
    EXPECT_EQ(r.b.master.read_al_status(r.station()).state(), AlState::Op);
}

TEST(SoeTwoAxes, ACommandOfDrive1IsNotifiedWithItsDriveNumber) {
    Running r(2);
    r.startup(AlState::PreOp);
    auto c = r.client();
    ASSERT_TRUE(
        c.write(1, el::Value, idn::ResetClass1Diagnostic, u16(soe::command_input::SetAndEnable)).ok());
    r.b.advance(soe::kDefaultCommandDurationUs * 1000ull);
    const auto n = c.notification(std::chrono::milliseconds(200));
    ASSERT_TRUE(n);
    EXPECT_EQ(n->drive, 1);
    EXPECT_EQ(n->idn, idn::ResetClass1Diagnostic);
    EXPECT_EQ(n->data_state, soe::command_state::Executed);
    EXPECT_EQ(r.drive().status_word(1) & status::CommandChange, status::CommandChange);
    EXPECT_EQ(r.drive().status_word(0) & status::CommandChange, 0);
}

// ---- Procedure command timing (P-0-0101)

TEST(SoeCommandTiming, InProgressForItsDurationThenExecuted) {
    DriveBench d;
    const std::uint64_t t0 = 1'000'000'000;
    d.drive.tick(t0);
    ASSERT_EQ(d.write_error(idn::CommandDuration, u32(5000)), std::nullopt);  // 5 ms
    ASSERT_EQ(d.write_error(idn::ResetClass1Diagnostic, u16(soe::command_input::SetAndEnable)), std::nullopt);
    EXPECT_EQ(d.drive.next_event_ns(), t0 + 5 * kMs);
    d.drive.tick(t0 + 5 * kMs - 1);
    EXPECT_EQ(ld_le16(d.read(el::DataState, idn::ResetClass1Diagnostic).data.data()),
              soe::command_state::InProgress);
    EXPECT_FALSE(d.drive.has_notification());
    d.drive.tick(t0 + 5 * kMs);
    EXPECT_EQ(ld_le16(d.read(el::DataState, idn::ResetClass1Diagnostic).data.data()),
              soe::command_state::Executed);
    EXPECT_TRUE(d.drive.has_notification());
    EXPECT_EQ(d.drive.next_event_ns(), esc::DistributedClock::kNever);
}

TEST(SoeCommandTiming, InterruptedWhileInProgressIsNeverExecuted) {
    DriveBench d;
    d.drive.tick(1'000'000'000);
    ASSERT_EQ(d.write_error(idn::ResetClass1Diagnostic, u16(soe::command_input::SetAndEnable)), std::nullopt);
    ASSERT_EQ(d.write_error(idn::ResetClass1Diagnostic, u16(soe::command_input::SetNotEnabled)),
              std::nullopt);
    EXPECT_EQ(ld_le16(d.read(el::DataState, idn::ResetClass1Diagnostic).data.data()),
              soe::command_state::Interrupted);
    d.drive.tick(1'100'000'000);
    EXPECT_EQ(ld_le16(d.read(el::DataState, idn::ResetClass1Diagnostic).data.data()),
              soe::command_state::Interrupted);
    EXPECT_FALSE(d.drive.has_notification());
    // Enabled again, it runs its time from now.
    ASSERT_EQ(d.write_error(idn::ResetClass1Diagnostic, u16(soe::command_input::SetAndEnable)), std::nullopt);
    EXPECT_EQ(ld_le16(d.read(el::DataState, idn::ResetClass1Diagnostic).data.data()),
              soe::command_state::InProgress);
    d.drive.tick(1'100'000'000 + soe::kDefaultCommandDurationUs * 1000ull);
    EXPECT_EQ(ld_le16(d.read(el::DataState, idn::ResetClass1Diagnostic).data.data()),
              soe::command_state::Executed);
}

TEST(SoeCommandTiming, DurationZeroExecutesAtOnceAndTheLimitIsChecked) {
    DriveBench d;
    ASSERT_EQ(d.write_error(idn::CommandDuration, u32(0)), std::nullopt);
    ASSERT_EQ(d.write_error(idn::ResetClass1Diagnostic, u16(soe::command_input::SetAndEnable)), std::nullopt);
    EXPECT_EQ(ld_le16(d.read(el::DataState, idn::ResetClass1Diagnostic).data.data()),
              soe::command_state::Executed);
    EXPECT_TRUE(d.drive.has_notification());
    EXPECT_EQ(d.write_error(idn::CommandDuration, u32(soe::kMaxCommandDurationUs + 1)),
              code(SoeError::DataAboveMax));
}

TEST(SoeCommandTiming, TheCp3CheckPassesAfterItsTimeWhenTheSyncManagersFit) {
    Running r;
    r.startup(AlState::SafeOp);
    r.startup(AlState::PreOp);  // SM2/SM3 stay configured with the telegrams' lengths
    auto c = r.client();
    ASSERT_TRUE(c.write(0, el::Value, idn::Cp3TransitionCheck, u16(soe::command_input::SetAndEnable)).ok());
    auto s = c.read(0, el::DataState, idn::Cp3TransitionCheck);
    ASSERT_TRUE(s.ok());
    EXPECT_EQ(ld_le16(s.data.data()), soe::command_state::InProgress);
    r.b.advance(soe::kDefaultCommandDurationUs * 1000ull);
    s = c.read(0, el::DataState, idn::Cp3TransitionCheck);
    ASSERT_TRUE(s.ok());
    EXPECT_EQ(ld_le16(s.data.data()), soe::command_state::Executed);
}
