#include "cia402/operation_mode.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

namespace vecat::cia402 {

namespace {

// 10^index for every int8 index, from std::pow once (the interpolation period is read every servo step).
double pow10_of(std::int8_t index) {
    static const std::array<double, 256> table = [] {
        std::array<double, 256> t{};
        for (int i = -128; i < 128; ++i)
            t[static_cast<std::size_t>(i + 128)] = std::pow(10.0, i);
        return t;
    }();
    return table[static_cast<std::size_t>(index + 128)];
}

}  // namespace

void Axis::stop(StopKind k, double dt) {
    if (k == StopKind::CurrentLimit || k == StopKind::VoltageLimit) {
        // Brake at the torque limit: velocity loop with a zero set-point.
        loop = LoopMode::Velocity;
        velocity_cmd = 0;
        torque_ff = 0;
        demand = {actual, 0.0, 0.0};
        profile.reset(demand);
        return;
    }
    const double dec = static_cast<double>(k == StopKind::QuickStopRamp ? par().quick_stop_deceleration
                                                                        : par().profile_deceleration);
    if (stopping != k) {
        // Starts from the current demand in position modes, from the actual motion otherwise. A slave that
        // followed TWINsync has a demand the profile never made: it brakes from its actual motion too
        // (the profile left from its enable would make the ramp jump back there).
        if (loop != LoopMode::Position || coupled) profile.reset({actual, velocity, 0.0});
        profile.stop(std::max(dec, 1.0), profile_limits().jerk);
        stopping = k;
    }
    demand = profile.step(dt);
    loop = LoopMode::Position;
    velocity_cmd = demand.v;
    torque_ff = 0;
}

double Axis::max_velocity() const {
    double v = static_cast<double>(par().max_profile_velocity);
    // Max motor speed 0x6080 (rpm) converted to user units/s.
    const double rpm = static_cast<double>(par().max_motor_speed);
    if (rpm > 0) v = std::min(v, ratios.radians_to_user(rpm / 60.0 * 2.0 * std::numbers::pi));
    return std::max(v, 1.0);
}

ProfileLimits Axis::profile_limits() const {
    const DriveParameters& p = par();
    ProfileLimits l;
    l.velocity = std::min(static_cast<double>(p.profile_velocity), max_velocity());
    l.acceleration = static_cast<double>(p.profile_acceleration);
    l.deceleration = static_cast<double>(p.profile_deceleration);
    if (p.max_acceleration > 0)
        l.acceleration = std::min(l.acceleration, static_cast<double>(p.max_acceleration));
    if (p.max_deceleration > 0)
        l.deceleration = std::min(l.deceleration, static_cast<double>(p.max_deceleration));
    l.jerk = p.motion_profile_type == 0 ? 0.0 : static_cast<double>(p.profile_jerk);
    return l;
}

double Axis::interpolation_period() const {
    const double value = par().interpolation_value;
    const double t = par().strategy.interpolation == InterpolationFormat::Ticks62_5us
                         ? value * 62.5e-6
                         : value * pow10_of(par().interpolation_index);
    return t > 0 ? std::max(t, kPeriod) : 1e-3;
}

bool Axis::software_limits_enabled() const {
    const auto lo = par().software_limit_min.value_or(std::numeric_limits<std::int32_t>::min());
    const auto hi = par().software_limit_max.value_or(std::numeric_limits<std::int32_t>::max());
    return lo < hi;
}

double Axis::clamp_to_software_limits(double p) const {
    if (!software_limits_enabled()) return p;
    return std::clamp(p, software_limit_min(), software_limit_max());
}

void Axis::set_position_range(std::int32_t lo, std::int32_t hi) {
    constexpr auto kMin = std::numeric_limits<std::int32_t>::min();
    constexpr auto kMax = std::numeric_limits<std::int32_t>::max();
    const bool linear = lo >= hi || (lo == kMin && hi == kMax);  // the default range: a linear axis
    modulo_range_ = linear ? 0.0 : static_cast<double>(hi) - static_cast<double>(lo);
    range_min_ = lo;
}

std::int64_t Axis::wrap_in_range(std::int64_t p) const {
    const auto r = static_cast<std::int64_t>(modulo_range_);  // exact: a difference of two INT32
    std::int64_t m = (p - range_min_) % r;
    if (m < 0) m += r;
    return m + range_min_;
}

namespace {

// x mod r in [0, r).
double floor_mod(double x, double r) {
    const double m = x - r * std::floor(x / r);
    return m >= r ? 0.0 : m;
}

}  // namespace

double Axis::modulo_target(double target, double from) const {
    const double r = modulo_range();
    if (r <= 0) return target;
    const double lo = range_min_;
    const double t = target - lo;
    const double orient = floor_mod(t, r);
    double delta = orient - floor_mod(from - lo, r);
    // Whole ranges beyond the range: turns before stopping at the orientation (one direction only).
    const double turns = (t < 0 || t >= r) ? std::floor(std::abs(t) / r) : 0.0;
    switch ((par().positioning_option >> kRotaryDirectionShift) & 3u) {
        case kRotaryOnlyNegative:
            if (delta > 0) delta -= r;
            delta -= turns * r;
            break;
        case kRotaryOnlyPositive:
            if (delta < 0) delta += r;
            delta += turns * r;
            break;
        case kRotaryShortest:
            if (delta > r / 2)
                delta -= r;
            else if (delta <= -r / 2)
                delta += r;
            break;
        default:  // as a linear axis within the range
            break;
    }
    return from + delta;
}

double Axis::modulo_nearest(double target, double from) const {
    const double r = modulo_range();
    if (r <= 0) return target;
    double delta = floor_mod(target - from, r);
    if (delta > r / 2) delta -= r;
    return from + delta;
}

}  // namespace vecat::cia402
