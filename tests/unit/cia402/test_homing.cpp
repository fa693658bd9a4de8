#include <gtest/gtest.h>
#include "cia402/homing.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace vecat::cia402 {
namespace {

namespace bits = homing_status_bits;

// How the simulated home switch is laid out.
enum class Shape { Window, ActiveAbove, ActiveBelow, Absent };

// A small kinematic world: the velocity follows the commanded velocity with the commanded acceleration, the
// position integrates it; switches and index pulses are functions of the position.
struct World {
    double negative_limit = -20;  // active at p <= negative_limit
    double positive_limit = 40;   // active at p >= positive_limit
    Shape shape = Shape::Window;
    double home_low = 10;   // Window: active on [home_low, home_high]; ActiveAbove: p >= home_low;
    double home_high = 15;  // ActiveBelow: p <= home_low
    double dt = 1e-3;

    HomingSignals signals(double p) const {
        HomingSignals s;
        s.negative_limit = p <= negative_limit;
        s.positive_limit = p >= positive_limit;
        switch (shape) {
            case Shape::Window:
                s.home_switch = p >= home_low && p <= home_high;
                break;
            case Shape::ActiveAbove:
                s.home_switch = p >= home_low;
                break;
            case Shape::ActiveBelow:
                s.home_switch = p <= home_low;
                break;
            case Shape::Absent:
                break;
        }
        return s;
    }
};

constexpr double kSpeedSwitch = 20;
constexpr double kSpeedZero = 2;
constexpr double kAcceleration = 200;
constexpr double kIndexPeriod = 1;
constexpr double kIndexPhase = 0.3;

HomingParameters parameters() {
    HomingParameters p;
    p.speed_switch = kSpeedSwitch;
    p.speed_zero = kSpeedZero;
    p.acceleration = kAcceleration;
    p.home_offset = 0;
    p.index_period = kIndexPeriod;
    p.index_phase = kIndexPhase;
    return p;
}

// The first index pulse strictly beyond `from` in direction dir (computed by walking the pulses).
double next_index(double from, int dir, double period = kIndexPeriod, double phase = kIndexPhase) {
    double x = phase + period * std::round((from - phase) / period) - 3 * dir * period;
    while ((x - from) * dir <= 0)
        x += dir * period;
    return x;
}

struct Outcome {
    bool started = false;
    bool finished = false;  // attained or error, and standing still
    HomingStatus status = HomingStatus::NotStarted;
    HomingFault fault = HomingFault::None;
    int found_events = 0;
    double home = std::numeric_limits<double>::quiet_NaN();
    double velocity_at_event = 0;
    std::uint16_t bits_at_event = 0;
    double position = 0;
    double velocity = 0;
    double min_position = 0;
    double max_position = 0;
    double max_speed = 0;
    std::uint16_t final_bits = 0;
    double position_shift = 0;
    int cycles = 0;
};

Outcome simulate(const World& w, int method, double start, const HomingParameters& p = parameters(),
                 int max_cycles = 200000) {
    Outcome r;
    Homing h;
    r.started = h.start(method, p, start);
    if (!r.started) return r;
    double pos = start;
    double vel = 0;
    r.min_position = r.max_position = start;
    for (int i = 0; i < max_cycles; ++i) {
        const HomingOutput out = h.update(pos, vel, w.signals(pos));
        r.cycles = i + 1;
        EXPECT_EQ(out.target_reached, (h.statusword_bits() & bits::TargetReached) != 0);
        EXPECT_EQ(out.status, h.status());
        if (out.home_found) {
            ++r.found_events;
            r.home = out.home_position;
            r.velocity_at_event = vel;
            r.bits_at_event = h.statusword_bits();
        }
        if ((out.status == HomingStatus::Attained || out.status == HomingStatus::Error) &&
            out.target_reached) {
            r.finished = true;
            break;
        }
        const double step = out.acceleration * w.dt;
        vel += std::clamp(out.velocity - vel, -step, step);
        pos += vel * w.dt;
        r.min_position = std::min(r.min_position, pos);
        r.max_position = std::max(r.max_position, pos);
        r.max_speed = std::max(r.max_speed, std::abs(vel));
    }
    r.status = h.status();
    r.fault = h.fault();
    r.position = pos;
    r.velocity = vel;
    r.final_bits = h.statusword_bits();
    r.position_shift = h.position_shift();
    return r;
}

// What CiA 402 specifies for each switch method, written out independently of the implementation:
// the switch layout, the position of the edge, the direction in which it is finally crossed.
struct Expectation {
    Shape shape;
    double edge;
    int dir;
};

Expectation expectation(int method) {
    const World w;
    const int base = method > 16 ? method - 16 : method;
    switch (base) {
        case 1:
            return {Shape::Window, w.negative_limit, +1};
        case 2:
            return {Shape::Window, w.positive_limit, -1};
        case 3:
            return {Shape::ActiveAbove, w.home_low, -1};
        case 4:
            return {Shape::ActiveAbove, w.home_low, +1};
        case 5:
            return {Shape::ActiveBelow, w.home_low, +1};
        case 6:
            return {Shape::ActiveBelow, w.home_low, -1};
        case 7:
            return {Shape::Window, w.home_low, -1};
        case 8:
            return {Shape::Window, w.home_low, +1};
        case 9:
            return {Shape::Window, w.home_high, -1};
        case 10:
            return {Shape::Window, w.home_high, +1};
        case 11:
            return {Shape::Window, w.home_high, +1};
        case 12:
            return {Shape::Window, w.home_high, -1};
        case 13:
            return {Shape::Window, w.home_low, +1};
        case 14:
            return {Shape::Window, w.home_low, -1};
    }
    ADD_FAILURE() << "no expectation for method " << method;
    return {Shape::Window, 0, 0};
}

// One cycle's travel at speed_zero (the edge is seen at the first sample past it), with the approach
// tolerance of the model.
constexpr double kEdgeTolerance = 1.5 * kSpeedZero * 1e-3 + 1e-12;

class HomingSwitchMethod : public ::testing::TestWithParam<int> {};

TEST_P(HomingSwitchMethod, FindsTheHomeFromEveryStartPosition) {
    const int method = GetParam();
    const bool index = method <= 14;
    const Expectation e = expectation(method);
    World w;
    w.shape = e.shape;
    // On the negative limit, left of the home switch, on it, right of it, on the positive limit.
    for (const double start : {-21.0, 0.0, 12.0, 25.0, 41.0}) {
        SCOPED_TRACE("method " + std::to_string(method) + " from " + std::to_string(start));
        const Outcome r = simulate(w, method, start);
        ASSERT_TRUE(r.started);
        ASSERT_TRUE(r.finished) << "after " << r.cycles << " cycles at " << r.position;
        EXPECT_EQ(r.status, HomingStatus::Attained);
        EXPECT_EQ(r.fault, HomingFault::None);
        EXPECT_EQ(r.found_events, 1);
        if (index) {
            EXPECT_NEAR(r.home, next_index(e.edge, e.dir), 1e-9);
        } else {
            // Past the edge in the final direction by at most one cycle's travel at the slow speed.
            EXPECT_GE((r.home - e.edge) * e.dir, 0.0) << r.home;
            EXPECT_LE((r.home - e.edge) * e.dir, kEdgeTolerance) << r.home;
        }
        // The reference was taken at the slow speed, in the final direction.
        EXPECT_GT(r.velocity_at_event * e.dir, 0.0);
        EXPECT_LE(std::abs(r.velocity_at_event), 1.5 * kSpeedZero);
        EXPECT_EQ(r.bits_at_event, bits::HomingAttained);  // attained, target not reached (still moving)
        // The switch search ran at speed_switch, never faster.
        EXPECT_LE(r.max_speed, kSpeedSwitch + 1e-9);
        // The axis stops right after the reference: braking from speed_zero takes speed_zero^2 / 2a.
        EXPECT_NEAR(r.velocity, 0.0, 1e-9);
        EXPECT_LE(std::abs(r.position - r.home), kSpeedZero * kSpeedZero / (2 * kAcceleration) + 0.01);
        EXPECT_EQ(r.final_bits, bits::HomingAttained | bits::TargetReached);
        EXPECT_DOUBLE_EQ(r.position_shift, -r.home);
        // Never further into a limit switch than the braking distance from speed_switch.
        const double brake = kSpeedSwitch * kSpeedSwitch / (2 * kAcceleration) + 0.05;
        EXPECT_GE(r.min_position, std::min(start, w.negative_limit - brake));
        EXPECT_LE(r.max_position, std::max(start, w.positive_limit + brake));
    }
}

INSTANTIATE_TEST_SUITE_P(HomingMethods, HomingSwitchMethod,
                         ::testing::Values(1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 17, 18, 19, 20, 21,
                                           22, 23, 24, 25, 26, 27, 28, 29, 30),
                         [](const ::testing::TestParamInfo<int>& param_info) {
                             return "Method" + std::to_string(param_info.param);
                         });

// The direction of the first move tells 7-10 (positive) from 11-14 (negative), also when the home switch
// is not in that direction: then the axis reverses at the limit switch.
TEST(HomingWindowSearch, InitialDirectionAndReversalAtTheLimitSwitch) {
    World w;
    // Right of the home switch, methods 7-10 first run into the positive limit switch.
    for (const int method : {7, 8, 9, 10, 23, 24, 25, 26}) {
        SCOPED_TRACE(method);
        const Outcome r = simulate(w, method, 25.0);
        EXPECT_EQ(r.status, HomingStatus::Attained);
        EXPECT_GE(r.max_position, w.positive_limit);
    }
    // Left of it, 11-14 first run into the negative limit switch.
    for (const int method : {11, 12, 13, 14, 27, 28, 29, 30}) {
        SCOPED_TRACE(method);
        const Outcome r = simulate(w, method, 0.0);
        EXPECT_EQ(r.status, HomingStatus::Attained);
        EXPECT_LE(r.min_position, w.negative_limit);
    }
    // Left of it, 7-10 never go near the negative limit switch; right of it, 11-14 never near the positive.
    for (const int method : {7, 8, 9, 10}) {
        SCOPED_TRACE(method);
        const Outcome r = simulate(w, method, 0.0);
        EXPECT_EQ(r.status, HomingStatus::Attained);
        EXPECT_GE(r.min_position, -1.0);
        EXPECT_LE(r.max_position, w.home_high + 2.0);
    }
    for (const int method : {11, 12, 13, 14}) {
        SCOPED_TRACE(method);
        const Outcome r = simulate(w, method, 25.0);
        EXPECT_EQ(r.status, HomingStatus::Attained);
        EXPECT_LE(r.max_position, 26.0);
        EXPECT_GE(r.min_position, w.home_low - 2.0);
    }
}

// A home switch narrower than the braking distance from speed_switch is overrun during the fast search;
// the edge must still be taken at the slow speed.
TEST(HomingWindowSearch, NarrowHomeSwitchOverrunAtSearchSpeed) {
    World w;
    w.home_low = 10;
    w.home_high = 10.5;  // braking from speed_switch needs 1.0
    for (const int method : {7, 8, 9, 10, 11, 12, 13, 14}) {
        const Expectation e = expectation(method);
        const double edge = e.edge == 15 ? w.home_high : w.home_low;
        for (const double start : {0.0, 25.0}) {
            SCOPED_TRACE("method " + std::to_string(method) + " from " + std::to_string(start));
            const Outcome r = simulate(w, method, start);
            ASSERT_EQ(r.status, HomingStatus::Attained);
            EXPECT_NEAR(r.home, next_index(edge, e.dir), 1e-9);
            EXPECT_LE(std::abs(r.velocity_at_event), 1.5 * kSpeedZero);
        }
    }
    const Outcome r = simulate(w, 26, 0.0);  // upper edge, falling, moving positive
    ASSERT_EQ(r.status, HomingStatus::Attained);
    EXPECT_GE(r.home, w.home_high);
    EXPECT_LE(r.home, w.home_high + kEdgeTolerance);
}

TEST(HomingIndexOnly, Method33SearchesNegativeMethod34Positive) {
    World w;
    Outcome r = simulate(w, 33, 0.0);
    EXPECT_EQ(r.status, HomingStatus::Attained);
    EXPECT_NEAR(r.home, -0.7, 1e-12);
    EXPECT_GT(r.velocity_at_event, -kSpeedZero - 1e-9);  // at speed_zero
    EXPECT_LT(r.velocity_at_event, 0.0);
    EXPECT_EQ(r.final_bits, bits::HomingAttained | bits::TargetReached);

    r = simulate(w, 34, 0.0);
    EXPECT_EQ(r.status, HomingStatus::Attained);
    EXPECT_NEAR(r.home, 0.3, 1e-12);
    EXPECT_GT(r.velocity_at_event, 0.0);
    EXPECT_LE(r.velocity_at_event, kSpeedZero + 1e-9);

    // The pulse must lie beyond the start: standing on a pulse finds the next one.
    r = simulate(w, 34, 0.3);
    EXPECT_NEAR(r.home, 1.3, 1e-12);
    r = simulate(w, 33, 0.3);
    EXPECT_NEAR(r.home, -0.7, 1e-12);

    // Another index geometry; the pulse is interpolated between two samples, not taken at a sample.
    HomingParameters p = parameters();
    p.index_period = 0.37;
    p.index_phase = -0.011;
    r = simulate(w, 34, 5.0, p);
    EXPECT_NEAR(r.home, next_index(5.0, +1, 0.37, -0.011), 1e-9);
    r = simulate(w, 33, 5.0, p);
    EXPECT_NEAR(r.home, next_index(5.0, -1, 0.37, -0.011), 1e-9);
}

TEST(HomingIndexOnly, LimitSwitchBeforeTheIndexPulseIsAnError) {
    World w;
    // Positive limit at 40, next pulse at 40.3.
    Outcome r = simulate(w, 34, 39.5);
    EXPECT_EQ(r.status, HomingStatus::Error);
    EXPECT_EQ(r.fault, HomingFault::LimitSwitch);
    EXPECT_EQ(r.found_events, 0);
    EXPECT_EQ(r.final_bits, bits::HomingError | bits::TargetReached);
    // Standing on the negative limit switch, method 33 cannot move.
    r = simulate(w, 33, -20.5);
    EXPECT_EQ(r.status, HomingStatus::Error);
    EXPECT_EQ(r.fault, HomingFault::LimitSwitch);
    EXPECT_EQ(r.cycles, 1);
    // ... but method 34 can.
    r = simulate(w, 34, -20.5);
    EXPECT_EQ(r.status, HomingStatus::Attained);
    EXPECT_NEAR(r.home, -19.7, 1e-9);
}

TEST(HomingCurrentPosition, Methods35And37AttainAtOnceWithoutMotion) {
    for (const int method : {35, 37}) {
        SCOPED_TRACE(method);
        Homing h;
        HomingParameters p;  // no speeds needed
        p.home_offset = 2.5;
        ASSERT_TRUE(h.start(method, p, 7.25));
        EXPECT_EQ(h.status(), HomingStatus::Attained);
        EXPECT_EQ(h.statusword_bits(), bits::HomingAttained | bits::TargetReached);
        EXPECT_EQ(h.home_position(), 7.25);
        // The current position reads as the home offset afterwards.
        EXPECT_DOUBLE_EQ(7.25 + h.position_shift(), 2.5);

        HomingOutput out = h.update(7.25, 0, {});
        EXPECT_TRUE(out.home_found);
        EXPECT_EQ(out.home_position, 7.25);
        EXPECT_EQ(out.velocity, 0);
        EXPECT_EQ(out.status, HomingStatus::Attained);
        EXPECT_TRUE(out.target_reached);
        out = h.update(7.25, 0, {});
        EXPECT_FALSE(out.home_found);  // reported once
        EXPECT_EQ(out.status, HomingStatus::Attained);
    }
}

TEST(HomingHomeOffset, HomePositionReadsAsTheHomeOffset) {
    World w;
    HomingParameters p = parameters();
    p.home_offset = -1.5;
    const Outcome r = simulate(w, 8, 0.0, p);
    ASSERT_EQ(r.status, HomingStatus::Attained);
    EXPECT_NEAR(r.home, 10.3, 1e-9);
    EXPECT_NEAR(r.home + r.position_shift, -1.5, 1e-12);
    EXPECT_NEAR(r.position_shift, -11.8, 1e-9);
}

TEST(HomingStatusword, BitsThroughAProcedure) {
    Homing h;
    EXPECT_EQ(h.status(), HomingStatus::NotStarted);
    EXPECT_EQ(h.statusword_bits(), bits::TargetReached);  // 0/0/1: not started

    World w;
    ASSERT_TRUE(h.start(24, parameters(), 0.0));
    double pos = 0;
    double vel = 0;
    std::vector<std::uint16_t> seen;
    for (int i = 0; i < 100000; ++i) {
        const HomingOutput out = h.update(pos, vel, w.signals(pos));
        const std::uint16_t b = h.statusword_bits();
        EXPECT_EQ(b & ~bits::Mask, 0);
        if (seen.empty() || seen.back() != b) seen.push_back(b);
        if (out.status == HomingStatus::InProgress) {
            EXPECT_EQ(b, 0);
        }
        if (out.status == HomingStatus::Attained && out.target_reached) break;
        const double step = out.acceleration * w.dt;
        vel += std::clamp(out.velocity - vel, -step, step);
        pos += vel * w.dt;
    }
    // in progress -> attained, target not reached -> completed
    const std::vector<std::uint16_t> expected{0, bits::HomingAttained,
                                              bits::HomingAttained | bits::TargetReached};
    EXPECT_EQ(seen, expected);
}

TEST(HomingStatusword, StandstillThreshold) {
    World w;
    HomingParameters p = parameters();
    p.standstill_velocity = 0.5;
    Homing h;
    ASSERT_TRUE(h.start(34, p, 0.0));
    h.update(0.0, 0.0, w.signals(0.0));
    // Velocity 2 past a pulse: attained, still moving.
    h.update(0.31, 2.0, w.signals(0.31));
    ASSERT_EQ(h.status(), HomingStatus::Attained);
    EXPECT_EQ(h.statusword_bits(), bits::HomingAttained);
    h.update(0.32, 0.6, w.signals(0.32));
    EXPECT_EQ(h.statusword_bits(), bits::HomingAttained);
    h.update(0.33, 0.5, w.signals(0.33));
    EXPECT_EQ(h.statusword_bits(), bits::HomingAttained | bits::TargetReached);
    EXPECT_NEAR(h.home_position(), 0.3, 1e-12);
}

TEST(HomingInterrupt, HaltStopsWithHomingAccelerationAndReportsInterrupted) {
    World w;
    Homing h;
    ASSERT_TRUE(h.start(17, parameters(), 0.0));
    double pos = 0;
    double vel = 0;
    HomingOutput out;
    for (int i = 0; i < 200; ++i) {
        out = h.update(pos, vel, w.signals(pos));
        const double step = out.acceleration * w.dt;
        vel += std::clamp(out.velocity - vel, -step, step);
        pos += vel * w.dt;
    }
    EXPECT_EQ(out.velocity, -kSpeedSwitch);  // searching the negative limit switch
    ASSERT_NEAR(vel, -kSpeedSwitch, 1e-9);
    h.halt();
    EXPECT_EQ(h.status(), HomingStatus::Interrupted);
    out = h.update(pos, vel, w.signals(pos));
    EXPECT_EQ(out.velocity, 0);
    EXPECT_EQ(out.acceleration, kAcceleration);
    EXPECT_EQ(out.status, HomingStatus::Interrupted);
    EXPECT_FALSE(out.target_reached);
    EXPECT_EQ(h.statusword_bits(), 0);  // still moving
    int cycles = 0;
    while (!out.target_reached && cycles < 1000) {
        const double step = out.acceleration * w.dt;
        vel += std::clamp(out.velocity - vel, -step, step);
        pos += vel * w.dt;
        out = h.update(pos, vel, w.signals(pos));
        ++cycles;
    }
    EXPECT_EQ(cycles, 100);                               // 20 / 200 s at 1 ms
    EXPECT_EQ(h.statusword_bits(), bits::TargetReached);  // 0/0/1: interrupted
    EXPECT_FALSE(out.home_found);
    EXPECT_EQ(h.fault(), HomingFault::None);
}

TEST(HomingInterrupt, AbortEndsTheSearchButKeepsAnAttainedHome) {
    World w;
    Homing h;
    ASSERT_TRUE(h.start(34, parameters(), 0.0));
    h.update(0.0, 0.0, w.signals(0.0));
    h.update(0.1, 2.0, w.signals(0.1));
    h.abort();
    EXPECT_EQ(h.status(), HomingStatus::Interrupted);
    HomingOutput out = h.update(0.2, 2.0, w.signals(0.2));  // past a pulse, but no longer searching
    EXPECT_FALSE(out.home_found);
    EXPECT_EQ(out.velocity, 0);
    EXPECT_EQ(h.statusword_bits(), 0);
    out = h.update(0.4, 0.0, w.signals(0.4));
    EXPECT_FALSE(out.home_found);
    EXPECT_EQ(h.statusword_bits(), bits::TargetReached);

    // Once attained, halt and abort change nothing.
    ASSERT_TRUE(h.start(34, parameters(), 0.0));
    h.update(0.0, 0.0, w.signals(0.0));
    h.update(0.31, 2.0, w.signals(0.31));
    ASSERT_EQ(h.status(), HomingStatus::Attained);
    h.halt();
    h.abort();
    EXPECT_EQ(h.status(), HomingStatus::Attained);
    EXPECT_EQ(h.statusword_bits(), bits::HomingAttained);
}

TEST(HomingErrors, HomeSwitchBehindALimitSwitch) {
    // Methods 3-6 and 19-22 have no reversal: the limit switch in the search direction is an error.
    World w;
    w.shape = Shape::ActiveAbove;
    w.home_low = 100;  // beyond the positive limit switch
    for (const int method : {3, 4, 19, 20}) {
        SCOPED_TRACE(method);
        const Outcome r = simulate(w, method, 0.0);
        EXPECT_EQ(r.status, HomingStatus::Error);
        EXPECT_EQ(r.fault, HomingFault::LimitSwitch);
        EXPECT_EQ(r.found_events, 0);
        EXPECT_EQ(r.final_bits, bits::HomingError | bits::TargetReached);
        EXPECT_GE(r.max_position, w.positive_limit);
    }
    w.shape = Shape::ActiveBelow;
    w.home_low = -100;
    for (const int method : {5, 6, 21, 22}) {
        SCOPED_TRACE(method);
        const Outcome r = simulate(w, method, 0.0);
        EXPECT_EQ(r.status, HomingStatus::Error);
        EXPECT_EQ(r.fault, HomingFault::LimitSwitch);
        EXPECT_LE(r.min_position, w.negative_limit);
    }
}

TEST(HomingErrors, NoHomeSwitchBetweenTheLimitSwitches) {
    World w;
    w.shape = Shape::Absent;
    for (const int method : {7, 11, 24, 30}) {
        SCOPED_TRACE(method);
        const Outcome r = simulate(w, method, 5.0);
        EXPECT_EQ(r.status, HomingStatus::Error);
        EXPECT_EQ(r.fault, HomingFault::HomeSwitchNotFound);
        // Both directions were searched.
        EXPECT_LE(r.min_position, w.negative_limit);
        EXPECT_GE(r.max_position, w.positive_limit);
        EXPECT_EQ(r.final_bits, bits::HomingError | bits::TargetReached);
        // One reversal only: the error comes at the limit switch opposite to the initial direction.
        const double brake = kSpeedSwitch * kSpeedSwitch / (2 * kAcceleration) + 0.05;
        if (method == 7 || method == 24) {
            EXPECT_NEAR(r.position, w.negative_limit - brake / 2, brake / 2);
        } else {
            EXPECT_NEAR(r.position, w.positive_limit + brake / 2, brake / 2);
        }
    }
}

TEST(HomingErrors, ErrorBitsWhileBraking) {
    World w;
    w.shape = Shape::ActiveAbove;
    w.home_low = 100;
    Homing h;
    ASSERT_TRUE(h.start(3, parameters(), 35.0));
    double pos = 35;
    double vel = 0;
    bool seen_moving_error = false;
    for (int i = 0; i < 10000; ++i) {
        const HomingOutput out = h.update(pos, vel, w.signals(pos));
        if (out.status == HomingStatus::Error && !out.target_reached) {
            seen_moving_error = true;
            EXPECT_EQ(h.statusword_bits(), bits::HomingError);  // 1/0/0
            EXPECT_EQ(out.velocity, 0);
        }
        if (out.status == HomingStatus::Error && out.target_reached) break;
        const double step = out.acceleration * w.dt;
        vel += std::clamp(out.velocity - vel, -step, step);
        pos += vel * w.dt;
    }
    EXPECT_TRUE(seen_moving_error);
    EXPECT_EQ(h.statusword_bits(), bits::HomingError | bits::TargetReached);  // 1/0/1
}

TEST(HomingErrors, IndexSearchRunsIntoTheOtherLimitSwitch) {
    World w;
    w.negative_limit = -20;
    w.positive_limit = -19.5;  // the first pulse right of -20 would be at -19.1
    HomingParameters p = parameters();
    p.index_phase = 0.9;
    const Outcome r = simulate(w, 1, -19.8, p);
    EXPECT_EQ(r.status, HomingStatus::Error);
    EXPECT_EQ(r.fault, HomingFault::LimitSwitch);
    EXPECT_EQ(r.found_events, 0);
    // Without index pulse (method 17) the same axis homes on the edge.
    const Outcome r17 = simulate(w, 17, -19.8, p);
    EXPECT_EQ(r17.status, HomingStatus::Attained);
    EXPECT_GE(r17.home, -20.0);
    EXPECT_LE(r17.home, -20.0 + kEdgeTolerance);
}

TEST(HomingStart, SupportedMethods) {
    for (int m = -5; m <= 40; ++m) {
        const bool expected =
            (m >= 1 && m <= 14) || (m >= 17 && m <= 30) || m == 33 || m == 34 || m == 35 || m == 37;
        EXPECT_EQ(Homing::supported(m), expected) << m;
        EXPECT_EQ(Homing::uses_index(m), (m >= 1 && m <= 14) || m == 33 || m == 34) << m;
        Homing h;
        EXPECT_EQ(h.start(m, parameters(), 0.0), expected) << m;
        if (!expected) {
            EXPECT_EQ(h.status(), HomingStatus::NotStarted);
            EXPECT_EQ(h.statusword_bits(), bits::TargetReached);
        }
    }
}

TEST(HomingStart, RejectsUnusableParameters) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    Homing h;
    HomingParameters p = parameters();
    p.speed_switch = 0;
    EXPECT_FALSE(h.start(17, p, 0));
    p = parameters();
    p.speed_zero = -1;
    EXPECT_FALSE(h.start(17, p, 0));
    p = parameters();
    p.acceleration = nan;
    EXPECT_FALSE(h.start(17, p, 0));
    p = parameters();
    EXPECT_FALSE(h.start(17, p, nan));
    // The index period is needed by the methods with index pulse only.
    p.index_period = 0;
    EXPECT_FALSE(h.start(1, p, 0));
    EXPECT_FALSE(h.start(34, p, 0));
    EXPECT_EQ(h.status(), HomingStatus::NotStarted);
    EXPECT_TRUE(h.start(17, p, 0));
    EXPECT_EQ(h.status(), HomingStatus::InProgress);
    EXPECT_EQ(h.method(), 17);
    // A refused start leaves a running procedure alone.
    EXPECT_FALSE(h.start(15, parameters(), 0));
    EXPECT_EQ(h.status(), HomingStatus::InProgress);
    EXPECT_EQ(h.method(), 17);
}

TEST(HomingStart, RestartAfterAttainedSearchesAgain) {
    World w;
    Homing h;
    ASSERT_TRUE(h.start(35, parameters(), 3.0));
    ASSERT_EQ(h.status(), HomingStatus::Attained);
    ASSERT_TRUE(h.start(34, parameters(), 3.0));
    EXPECT_EQ(h.status(), HomingStatus::InProgress);
    EXPECT_EQ(h.statusword_bits(), 0);
    const HomingOutput out = h.update(3.0, 0.0, w.signals(3.0));
    EXPECT_FALSE(out.home_found);
    EXPECT_EQ(out.velocity, kSpeedZero);
}

}  // namespace
}  // namespace vecat::cia402
