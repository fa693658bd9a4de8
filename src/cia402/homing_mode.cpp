#include "cia402/homing_mode.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vecat::cia402 {

namespace cw = protocol::cia402::cw;

namespace {
bool has_accuracy_compensation(const Axis& a) {
    return a.par().strategy.homing == HomingConvention::Hiwin;
}
}  // namespace

std::optional<int> homing_method_of(HomingConvention c, int value) {
    if (c == HomingConvention::Cia402) return value;
    switch (value) {
        case 1:
        case 2:
        case 33:
        case 34:
            return value;
        case 3:
            return 7;
        case 4:
            return 10;
        case 5:
            return 11;
        case 6:
            return 14;
        default:
            return std::nullopt;
    }
}

void HomingMode::reset() {
    bits_ = 0;
    active_ = error_ = compensated_ = false;
    velocity_ = 0;
    homing_.abort();
}

void HomingMode::step(Axis& a, double dt) {
    // Bit 4 rising starts the homing method 0x6098; bit 4 falling or halt interrupts it.
    if (a.rising(cw::HomingStart)) {
        const DriveParameters& p = a.par();
        const double ipu = a.ratios.per_user;
        HomingParameters hp;
        hp.speed_switch = p.homing_speed_switch;
        hp.speed_zero = p.homing_speed_zero;
        hp.acceleration = p.homing_acceleration;
        hp.home_offset = p.home_offset;
        hp.index_period = a.ratios.per_revolution / ipu;
        hp.index_phase = p.index_pulse_offset / ipu + a.home_shift;
        hp.standstill_velocity = a.standstill_velocity;
        const auto method = homing_method_of(p.strategy.homing, p.homing_method);
        const bool no_homing = p.strategy.homing == HomingConvention::Hiwin && p.homing_method == 0;
        if (no_homing) homing_ = Homing{};  // HIWIN 0, "No homing mode": nothing starts, nothing fails
        active_ = method && homing_.start(*method, hp, a.actual);
        error_ = !active_ && !no_homing;
        compensated_ = false;
        velocity_ = 0;
    }
    if (active_ && (!(a.controlword & cw::HomingStart) || a.halted)) {
        homing_.halt();
        active_ = false;
    }
    HomingOutput out;
    if (active_) {
        out = homing_.update(a.actual, a.velocity, {a.negative_limit, a.positive_limit, a.home_switch});
        if (out.home_found) {
            // The coordinate system: the home position now reads as the home offset 0x607C.
            const double shift = homing_.position_shift();
            a.home_shift += shift;
            a.actual += shift;
            a.demand.p += shift;
            a.profile.reset(a.demand);
            velocity_ = std::numeric_limits<double>::quiet_NaN();  // re-plan from the shifted state
        }
        if (out.status == HomingStatus::Attained && out.target_reached) active_ = false;
        if (out.status == HomingStatus::Error && out.target_reached) active_ = false;
    }
    // HIWIN 9.4, "Initiate accuracy compensation": once homing is completed (bits 10 and 12), 0x2010 bit 0
    // makes the drive clear the feedback position to 0 and set bit 15. The master then takes the actual
    // position as its command position (step VIII).
    if (has_accuracy_compensation(a) && !active_ && !compensated_ && attained() &&
        (bits_ & sw::TargetReached) && (a.cmd().input_function & 1u)) {
        const double shift = -a.actual;
        a.home_shift += shift;
        a.actual = 0;
        a.demand.p += shift;
        a.profile.reset(a.demand);
        velocity_ = std::numeric_limits<double>::quiet_NaN();
        compensated_ = true;
    }
    if (a.halted && !active_) {
        a.stop(stop_for(StopOption::Halt, a.par().options), dt);
    } else {
        a.stopping = StopKind::None;
        const double v = active_ ? out.velocity : 0.0;
        // (0x609A absent reads 0 here and 1 there: the same, as both are raised to 1.)
        const double acc = (active_ && out.acceleration > 0)
                               ? out.acceleration
                               : std::max<double>(a.par().homing_acceleration, 1.0);
        if (!(v == velocity_)) {
            ProfileLimits l{std::max(std::abs(v), 1.0), acc, acc, 0.0};
            a.profile.run_at(v, l);
            velocity_ = v;
        }
        a.demand = a.profile.step(dt);
        a.loop = LoopMode::Position;
        a.torque_ff = 0;
    }
    bits_ = error_ ? static_cast<std::uint16_t>(sw::Bit13 | sw::TargetReached) : homing_.statusword_bits();
}

ModeStatus HomingMode::status(const Axis&, const StatusInputs&) {
    return {(bits_ & sw::TargetReached) != 0, (bits_ & sw::Bit12) != 0, (bits_ & sw::Bit13) != 0};
}

}  // namespace vecat::cia402
