#include "cia402/cyclic_modes.hpp"

#include <algorithm>
#include <cmath>

#include "cia402/profile_modes.hpp"

namespace vecat::cia402 {

namespace {

// Bit 12 of the cyclic modes. `cyclic_following` is the axis's: a TWINsync slave that follows its master
// sets it too, and the torque mode leaves it as it was.
bool follows_command(const Axis& a) {
    return a.cyclic_following && !a.halted;
}

}  // namespace

void CyclicPositionMode::step(Axis& a, double dt) {
    const std::int32_t raw = a.cmd().target_position;
    const double offset = a.cmd().position_offset;
    if (!valid_ || raw != raw_) {
        from_ = valid_ ? a.demand.p : a.actual;
        to_ = static_cast<double>(raw) + offset;
        // A modulo axis (0x607B): the set-point is a position in the range, nearest to the demand.
        if (a.modulo()) to_ = a.modulo_nearest(to_, from_);
        raw_ = raw;
        since_.restart();
        valid_ = true;
    }
    if (a.halted) {
        a.stop(stop_for(StopOption::Halt, a.par().options), dt);
        valid_ = false;
        return;
    }
    a.stopping = StopKind::None;
    const double period = a.interpolation_period();
    since_.advance(true, dt);
    // (min(1, since / period): a quotient of at least 1 is 1.)
    const double frac = since_.at_least(period) ? 1.0 : since_.seconds() / period;
    double p = from_ + (to_ - from_) * frac;
    // The velocity feed-forward is the demand's own change over this servo period.
    double v = (p - a.demand.p) / dt;
    const double limited = a.modulo() ? p : a.clamp_to_software_limits(p);  // no limits on an endless axis
    if (limited != p) {
        a.internal_limit = true;
        p = limited;
        v = 0;
    }
    if (a.blocked(p - a.demand.p)) {
        a.internal_limit = true;
        p = a.demand.p;
        v = 0;
    }
    a.cyclic_following = !a.internal_limit;
    const double acc = (v - a.demand.v) / dt;
    a.demand = {p, v, std::abs(acc) < 1e12 ? acc : 0.0};
    a.demand.v += a.cmd().velocity_offset;
    a.loop = LoopMode::Position;
    a.torque_ff = a.cmd().torque_offset;
}

ModeStatus CyclicPositionMode::status(const Axis& a, const StatusInputs& in) {
    ModeStatus s;
    s.target_reached = std::abs(to_ - a.actual) <= a.par().position_window;
    s.bit12 = follows_command(a);
    s.bit13 = in.following_error;
    return s;
}

void CyclicVelocityMode::step(Axis& a, double dt) {
    if (a.halted) {
        a.stop(stop_for(StopOption::Halt, a.par().options), dt);
        if (a.loop == LoopMode::Position) {
            a.loop = LoopMode::Velocity;
            a.velocity_cmd = a.demand.v;
        }
        return;
    }
    a.stopping = StopKind::None;
    double v = static_cast<double>(a.cmd().target_velocity) + a.cmd().velocity_offset;
    v = std::clamp(v, -a.max_velocity(), a.max_velocity());
    if (a.blocked(v)) {
        a.internal_limit = true;
        v = 0;
    }
    a.cyclic_following = !a.internal_limit;
    a.loop = LoopMode::Velocity;
    a.velocity_cmd = v;
    a.torque_ff = a.cmd().torque_offset;
}

ModeStatus CyclicVelocityMode::status(const Axis& a, const StatusInputs&) {
    ModeStatus s;
    s.bit12 = follows_command(a);
    return s;
}

void CyclicTorqueMode::step(Axis& a, double dt) {
    torque_step(a, static_cast<double>(a.cmd().target_torque) + a.cmd().torque_offset, false, dt);
}

ModeStatus CyclicTorqueMode::status(const Axis& a, const StatusInputs&) {
    ModeStatus s;
    s.bit12 = follows_command(a);
    return s;
}

}  // namespace vecat::cia402
