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
}

void ProfilePositionMode::disable() {
    // The acknowledge stays until the master takes bit 4 back.
    moving_ = false;
    pending_target_.reset();
}

void ProfilePositionMode::start_move(Axis& a, double target) {
    target_ = target;
    moving_ = true;
    a.profile.move_to(target, a.profile_limits());
}

void ProfilePositionMode::step(Axis& a, double dt) {
    const std::uint16_t c = a.controlword;
    if (a.rising(cw::NewSetpoint) && !pending_target_) {
        double target = static_cast<double>(a.cmd().target_position);
        if (c & cw::Relative) target += target_;
        const double clamped = a.clamp_to_software_limits(target);
        if (clamped != target) a.internal_limit = true;
        setpoint_ack_ = true;
        if (!a.blocked(clamped - a.actual)) {
            if (!moving_ || (c & cw::ChangeSetImmediately) || a.halted)
                start_move(a, clamped);
            else
                pending_target_ = clamped;  // set of set-points: executed after the current one
        }
    }
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
    if (moving_ && a.profile.done()) {
        moving_ = false;
        if (pending_target_) {
            start_move(a, *pending_target_);
            pending_target_.reset();
        }
    }
    if (a.positive_limit || a.negative_limit) a.internal_limit = true;
    if (a.software_limits_enabled() &&
        (a.actual <= a.software_limit_min() || a.actual >= a.software_limit_max()))
        a.internal_limit = true;
}

ModeStatus ProfilePositionMode::status(const Axis& a, const StatusInputs& in) {
    const bool in_window = std::abs(target_ - a.actual) <= a.par().position_window;
    position_window_time_ = (in_window && !moving_ && a.profile.done()) ? position_window_time_ + in.dt : 0.0;
    ModeStatus s;
    s.target_reached = a.halted ? (in.standing && a.profile.done())
                                : !moving_ && !pending_target_ &&
                                      position_window_time_ >= a.par().position_window_time * 1e-3;
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
    velocity_window_time_ = in_window ? velocity_window_time_ + in.dt : 0.0;
    ModeStatus s;
    s.target_reached = a.halted ? in.standing : velocity_window_time_ >= a.par().velocity_window_time * 1e-3;
    s.bit12 = in.speed_zero_time >= a.par().velocity_threshold_time * 1e-3;  // speed zero
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
