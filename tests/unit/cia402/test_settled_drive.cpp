// A settled drive skips its servo periods (DriveCore, "Settled" in drive_core.cpp): these tests run a core
// that skips beside a twin that runs every period, with the same inputs, and compare what both show after
// every period. A scenario with holds (where the skipping happens), moves, window timers that cross their
// thresholds, thresholds changed after a long hold, a change of the servo period, faults, a probe latch and
// the public methods that change the core between periods.
#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <sstream>

#include "cia402/drive_core.hpp"
#include "drive_core_test_io.hpp"
#include "protocol/cia402.hpp"

namespace vecat::cia402 {
namespace {

namespace cmd = protocol::cia402::cmd;

// What a DriveIo's feedback shows the adapter: the values, the events, the latched probe values.
::testing::AssertionResult same_feedback(const DriveFeedback& a, const DriveFeedback& b) {
    std::ostringstream diff;
    auto field = [&](const char* name, auto x, auto y) {
        if (x != y) diff << ' ' << name << ' ' << +x << " != " << +y;
    };
    field("statusword", a.statusword, b.statusword);
    field("mode_display", a.mode_display, b.mode_display);
    field("position_demand", a.position_demand, b.position_demand);
    field("position_internal", a.position_internal, b.position_internal);
    field("position_actual", a.position_actual, b.position_actual);
    field("velocity_demand", a.velocity_demand, b.velocity_demand);
    field("velocity_actual", a.velocity_actual, b.velocity_actual);
    field("torque_demand", a.torque_demand, b.torque_demand);
    field("torque_actual", a.torque_actual, b.torque_actual);
    field("current_actual", a.current_actual, b.current_actual);
    field("following_error", a.following_error, b.following_error);
    field("position_demand_internal", a.position_demand_internal, b.position_demand_internal);
    field("digital_inputs", a.digital_inputs, b.digital_inputs);
    field("temperature", a.temperature, b.temperature);
    field("index_touched", a.index_touched, b.index_touched);
    field("index_position", a.index_position, b.index_position);
    field("probe_status", a.probe_status, b.probe_status);
    for (int n = 0; n < 2; ++n)
        for (int edge = 0; edge < 2; ++edge) {
            field("probe latched", a.probe_latched.set[n][edge], b.probe_latched.set[n][edge]);
            if (a.probe_latched.set[n][edge])
                field("probe value", a.probe_latched.value[n][edge], b.probe_latched.value[n][edge]);
        }
    field("twinsync", a.twinsync, b.twinsync);
    if (a.twinsync && b.twinsync) {
        // (Field by field: the struct has padding, which a copy need not keep.)
        const TwinsyncValues &x = a.twinsync_values, &y = b.twinsync_values;
        field("ref_torque", x.ref_torque, y.ref_torque);
        field("act_torque", x.act_torque, y.act_torque);
        field("ref_speed", x.ref_speed, y.ref_speed);
        field("act_speed", x.act_speed, y.act_speed);
        field("ref_pos", x.ref_pos, y.ref_pos);
        field("act_pos", x.act_pos, y.act_pos);
        field("speed_actual_rpm", x.speed_actual_rpm, y.speed_actual_rpm);
        field("speed_setpoint_rpm", x.speed_setpoint_rpm, y.speed_setpoint_rpm);
        field("eps", x.eps, y.eps);
        field("error_number", x.error_number, y.error_number);
        field("error_location", x.error_location, y.error_location);
    }
    field("raised", a.raised.has_value(), b.raised.has_value());
    if (a.raised && b.raised) field("raised code", a.raised->code, b.raised->code);
    field("cleared", a.cleared, b.cleared);
    if (diff.str().empty()) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << diff.str();
}

struct SettledDriveTest : ::testing::Test {
    DriveIo io_skip, io_run;
    DriveCore skipping{MotorParameters{}}, running{MotorParameters{}};
    int period = 0;

