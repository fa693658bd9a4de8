#include "cia402/drive_core.hpp"

#include "cia402/settled.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <utility>

#include "common/rounding.hpp"
#include "protocol/coe.hpp"

namespace vecat::cia402 {

namespace {

namespace cw = protocol::cia402::cw;
namespace error_register = protocol::error_register;

std::int32_t sat32(double v) {
    if (!(v == v)) return 0;
    v = std::clamp(v, -2147483648.0, 2147483647.0);
    return static_cast<std::int32_t>(round_half_away(v));
}

std::int16_t sat16(double v) {
    if (!(v == v)) return 0;
    return static_cast<std::int16_t>(round_half_away(std::clamp(v, -32768.0, 32767.0)));
}

}  // namespace

DriveCore::DriveCore(const MotorParameters& motor)
    : mech_(motor, ControlGains{}), settled_(std::make_unique<Settled>(*this)) {
    axis_.inertia = motor.rotor_inertia + motor.load_inertia;
}

DriveCore::~DriveCore() = default;

void DriveCore::set_period_ns(std::uint64_t ns) {
    wake();  // (the skipped periods' time at the period they were skipped at)
    period_ns_ = ns > 0 ? ns : kPeriodNs;
}

// (A settled drive needs no wake() here: the fields set here come from the DriveIo's parameters alone, and
// a period is skipped only while the DriveIo is as the settled period found it.)
void DriveCore::configure(const DriveIo& io) {
    axis_.io = &io;
    const DriveParameters& p = io.parameters;
    // factors_ only ever holds a valid group, so an unchanged one needs no check.
    const FactorGroup& f = p.factors;
    const bool same = f.encoder_increments == factors_.encoder_increments &&
                      f.motor_revolutions == factors_.motor_revolutions &&
                      f.gear_motor_revolutions == factors_.gear_motor_revolutions &&
                      f.gear_shaft_revolutions == factors_.gear_shaft_revolutions &&
                      f.feed == factors_.feed && f.feed_shaft_revolutions == factors_.feed_shaft_revolutions;
    if (!same && f.valid()) {
        factors_ = f;
        axis_.ratios = f.ratios();
    }
    const double rated = static_cast<double>(p.rated_torque) * 1e-3;  // Nm
    axis_.nm_per_permille = rated / 1000.0;
    // Velocity threshold 0x606F, at least one unit per second.
    axis_.standstill_velocity = std::max<double>(p.velocity_threshold, 1.0);
    axis_.set_position_range(p.position_range_min, p.position_range_max);  // 0x607B: modulo or linear
}

void DriveCore::start(DriveIo& io) {
    wake();
    settled_->on = settled_->values_current = false;
    axis_.io = &io;
    update_inputs(io);
    write_feedback(io);
}

void DriveCore::step(DriveIo& io, bool publish) {
    const double dt = static_cast<double>(period_ns_) * 1e-9;
    axis_.io = &io;
    DriveFeedback& fb = io.feedback;
    fb.raised.reset();
    fb.cleared = fb.probe = fb.twinsync = false;
    // A settled drive skips the period, unless it has to run it (skippable, below).
    Settled& settled = *settled_;
    bool check = false;
    if (settled.on) {
        const bool same = (!settled.touched || settled.same_core(*this)) && settled.same_io(io);
        if (same) settled.touched = false;
        if (same && skippable(io)) {
            skip(io, publish);
            return;
        }
        settled.on = false;
        settled.values_current = false;
        check = same;
    }
    if (settled.pending != 0) catch_up_skipped();
    settled.temperature_steady = false;
    if (check) {
        settled.begin_timers(*this);  // the bytes are the settled period's: compared again after this one
    } else if (publish && settled.enabled && settled.worth_checking(fb)) {
        // A period that publishes its feedback may settle (not one that leaves an older feedback in the
        // DriveIo).
        check = true;
        settled.take(*this, io);
    }
    ++steps_;

    axis_.controlword = coupling_.controlword(io.command.controlword, io.twinsync, sm_.state());
    update_inputs(io);
    check_faults(io, dt);
    run_state_machine(io);
    // Velocity override (TwinCAT NC PTP online change) of the profile modes, in ppm of 100 %.
    const std::uint32_t ov = std::min<std::uint32_t>(io.parameters.velocity_override, 1'000'000);
    if (io.parameters.override_type != axis_.profile.override_type())
        axis_.profile.set_override_type(io.parameters.override_type);
    if (ov != override_ppm_) {
        override_ppm_ = ov;
        axis_.profile.set_override(ov * 1e-6);
    }
    select_mode(io.command);
    run_setpoints(io, dt);
    if (axis_.target_refused) {
        // A profile position target beyond the software position limits 0x607D (0x2112 = 0).
        axis_.target_refused = false;
        raise(io, {fault::ReferenceLimit, error_register::DeviceProfile});
    }
    if (mode_ == Mode::Homing && hm_.attained()) coupling_.set_homed();

    // The touch probe and the index latch what the encoder measures: nothing while it is lost, and not
    // the jump of the period in which it is read again.
    const bool encoder_was_valid = encoder_valid_;
    const double previous_inc = previous_machine_inc_;
    run_mechanics(io, dt);
    run_touch_probe(io, encoder_was_valid ? previous_inc : previous_machine_inc_, previous_machine_inc_);
    write_feedback(io, publish);
    // The TWINsync values every cycle while the link is on; otherwise only for SDO reads, every 4 ms.
    if (io.twinsync.active || steps_ % 16 == 0) {
        fb.twinsync = true;
        fb.twinsync_values = coupling_.values(axis_, mech_, machine_increments(), active_fault_, io.twinsync);
    }
    axis_.previous_controlword = axis_.controlword;
    if (check) {
        settled.on = settled.settled(*this, io);
        settled.touched = !settled.on;
        if (!settled.on) settled.failed();
        // The TWINsync values this period worked out are the fixed point's: the skipped periods show them.
        settled.values_current = settled.on && fb.twinsync;
    }
}

// A settled period that need not run: not while the TWINsync link is on (its values every period), not a
// period that works out the TWINsync values (every 16th) unless a period at this fixed point worked them
// out already.
bool DriveCore::skippable(const DriveIo& io) const {
    return !io.twinsync.active && ((steps_ + 1) % 16 != 0 || settled_->values_current);
}

void DriveCore::skip(DriveIo& io, bool publish) {
    Settled& settled = *settled_;
    DriveFeedback& fb = io.feedback;
    ++steps_;
    ++settled.pending;
    ++settled.skipped;
    // The TWINsync values of the fixed point, every 16th period as a period that runs shows them.
    fb.twinsync = steps_ % 16 == 0;
    // The temperature goes on towards its steady value (the only value of a settled period that may still
    // change); once a period left it as it was, so do the next.
    if (!settled.temperature_steady) {
        const double before = temperature_;
        heat(io.parameters, static_cast<double>(period_ns_) * 1e-9);
        settled.temperature_steady = temperature_ == before;
    }
    if (publish) fb.temperature = sat16(temperature_);
}

bool DriveCore::skip_unchanged_period(DriveIo& io, bool publish) {
    const Settled& settled = *settled_;
    if (!settled.on || settled.touched || !skippable(io)) return false;
    DriveFeedback& fb = io.feedback;
    fb.raised.reset();
    fb.cleared = fb.probe = false;
    skip(io, publish);
    return true;
}

void DriveCore::compensate(double distance, double length, const CompensationLimits& limits) {
    wake();
    // 0 = the move's own dynamics: VK = V, AK+ = A+, AK- = A-, VP = the cruise velocity of the move.
    const ProfileLimits move = axis_.profile_limits();
    CompensationLimits c = limits;
    if (!(c.velocity > 0)) c.velocity = move.velocity;
    if (!(c.acceleration > 0)) c.acceleration = move.acceleration;
    if (!(c.deceleration > 0)) c.deceleration = move.deceleration;
    // The move now ends at its target plus the achievable part of the compensation.
    if (axis_.profile.compensate(distance, length, c) && pp_.moving()) pp_.set_target(axis_.profile.target());
}

void DriveCore::stop_compensation() {
    wake();
    // The move ends at its target plus what the compensation will have travelled.
    if (axis_.profile.stop_compensation() && pp_.moving()) pp_.set_target(axis_.profile.target());
}

void DriveCore::zero_position() {
    wake();
    const double shift = -axis_.actual;
    axis_.home_shift += shift;
    axis_.actual = 0;
    axis_.demand.p += shift;
    axis_.profile.reset(axis_.demand);
}

twinsync::LocalState DriveCore::twinsync_local(std::uint16_t own_controlword, bool synchronised) const {
    return coupling_.local(sm_.state(), sm_.stop(), own_controlword, mode_ == Mode::Homing, synchronised,
                           axis_, mech_);
}

double DriveCore::machine_increments() const {
    return mech_.position() / (2.0 * std::numbers::pi) * axis_.ratios.per_revolution;
}

void DriveCore::update_inputs(DriveIo& io) {
    const DriveParameters& c = io.parameters;
    // Machine position in increments (homing does not move it).
    const double inc = machine_increments();
    axis_.negative_limit = inc <= c.negative_limit_switch;
    axis_.positive_limit = inc >= c.positive_limit_switch;
    const std::int32_t dog = c.strategy.home_switch_length;
    axis_.home_switch = inc >= c.home_switch && (dog <= 0 || inc < static_cast<double>(c.home_switch) + dog);
    probe_inputs_ = c.probe_inputs;
    // 0x60FD: negative and positive limit switch, home switch (CiA 402 6.3.8); bits 16/17 manufacturer:
    // touch probe inputs 1 and 2.
    std::uint32_t di = 0;
    if (axis_.negative_limit) di |= 1u << 0;
    if (axis_.positive_limit) di |= 1u << 1;
    if (axis_.home_switch) di |= 1u << 2;
    if (probe_inputs_ & 1) di |= 1u << 16;
    if (probe_inputs_ & 2) di |= 1u << 17;
    io.feedback.digital_inputs = di;
}

void DriveCore::raise(DriveIo& io, const RaisedFault& f) {
    if (active_fault_ != 0) return;
    active_fault_ = f.code;
    io.feedback.raised = f;
}

void DriveCore::check_faults(DriveIo& io, double dt) {
    const DriveParameters& p = io.parameters;
    const std::uint16_t injected = p.simulated_fault;
    // Encoder and over-current faults are injected into the mechanics, which the drive then monitors
    // (the encoder freezes; the power stage reports over-current, also from its I2t protection).
    mech_.inject_encoder_fault(injected == fault::Encoder);
    mech_.inject_overcurrent(injected == fault::OverCurrent);
    if (mech_.overcurrent()) raise(io, {fault::OverCurrent, error_register::Current});
    if (!mech_.encoder_ok()) raise(io, {fault::Encoder, error_register::Manufacturer});
    if (injected == fault::FollowingError) raise(io, {fault::FollowingError, error_register::DeviceProfile});
    if (injected == fault::ReferenceLimit) raise(io, {fault::ReferenceLimit, error_register::DeviceProfile});

    // Following error (position loop): window 0xFFFFFFFF switches the monitoring off.
    const std::uint32_t window = p.following_error_window;
    const double timeout = p.following_error_timeout * 1e-3;
    const bool outside =
        axis_.loop == LoopMode::Position && window != 0xFFFFFFFFu && std::abs(axis_.following_error) > window;
    axis_.following_error_time.advance(outside, dt);
    if (outside && axis_.following_error_time.more_than(timeout))
        raise(io, {fault::FollowingError, error_register::DeviceProfile});
    // Limit switch with reaction "fault".
    if (p.limit_switch_reaction == 1 && sm_.drive_enabled() && mode_ != Mode::Homing &&
        (axis_.negative_limit || axis_.positive_limit))
        raise(io, {fault::ReferenceLimit, error_register::DeviceProfile});
    // TWINsync errors become faults in state Control (TWINsync chapter 7).
    if (const auto e = io.twinsync.pending_error;
        e && sm_.state() == State::OperationEnabled && active_fault_ == 0)
        raise(io, coupling_.raise(*e));
}

void DriveCore::run_state_machine(DriveIo& io) {
    const State before = sm_.state();
    // The fault is present while its cause lasts; a fault raised once (following error, limit switch)
    // counts until the state machine reached FAULT, so that a fault reset clears it then.
    const bool fault_present =
        active_fault_ != 0 &&
        (io.parameters.simulated_fault != 0 || mech_.overcurrent() || !mech_.encoder_ok() ||
         coupling_.error_present(io.twinsync) || sm_.state() != State::Fault);
    // A stop ramp ends at rest. Without an encoder (fault 0x7305) the drive can neither brake under control
    // (its position and velocity loops read a frozen encoder and would drive the motor away) nor tell
    // that the axis stands: the ramp ends at once, so the fault reaction ends in FAULT (transition 14)
    // with the power stage disabled and the motor coasting, as 0x605E = 0 "disable drive function, motor
    // free to rotate" (CiA 402 6.2; the HIWIN guide, chapter 6: in FAULT "the drive has de-magnetized the
    // motor"). src/cia402/README.md, "Fault reaction without an encoder".
    const bool at_rest = !mech_.encoder_ok() || (std::abs(axis_.velocity) <= axis_.standstill_velocity &&
                                                 (axis_.loop != LoopMode::Position || axis_.profile.done()));
    sm_.update(axis_.controlword, fault_present, at_rest, io.parameters.options);
    const State now = sm_.state();
    if (now != before) {
        if (before == State::Fault && now == State::SwitchOnDisabled) {
            active_fault_ = 0;
            // The reset re-initialises the encoder evaluation: the actual values are measured again.
            if (mech_.encoder_ok()) encoder_valid_ = true;
            coupling_.clear_error();
            io.feedback.cleared = true;
        }
        if (now == State::OperationEnabled) {
            apply_gains(io.parameters);
            on_mode_change();
        }
    }
    // A stop of the state machine (transitions 5/8 with a slow-down, quick stop, fault reaction) that
    // ended leaves no ramp behind. A halt ramp (controlword bit 8) is the mode's: the mode ends it when the
    // halt is released and goes on with its motion (CiA 402 6.5.3, HIWIN guide 9.1.1).
    if (sm_.stop() == StopKind::None && state_machine_stopped_) {
        axis_.stopping = StopKind::None;
        state_machine_stopped_ = false;
    }
}

void DriveCore::apply_gains(const DriveParameters& c) {
    // 0x2003: a non-zero entry replaces the gain tuned from the motor parameters.
    ControlGains g = Mechanics::tuned_for(mech_.parameters());
    auto u = [](std::uint32_t v) { return static_cast<double>(v); };
    if (u(c.gain_position_kp) > 0) g.position_kp = u(c.gain_position_kp) * 0.01;
    if (u(c.gain_velocity_kp) > 0) g.velocity_kp = u(c.gain_velocity_kp) * 1e-6;
    if (u(c.gain_velocity_ti) > 0) g.velocity_ti = u(c.gain_velocity_ti) * 1e-6;
    if (u(c.gain_current_bandwidth) > 0) g.current_bandwidth = u(c.gain_current_bandwidth);
    mech_.set_gains(g);
}

void DriveCore::select_mode(const DriveCommand& c) {
    // Modes of operation: a supported mode takes effect at once; 0x6061 shows it.
    const auto requested = static_cast<Mode>(c.mode);
    if (requested == mode_ || !supported(requested)) return;
    mode_ = requested;
    switch (mode_) {
        case Mode::ProfilePosition:
            active_ = &pp_;
            break;
        case Mode::ProfileVelocity:
            active_ = &pv_;
            break;
        case Mode::ProfileTorque:
            active_ = &pt_;
            break;
        case Mode::Homing:
            active_ = &hm_;
            break;
        case Mode::CyclicPosition:
            active_ = &csp_;
            break;
        case Mode::CyclicVelocity:
            active_ = &csv_;
            break;
        case Mode::CyclicTorque:
            active_ = &cst_;
            break;
        default:
            active_ = nullptr;
            break;
    }
    on_mode_change();
}

void DriveCore::on_mode_change() {
    // A new mode starts from where the axis is.
    coupling_.end_motion();
    axis_.profile.reset({axis_.actual, axis_.velocity, 0.0});
    axis_.demand = {axis_.actual, axis_.velocity, 0.0};
    axis_.torque_cmd = 0;
    for (OperationMode* m : modes_)
        m->reset();
}

void DriveCore::hold_disabled() {
    // No torque: the demand follows the actual position, so enabling starts without a jump.
    axis_.loop = LoopMode::Off;
    axis_.demand = {axis_.actual, axis_.velocity, 0.0};
    axis_.profile.reset(axis_.demand);
    axis_.velocity_cmd = 0;
    axis_.torque_cmd = 0;
    axis_.torque_ff = 0;
    axis_.stopping = StopKind::None;  // no ramp runs without torque
    // Once is enough: only a mode's step gives it something to drop again.
    if (!modes_disabled_) {
        for (OperationMode* m : modes_)
            m->disable();
        modes_disabled_ = true;
    }
}

void DriveCore::run_stop(StopKind k, double dt) {
    if (k == StopKind::Coast)
        hold_disabled();
    else
        axis_.stop(k, dt);
}

void DriveCore::run_setpoints(DriveIo& io, double dt) {
    axis_.internal_limit = false;
    const bool follow = coupling_.update(axis_, io.twinsync, sm_.following_setpoints());
    if (!sm_.drive_enabled()) {
        hold_disabled();
        coupling_.release(axis_);
    } else if (sm_.stop() != StopKind::None) {
        run_stop(sm_.stop(), dt);
        state_machine_stopped_ = true;
        coupling_.release(axis_);
    } else if (follow) {
        coupling_.follow(axis_, io.twinsync, dt);
    } else if (coupling_.continuing()) {
        if (!coupling_.continue_motion(axis_, dt)) {
            on_mode_change();
            run_mode(dt);
        }
    } else {
        run_mode(dt);
    }
}

void DriveCore::run_mode(double dt) {
    axis_.halted = (axis_.controlword & cw::Halt) && (!active_ || active_->obeys_halt());
    if (active_) {
        modes_disabled_ = false;
        active_->step(axis_, dt);
    } else {
        // No mode selected yet: hold the position.
        axis_.loop = LoopMode::Position;
        axis_.demand.v = axis_.demand.a = 0;
    }
}

void DriveCore::run_mechanics(const DriveIo& io, double dt) {
    const DriveParameters& p = io.parameters;
    const double nm = axis_.nm_per_permille;
    const double torque_limit_pos = std::min(p.max_torque, p.positive_torque_limit) * nm;
    const double torque_limit_neg = std::min(p.max_torque, p.negative_torque_limit) * nm;
    mech_.set_torque_limits(torque_limit_pos, torque_limit_neg);
    mech_.set_load_torque(io.parameters.load_torque * nm);
    const Kinematics& d = axis_.demand;
    switch (axis_.loop) {
        case LoopMode::Off:
            mech_.command(LoopMode::Off, 0, 0, 0);
            break;
        case LoopMode::Position:
            mech_.command(LoopMode::Position, user_to_rad(d.p), axis_.user_velocity_to_rad(d.v),
                          axis_.inertia * axis_.user_velocity_to_rad(d.a) + axis_.torque_ff * nm);
            break;
        case LoopMode::Velocity:
            mech_.command(LoopMode::Velocity, 0, axis_.user_velocity_to_rad(axis_.velocity_cmd),
                          axis_.torque_ff * nm);
            break;
        case LoopMode::Torque:
            mech_.command(LoopMode::Torque, 0, 0, axis_.torque_cmd * nm);
            break;
    }
    mech_.step(dt);
    // The drive knows the motion only through its encoder. Lost (fault 0x7305), it cannot know it: the
    // position actual values (0x6063/0x6064) stay at the last measured one and the velocity actual value
    // (0x606C) reads 0, until a fault reset once the encoder is back (README, "Fault reaction without an
    // encoder"). The simulated motor goes on moving (mechanics()); the limit switches are wired to the
    // machine and still see it.
    if (!mech_.encoder_ok()) encoder_valid_ = false;
    if (encoder_valid_) {
        const double machine_inc = machine_increments();
        previous_machine_inc_ = machine_inc;
        increments_ = floor64(machine_inc);
        axis_.actual = static_cast<double>(axis_.ratios.increments_to_user(increments_)) + axis_.home_shift;
        axis_.velocity = axis_.ratios.radians_to_user(mech_.velocity());
    } else {
        axis_.velocity = 0;
    }
    if (axis_.loop != LoopMode::Position)
        axis_.demand = {axis_.actual, axis_.loop == LoopMode::Velocity ? axis_.velocity_cmd : axis_.velocity,
                        0.0};
    axis_.following_error = axis_.loop == LoopMode::Position ? axis_.demand.p - axis_.actual : 0.0;
}

void DriveCore::run_touch_probe(DriveIo& io, double previous_inc, double machine_inc) {
    TouchProbe::Period p;
    p.function = io.command.probe_function;
    p.inputs = probe_inputs_;
    p.previous_inc = previous_inc;
    p.machine_inc = machine_inc;
    p.index_offset = io.parameters.index_pulse_offset;
    p.on_index_only = io.parameters.strategy.probe_on_index;
    io.feedback.probe_latched = probe_.step(p, axis_.ratios, axis_.home_shift);
    // The index pulse itself (HIWIN 0x2020/0x2021): where the last one was crossed, as 0x6064 reads it.
    if (const auto at = TouchProbe::index_crossing(previous_inc, machine_inc, axis_.ratios.per_revolution,
                                                   p.index_offset)) {
        const double user =
            static_cast<double>(axis_.ratios.increments_to_user(floor64(*at))) + axis_.home_shift;
        io.feedback.index_touched = true;
        io.feedback.index_position = wrap32(floor64(user));
    }
    io.feedback.probe_status = probe_.status();
    io.feedback.probe = true;
}

// Drive temperature: 35 C plus a rise with the square of the current.
void DriveCore::heat(const DriveParameters& p, double dt) {
    const double rated_a = std::max<double>(p.rated_current, 1.0) * 1e-3;
    const double i_rel = mech_.current() / rated_a;
    temperature_ += (350.0 + 300.0 * i_rel * i_rel - temperature_) * dt / 60.0;
}

void DriveCore::write_feedback(DriveIo& io, bool publish) {
    const DriveParameters& p = io.parameters;
    DriveFeedback& fb = io.feedback;
    const double dt = static_cast<double>(period_ns_) * 1e-9;
    std::uint16_t status = sm_.statusword_bits() | sw::Remote;
    const State st = sm_.state();
    const bool enabled = st == State::OperationEnabled && sm_.stop() == StopKind::None;

    // Target reached (bit 10) and the mode-specific bits 12/13 (CiA 402 6.3.3).
    StatusInputs in;
    in.dt = dt;
    in.standing = std::abs(axis_.velocity) <= axis_.standstill_velocity;
    speed_zero_.advance(in.standing, dt);
    in.speed_zero = &speed_zero_;
    const std::uint32_t fe_window = p.following_error_window;
    in.following_error = fe_window != 0xFFFFFFFFu && std::abs(axis_.following_error) > fe_window &&
                         axis_.following_error_time.more_than(p.following_error_timeout * 1e-3);
    ModeStatus ms;
    if (enabled) {
        if (active_) ms = active_->status(axis_, in);
    } else if (st == State::QuickStopActive) {
        ms.target_reached = in.standing;  // the quick stop has ended
    }
    // The homing bits stay visible outside OPERATION ENABLED.
    if (mode_ == Mode::Homing && !enabled) ms = hm_.status(axis_, in);
    if (ms.target_reached) status |= sw::TargetReached;
    if (ms.bit12) status |= sw::Bit12;
    if (ms.bit13) status |= sw::Bit13;
    // HIWIN 9.4: "accuracy compensation initiated" after homing (bit 15, manufacturer specific).
    if (mode_ == Mode::Homing && hm_.compensated()) status |= kAccuracyCompensation;
    heat(p, dt);
    if (!publish) return;
    const double rated_a = std::max<double>(p.rated_current, 1.0) * 1e-3;
    const bool limit_switch = axis_.positive_limit || axis_.negative_limit;
    if (axis_.internal_limit || limit_switch) status |= sw::InternalLimit;
    if (limit_switch || (enabled && mech_.torque_limited())) status |= sw::Warning;

    const Kinematics& d = axis_.demand;
    fb.statusword = status;
    fb.mode_display = static_cast<std::int8_t>(mode_);
    // A modulo axis (0x607B) shows its positions in the range; it moves on the continuous axis.
    fb.position_demand =
        axis_.modulo() ? wrap32(axis_.wrap_position(floor64(round_half_away(d.p)))) : sat32(d.p);
    fb.position_demand_internal = wrap32(
        axis_.ratios.user_to_increments(static_cast<std::int64_t>(round_half_away(d.p - axis_.home_shift))));
    fb.position_internal = wrap32(increments_);
    fb.position_actual = wrap32(axis_.wrap_position(floor64(axis_.actual)));
    fb.following_error = sat32(axis_.following_error);
    fb.velocity_demand = sat32(axis_.loop == LoopMode::Velocity ? axis_.velocity_cmd : d.v);
    fb.velocity_actual = sat32(axis_.velocity);
    const double per = axis_.nm_per_permille;
    fb.torque_demand = sat16(axis_.loop == LoopMode::Torque ? axis_.torque_cmd : mech_.torque() / per);
    fb.torque_actual = sat16(mech_.torque() / per);
    fb.current_actual = sat16(mech_.current() / rated_a * 1000.0);
    fb.temperature = sat16(temperature_);
}

}  // namespace vecat::cia402
