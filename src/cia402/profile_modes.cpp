#include "cia402/profile_modes.hpp"

#include <algorithm>
#include <cmath>

namespace vecat::cia402 {

namespace cw = protocol::cia402::cw;

// ---- Profile position (CiA 402 6.5) ---------------------------------------------------------------------

void ProfilePositionMode::reset() {
    moving_ = false;
    pending_target_.reset();
    setpoint_ack_ = false;
    refused_ = false;
    velocity_.reset();
    activation_.reset();
}

void ProfilePositionMode::disable() {
    // The acknowledge stays until the master takes bit 4 back.
    moving_ = false;
    pending_target_.reset();
    activation_.reset();
}

void ProfilePositionMode::start_move(Axis& a, double target) {
    target_ = target;
    moving_ = true;
    ProfileLimits l = a.profile_limits();
    if (velocity_) l.velocity = *velocity_;
    a.profile.move_to(target, l);
}

std::optional<double> ProfilePositionMode::accept(Axis& a, std::uint16_t c) {
    double target = static_cast<double>(a.cmd().target_position);
    const bool queued = moving_ && !(c & cw::ChangeSetImmediately) && !a.halted;
    if (c & cw::Relative) {
        target += target_;
    } else if (a.modulo()) {
        // A modulo axis (0x607B): the target is an orientation, reached as 0x60F2 says, from where the
        // axis will be when the move starts.
        return a.modulo_target(target, queued ? target_ : a.demand.p);
    }
    if (a.modulo()) return target;  // no software limits on an endless axis
    const double clamped = a.clamp_to_software_limits(target);
    if (clamped == target) return target;
    // Beyond the software position limits (0x607D). TX1250 2.1, start parameters note 4: "the start is
    // refused and an error is generated"; the set-point is not acknowledged (bit 12 stays 0).
    const std::uint8_t reaction = a.par().software_limit_reaction;
    if (reaction == limit_reaction::Clamp) {
        a.internal_limit = true;
        return clamped;
    }
    refused_ = true;
    if (reaction == limit_reaction::Fault) a.target_refused = true;
    return std::nullopt;
}

void ProfilePositionMode::new_velocity_and_end_position(Axis& a, double epos) {
    const double pos = a.demand.p;
    // The logical direction of the positioning: of the motion, else towards the new end position.
    const double v = a.demand.v;
    const double dir = v != 0 ? (v > 0 ? 1.0 : -1.0) : (epos >= pos ? 1.0 : -1.0);
    // On a modulo axis APos is a position in the range: the continuous position nearest to the axis.
    const double apos = a.modulo_nearest(static_cast<double>(a.par().activation_position), pos);
    const double p = dir * pos, e = dir * epos, ap = dir * apos;
    const double vnew = std::min(static_cast<double>(a.par().activation_velocity), a.max_velocity());
    activation_.reset();
    velocity_.reset();  // VOld, the profile velocity 0x6081
    if (e < p) {
        // Cases 3, 5, 6 (APos <= EPos <= Pos, EPos <= APos <= Pos, EPos <= Pos <= APos): stop, and back
        // to EPos with VOld (the generator's stop and return).
    } else if (ap <= p) {
        velocity_ = vnew;  // case 2, APos <= Pos <= EPos: APos already crossed, VNew at once
    } else if (ap <= e) {
        activation_ = dir * ap;  // case 1, Pos <= APos <= EPos: VNew once APos is crossed
        activation_dir_ = dir;
        activation_velocity_ = vnew;
    }  // else case 4, Pos <= EPos <= APos: the new end position with VOld only
    start_move(a, epos);
}

void ProfilePositionMode::step(Axis& a, double dt) {
    const std::uint16_t c = a.controlword;
    if (a.rising(cw::NewSetpoint) && !pending_target_) {
        // TX1250 2.4: VNew must be above 0 (and is limited to the maximum velocity).
        const bool nvp = a.par().activation_mode == 1 && a.par().activation_velocity > 0;
        if (const auto target = accept(a, c)) {
            refused_ = false;
            setpoint_ack_ = true;
            if (!a.blocked(*target - a.actual)) {
                if (!moving_ || (c & cw::ChangeSetImmediately) || a.halted) {
                    if (nvp) {
                        new_velocity_and_end_position(a, *target);
                    } else {
                        // A plain new set-point ends a pending activation (TX1250 2.4, special features).
                        velocity_.reset();
                        activation_.reset();
                        start_move(a, *target);
                    }
                } else {
                    pending_target_ = *target;  // set of set-points: executed after the current one
                }
            }
        }
    }
    if (refused_) a.internal_limit = true;
    // Set-point acknowledge: cleared once the master took bit 4 back and the buffer is free again.
    if (!(c & cw::NewSetpoint) && !pending_target_) setpoint_ack_ = false;

    if (a.halted) {
        a.stop(stop_for(StopOption::Halt, a.par().options), dt);
        return;
    }
    if (a.stopping != StopKind::None) {
        // Halt released (bit 8 = 0: "execute positioning", CiA 402 6.5.3; HIWIN guide 9.1.1): the move goes
        // on from where the halt ramp is towards its target.
        a.stopping = StopKind::None;
        if (moving_) start_move(a, target_);
    }
    if (pending_target_ && (c & cw::ChangeOnSetpoint)) {
        // Change on set-point: go on to the next target without stopping at this one.
        start_move(a, *pending_target_);
        pending_target_.reset();
    }
    // A hardware limit switch in the direction of travel stops the move.
    if (moving_ && a.blocked(a.demand.v) && a.stopping == StopKind::None) {
        a.profile.stop(static_cast<double>(std::max<std::uint32_t>(a.par().quick_stop_deceleration, 1)),
                       a.profile_limits().jerk);
        target_ = a.profile.target();
        moving_ = false;
        pending_target_.reset();
    }
    a.loop = LoopMode::Position;
    a.torque_ff = 0;
    a.demand = a.profile.step(dt);
    if (activation_ && moving_ && activation_dir_ * (a.demand.p - *activation_) >= 0) {
        // TX1250 2.4 case 1: APos crossed, the rest of the move at VNew.
        activation_.reset();
        velocity_ = activation_velocity_;
        start_move(a, target_);
    }
    if (moving_ && a.profile.done()) {
        moving_ = false;
        activation_.reset();
        if (pending_target_) {
            velocity_.reset();
            start_move(a, *pending_target_);
            pending_target_.reset();
        }
    }
    if (a.positive_limit || a.negative_limit) a.internal_limit = true;
    if (!a.modulo() && a.software_limits_enabled() &&
        (a.actual <= a.software_limit_min() || a.actual >= a.software_limit_max()))
        a.internal_limit = true;
}

ModeStatus ProfilePositionMode::status(const Axis& a, const StatusInputs& in) {
    const bool in_window = std::abs(target_ - a.actual) <= a.par().position_window;
    position_window_time_.advance(in_window && !moving_ && a.profile.done(), in.dt);
    ModeStatus s;
    s.target_reached = a.halted ? (in.standing && a.profile.done())
                                : !moving_ && !pending_target_ &&
                                      position_window_time_.at_least(a.par().position_window_time * 1e-3);
    s.bit12 = setpoint_ack_;       // set-point acknowledge
    s.bit13 = in.following_error;  // following error
    return s;
}

// ---- Profile velocity (CiA 402 6.7) ---------------------------------------------------------------------

void ProfileVelocityMode::step(Axis& a, double dt) {
    double target = static_cast<double>(a.cmd().target_velocity);
    target = std::clamp(target, -a.max_velocity(), a.max_velocity());
    if (a.halted) {
        a.stop(stop_for(StopOption::Halt, a.par().options), dt);
        if (a.loop == LoopMode::Position) {
            a.loop = LoopMode::Velocity;
            a.velocity_cmd = a.demand.v;
        }
        running_ = false;
        return;
    }
    if (a.blocked(target)) {
        a.internal_limit = true;
        target = 0;
    }
    if (a.stopping != StopKind::None || target != target_ || !running_) {
        if (a.stopping != StopKind::None) a.profile.reset({a.actual, a.velocity, 0.0});
        a.stopping = StopKind::None;
        ProfileLimits l = a.profile_limits();
        a.profile.run_at(target, l);
        target_ = target;
        running_ = true;
    }
    const Kinematics k = a.profile.step(dt);
    a.loop = LoopMode::Velocity;
    a.velocity_cmd = k.v;
    a.torque_ff = a.inertia * a.user_velocity_to_rad(k.a) / a.nm_per_permille;
}

ModeStatus ProfileVelocityMode::status(const Axis& a, const StatusInputs& in) {
    const double target = a.cmd().target_velocity;
    const bool in_window = std::abs(target - a.velocity) <= a.par().velocity_window;
    velocity_window_time_.advance(in_window, in.dt);
    ModeStatus s;
    s.target_reached =
        a.halted ? in.standing : velocity_window_time_.at_least(a.par().velocity_window_time * 1e-3);
    s.bit12 = in.speed_zero && in.speed_zero->at_least(a.par().velocity_threshold_time * 1e-3);  // speed zero
    return s;
}

// ---- Profile torque (CiA 402 6.9) and the torque loop of both torque modes ------------------------------

void torque_step(Axis& a, double target, bool profile, double dt) {
    const double max = a.par().max_torque;
    target = std::clamp(target, -max, max);
    if (a.blocked(target)) {
        a.internal_limit = true;
        target = 0;
    }
    if (profile) {
        // Profile torque: the demand moves to the target at the torque slope (per mille per second).
        const double slope = std::max<double>(a.par().torque_slope, 1.0);
        const double step = slope * dt;
        a.torque_cmd += std::clamp(target - a.torque_cmd, -step, step);
    } else {
        a.torque_cmd = target;
    }
    a.loop = LoopMode::Torque;
    // Speed limit: above the maximum motor speed the velocity loop takes over at that speed, with the
    // torque demand as the limit.
    const double vmax = a.max_velocity();
    if (std::abs(a.velocity) > vmax && a.torque_cmd * a.velocity > 0) {
        a.loop = LoopMode::Velocity;
        a.velocity_cmd = std::copysign(vmax, a.velocity);
        a.internal_limit = true;
    }
}

void ProfileTorqueMode::step(Axis& a, double dt) {
    torque_step(a, a.cmd().target_torque, true, dt);
}

ModeStatus ProfileTorqueMode::status(const Axis& a, const StatusInputs&) {
    ModeStatus s;
    s.target_reached = std::abs(a.torque_cmd - a.cmd().target_torque) < 0.5;
    return s;
}

}  // namespace vecat::cia402