    void SetUp() override {
        running.skip_settled_periods(false);
        set([](DriveIo& io) {
            set_test_profile(io);
            io.parameters.position_window_time = 50;
            io.parameters.velocity_window = 10;
            io.parameters.velocity_window_time = 20;
            io.parameters.velocity_threshold = 10;
            io.parameters.velocity_threshold_time = 100;
        });
        skipping.configure(io_skip);
        running.configure(io_run);
        skipping.start(io_skip);
        running.start(io_run);
    }
    template <class F>
    void set(F f) {
        f(io_skip);
        f(io_run);
    }
    template <class F>
    void both(F f) {
        f(skipping);
        f(running);
    }
    // One frame's advance as cia402::Drive runs it: configure, then the periods, only the last publishing.
    void advance(int periods = 4) {
        skipping.configure(io_skip);
        running.configure(io_run);
        for (int i = 0; i < periods; ++i) {
            const bool publish = i == periods - 1;
            skipping.step(io_skip, publish);
            running.step(io_run, publish);
            ++period;
            ASSERT_TRUE(same_feedback(io_skip.feedback, io_run.feedback)) << "period " << period;
            ASSERT_EQ(skipping.state(), running.state()) << "period " << period;
            ASSERT_EQ(skipping.position_demand(), running.position_demand()) << "period " << period;
            ASSERT_EQ(skipping.position_actual(), running.position_actual()) << "period " << period;
            ASSERT_EQ(skipping.velocity_actual(), running.velocity_actual()) << "period " << period;
            ASSERT_EQ(skipping.mechanics().current(), running.mechanics().current()) << "period " << period;
            ASSERT_EQ(skipping.steps(), running.steps());
        }
    }
    void run_ms(int ms, int periods_per_ms = 4) {
        for (int i = 0; i < ms && !HasFatalFailure(); ++i)
            advance(periods_per_ms);
    }
    // A hold: the motor comes to rest, then `ms` in which the skipping core skips all periods but the first
    // that works out the TWINsync values (every 16th; the later ones show its values). (After a move the
    // velocity loop's integrator may take seconds to wind the current through the motor's static friction
    // before the motor settles.)
    void hold(int ms) {
        for (int i = 0; i < 20'000 && !HasFatalFailure(); ++i) {
            const std::uint64_t before = skipping.skipped_steps();
            run_ms(1);
            if (skipping.skipped_steps() - before >= 3) break;
        }
        const std::uint64_t before = skipping.skipped_steps();
        run_ms(ms);
        EXPECT_GE(skipping.skipped_steps() - before, static_cast<std::uint64_t>(ms) * 4 - 1)
            << "period " << period;
    }
    void enable(Mode m) {
        set([m](DriveIo& io) { io.command.mode = static_cast<std::int8_t>(m); });
        for (const std::uint16_t c : {cmd::Shutdown, cmd::SwitchOn, cmd::EnableOperation}) {
            set([c](DriveIo& io) { io.command.controlword = c; });
            run_ms(2);
        }
    }
};

TEST_F(SettledDriveTest, SkippedPeriodsShowWhatRunPeriodsShow) {
    hold(100);  // disabled, at rest
    EXPECT_EQ(running.skipped_steps(), 0u);

    // CSP holding its position, then a move of set-points and a hold at the end.
    enable(Mode::CyclicPosition);
    hold(200);
    for (int i = 1; i <= 50; ++i) {
        set([i](DriveIo& io) { io.command.target_position = i * 200; });
        run_ms(1);
    }
    hold(300);
    // A load held at standstill: the current warms the drive (0x2001) while it is settled.
    set([](DriveIo& io) { io.parameters.load_torque = 300; });
    const std::int16_t cool = io_run.feedback.temperature;
    hold(5000);
    EXPECT_GT(io_run.feedback.temperature, cool);
    // A position range 0x607B (DriveCore::configure): the axis is modulo and shows its position in the
    // range.
    EXPECT_GT(io_run.feedback.position_actual, 4096);
    set([](DriveIo& io) {
        io.parameters.position_range_min = 0;
        io.parameters.position_range_max = 4096;
    });
    run_ms(5);
    EXPECT_LT(io_run.feedback.position_actual, 4096);
    set([](DriveIo& io) {
        io.parameters.load_torque = 0;
        io.parameters.position_range_min = std::numeric_limits<std::int32_t>::min();
        io.parameters.position_range_max = std::numeric_limits<std::int32_t>::max();
    });
    hold(100);

    // PV at velocity 0: speed zero (bit 12) after 0x6070 = 100 ms, target reached after 0x606E = 20 ms.
    enable(Mode::ProfileVelocity);
    hold(1000);
    EXPECT_TRUE(io_run.feedback.statusword & sw::Bit12);
    // Thresholds changed after the long hold: the timers must have counted the skipped periods.
    set([](DriveIo& io) { io.parameters.velocity_threshold_time = 700; });
    run_ms(5);
    EXPECT_TRUE(io_run.feedback.statusword & sw::Bit12) << "standing for more than 1 s";
    set([](DriveIo& io) { io.parameters.velocity_threshold_time = 65535; });
    run_ms(5);
    EXPECT_FALSE(io_run.feedback.statusword & sw::Bit12);
    // A running timer whose read still says no keeps the periods running.
    const std::uint64_t skipped = skipping.skipped_steps();
    run_ms(100);
    EXPECT_EQ(skipping.skipped_steps(), skipped);
    set([](DriveIo& io) { io.parameters.velocity_threshold_time = 1200; });
    run_ms(300);  // crosses 1.2 s of standing in these periods
    EXPECT_TRUE(io_run.feedback.statusword & sw::Bit12);
    hold(100);

    // PP: a move, the position window time 0x6068, a hold; compensation and zeroing between periods.
    enable(Mode::ProfilePosition);
    set([](DriveIo& io) {
        io.command.target_position = 1 << 18;
        io.command.controlword = cmd::EnableOperation | protocol::cia402::cw::NewSetpoint;
    });
    run_ms(1);
    set([](DriveIo& io) { io.command.controlword = cmd::EnableOperation; });
    run_ms(1500);
    EXPECT_TRUE(io_run.feedback.statusword & sw::TargetReached);
    hold(200);
    both([](DriveCore& c) { c.zero_position(); });
    run_ms(10);
    EXPECT_NEAR(io_run.feedback.position_actual, 0, 10);
    hold(100);
    both([](DriveCore& c) { c.compensate(1000, 2000); });
    run_ms(500);
    hold(100);

    // A shorter servo period between two advances (TWIN sampling time at 8 kHz), and back.
    both([](DriveCore& c) { c.set_period_ns(125'000); });
    run_ms(200, 8);
    both([](DriveCore& c) { c.set_period_ns(250'000); });
    hold(100);

    // Touch probe 1 on the positive edge of its input while settled.
    set([](DriveIo& io) { io.command.probe_function = 0x0011; });  // probe 1 on, positive edge
    hold(50);
    set([](DriveIo& io) { io.parameters.probe_inputs = 1; });
    run_ms(10);
    EXPECT_TRUE(io_run.feedback.probe_status & 0x0002);
    hold(50);

    // An injected fault while settled, and the fault reset.
    set([](DriveIo& io) { io.parameters.simulated_fault = fault::FollowingError; });
    run_ms(20);
    EXPECT_EQ(running.state(), State::Fault);
    set([](DriveIo& io) {
        io.parameters.simulated_fault = 0;
        io.command.controlword = cmd::FaultReset;
    });
    run_ms(5);
    hold(100);

    // A following error (window 0x6065, timeout 0x6066) from a jump of the CSP set-point.
    enable(Mode::CyclicPosition);
    set([&](DriveIo& io) {
        io.command.target_position = io_run.feedback.position_actual;
        io.parameters.following_error_window = 50;
        io.parameters.following_error_timeout = 5;
    });
    hold(100);
    set([](DriveIo& io) { io.command.target_position += 100'000; });
    run_ms(50);
    EXPECT_EQ(running.state(), State::Fault);
}

// A drive that never stands (a constant velocity) runs every period.
TEST_F(SettledDriveTest, AMovingDriveRunsEveryPeriod) {
    enable(Mode::ProfileVelocity);
    set([](DriveIo& io) { io.command.target_velocity = 1 << 18; });
    run_ms(200);
    const std::uint64_t before = skipping.skipped_steps();
    run_ms(500);
    EXPECT_EQ(skipping.skipped_steps(), before);
}

}  // namespace
}  // namespace vecat::cia402
