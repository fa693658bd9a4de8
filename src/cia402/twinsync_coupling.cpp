#include "cia402/twinsync_coupling.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "protocol/coe.hpp"
#include "twinsync/mapping.hpp"
#include "twinsync/parameters.hpp"
#include "twinsync/telegram.hpp"

namespace vecat::cia402 {

namespace cw = protocol::cia402::cw;
namespace error_register = protocol::error_register;
using twinsync::Follow;
using twinsync::Setting;

namespace {

// The MSD display numbers the DriveCom states from 1 in the order of CiA 402's (0 is its start-up).
twinsync::DriveComState drivecom_state(State s) {
    static_assert(static_cast<int>(State::NotReadyToSwitchOn) + 1 ==
                      static_cast<int>(twinsync::DriveComState::NotReadyToSwitchOn) &&
                  static_cast<int>(State::OperationEnabled) + 1 ==
                      static_cast<int>(twinsync::DriveComState::OperationEnabled) &&
                  static_cast<int>(State::Fault) + 1 == static_cast<int>(twinsync::DriveComState::Fault));
    return static_cast<twinsync::DriveComState>(static_cast<std::uint8_t>(s) + 1);
}

double rpm_of_rad(double rad_per_s) {
    return rad_per_s * 60.0 / (2.0 * std::numbers::pi);
}

// A value as a 16-bit fraction of its reference (section 4.1.6: -reference..+reference = -32768..32767).
std::int16_t scaled16(double value, double reference) {
    if (!(reference > 0)) return 0;
    return static_cast<std::int16_t>(
        std::clamp(std::llround(value / reference * 32768.0), -32768ll, 32767ll));
}

}  // namespace

std::uint16_t TwinsyncCoupling::controlword(std::uint16_t own, const TwinsyncInputs& t, State state) {
    previous_control_ = control_;
    control_ = t.received_control_word;
    std::uint16_t c = own;
    // A slave controlled through TWINsync obeys the master drive's control word (P2611) instead of 0x6040.
    if (t.controlled_by_twinsync && t.has_data) c = twinsync::cia402_from_control_word(control_);
    // A master drive switches on its control once its slave is in state Control (unless P2651 bit 2).
    if (t.active && t.role == twinsync::Role::Master && t.link_ok &&
        t.partner_role == twinsync::Role::Slave && !t.partner_enabled &&
        !(t.config & twinsync::kConfigNoSlaveStateCheck) && state != State::OperationEnabled)
        c = static_cast<std::uint16_t>(c & ~cw::EnableOperation);
    return c;
}

RaisedFault TwinsyncCoupling::raise(twinsync::ErrorId e) {
    // 0x603F (CiA 402 error code table): serial interface 2 for the link (40-xx) and the other axis
    // (39-02); the speed and torque monitoring of the gantry as velocity and torque control faults. The
    // emergency's manufacturer bytes carry the MSD error number and location.
    constexpr std::uint16_t kSerialInterface2 = 0x7520;
    constexpr std::uint16_t kVelocityControl = 0x8400;
    constexpr std::uint16_t kTorqueControl = 0x8300;
    RaisedFault f{kSerialInterface2,
                  static_cast<std::uint8_t>(error_register::Communication | error_register::Manufacturer),
                  {e.number, e.location, 0, 0, 0}};
    if (e == twinsync::error::SpeedDifference) {
        f.code = kVelocityControl;
        f.register_bits = error_register::Manufacturer;
    } else if (e == twinsync::error::TorqueDifference) {
        f.code = kTorqueControl;
        f.register_bits = error_register::Manufacturer;
    }
    error_ = e;
    return f;
}

bool TwinsyncCoupling::update(Axis& a, const TwinsyncInputs& t, bool following_setpoints) {
    const bool follow = t.follows && t.has_data;
    if (a.coupled && !follow) {
        // Decoupled: in motion, the axis goes on as if it were still coupled until it is stopped.
        a.coupled = false;
        if (following_setpoints && std::abs(a.demand.v) > a.standstill_velocity) {
            continuing_ = true;
            continue_halting_ = false;
            continue_velocity_ = a.demand.v;
            continue_target_position_ = a.cmd().target_position;
            continue_target_velocity_ = a.cmd().target_velocity;
        }
    }
    return follow;
}

void TwinsyncCoupling::hold_for_coupling(Axis& a) {
    a.loop = LoopMode::Position;
    a.demand.v = a.demand.a = 0;
    a.torque_ff = 0;
}

// REFPOS (6.2.10): "The homing is controlled via the master and is also synchronized with the slave. The
// synchronization of the slave with the position of the master is absolute." While the master homes (its
// control word P2611 carries StartHoming) the slave follows its motion; when the master's homing redefines
// its coordinates (the home position reads as its home offset), its position set-point P2600 jumps without
// a motion, and the slave takes the same reference: its own coordinates shift by the jump, so it does not
// move, reads the master's position from then on, and reports itself homed (P2612 HomePositionSet). The
// telegram carries no "homed" flag from the master (table 4.5), so the slave finds the jump in the set-point:
// the change of its increment between two consecutive telegrams, beyond what an acceleration of the
// slave's homing acceleration 0x609A (master and slave are parametrised alike, 4.1.6) explains, plus two
// units. A smaller re-referencing is followed as a motion.
void TwinsyncCoupling::take_master_reference(Axis& a, const TwinsyncInputs& t, double dt) {
    if (!t.fresh) {
        refpos_seen_ = 0;  // frozen data (4.1.2): start again from the next two telegrams
        return;
    }
    const std::int32_t rx = t.remote_ref_pos;
    if (refpos_seen_ == 0) {
        refpos_last_ = rx;
        refpos_seen_ = 1;
        return;
    }
    const std::int64_t step =
        static_cast<std::int32_t>(static_cast<std::uint32_t>(rx) - static_cast<std::uint32_t>(refpos_last_));
    refpos_last_ = rx;
    if (refpos_seen_ == 1) {
        refpos_step_ = step;
        refpos_seen_ = 2;
        return;
    }
    const double jump = static_cast<double>(step - refpos_step_);
    const double tolerance = 2.0 + 2.0 * std::max<double>(a.par().homing_acceleration, 1.0) * dt * dt;
    if ((control_ & twinsync::control::StartHoming) && std::abs(jump) > tolerance) {
        const double shift = (t.inverted < 0 ? -1.0 : 1.0) * jump;
        a.home_shift += shift;
        a.actual += shift;
        a.demand.p += shift;
        a.profile.reset(a.demand);
        homed_ = true;
        return;  // the master's motion goes on at the increment it had before the jump
    }
    refpos_step_ = step;
}

void TwinsyncCoupling::follow(Axis& a, const TwinsyncInputs& t, double dt) {
    const twinsync::ModeInfo* m = t.mode;
    Follow f = m->follow;
    if (f == Follow::ByControlMode) {
        const auto cm = t.control_mode;
        f = cm == 1 ? Follow::Torque : cm == 2 ? Follow::Speed : Follow::PositionAbsolute;
    }
    const bool user = m->follow == Follow::ByControlMode;
    const double inv = t.inverted < 0 ? -1.0 : 1.0;
    const double remote_speed_ref = static_cast<double>(t.remote_speed_reference);
    const double remote_torque_ref = static_cast<double>(t.remote_torque_reference);
    auto speed = [&](std::int16_t v) { return v / 32768.0 * remote_speed_ref; };    // rpm
    auto torque = [&](std::int16_t v) { return v / 32768.0 * remote_torque_ref; };  // Nm
    auto rpm_to_user = [&](double rpm) {
        return a.ratios.radians_to_user(rpm / 60.0 * 2.0 * std::numbers::pi);
    };
    const double still = a.standstill_velocity;
    // The master's speed arrives as a 16-bit fraction of P2609: standstill within two of its steps.
    const double still_remote = std::max(still, 2.0 * std::abs(rpm_to_user(remote_speed_ref / 32768.0)));
    a.torque_ff = 0;
    a.cyclic_following =
        true;  // statusword bit 12 of the cyclic modes: the drive follows (TWINsync's) command

    switch (f) {
        case Follow::PositionAbsolute: {
            // IP: the master's actual position; REFPOS and GANTRY (and USER/EXT_MAP): its set-point.
            const bool ip = m->setting == Setting::PconIpSlave;
            const double master = ip ? t.remote_act_pos : t.remote_ref_pos;
            const double ff_rpm = m->setting == Setting::PconGantrySlave
                                      ? static_cast<double>(t.act_speed_master)
                                      : speed(ip ? t.remote_act_speed : t.remote_ref_speed);
            const double v = inv * rpm_to_user(ff_rpm);
            if (!a.coupled) {
                // Coupling only at standstill of both axes.
                if (std::abs(v) > still_remote || std::abs(a.velocity) > still) return hold_for_coupling(a);
                a.coupled = true;
                refpos_seen_ = 0;
            }
            if (m->setting == Setting::PconRefposSlave) take_master_reference(a, t, dt);
            a.demand = {a.clamp_to_software_limits(inv * master), v, 0.0};
            a.loop = LoopMode::Position;
            if (m->setting == Setting::PconGantrySlave)
                a.torque_ff = inv * torque(t.remote_act_torque) / a.nm_per_permille;
            break;
        }
        case Follow::PositionDelta: {
            // PCON: increments of the master's actual position, corrected by the resolution factors
            // (P0270/P2652), geared (P2653/P2654), reversed by P2583, integrated onto the coupling position.
            // The coupling factor (TX1250 3.2.2) is the whole of it; it may change while coupled (the
            // gear is read every cycle: TX1250 3.3, the cyclic slave axis), smoothed by AccBound.
            const std::int32_t master = t.remote_act_pos;
            const double commanded =
                inv * static_cast<double>(t.local_resolution) / std::max<double>(t.remote_resolution, 1.0) *
                static_cast<double>(t.gear_numerator) / std::max<double>(t.gear_denominator, 1.0);
            const double master_speed = rpm_to_user(speed(t.remote_act_speed));
            if (!a.coupled) {
                if (std::abs(commanded * master_speed) > still_remote || std::abs(a.velocity) > still)
                    return hold_for_coupling(a);
                a.coupled = true;
                master_last_ = master;
                factor_ = commanded;  // the factor is set at coupling (3.2.2)
            }
            const auto delta = static_cast<std::int32_t>(static_cast<std::uint32_t>(master) -
                                                         static_cast<std::uint32_t>(master_last_));
            master_last_ = master;
            smooth_factor(commanded, delta, a.par().coupling_acc_bound, dt);
            const double k = factor_;
            const double v = k * master_speed;
            // slave = k x master + offset with the offset re-based at each change of k: the increments are
            // added with the factor of their period, so a new factor changes the slope, never the position.
            double p = a.demand.p + k * delta;
            // Re-synchronisation (P2611 bit 12, rising): the slave takes the master position itself.
            if ((control_ & twinsync::control::ReSyncPosition) &&
                !(previous_control_ & twinsync::control::ReSyncPosition))
                p = k * master;
            a.demand = {a.clamp_to_software_limits(p), v, 0.0};
            a.loop = LoopMode::Position;
            break;
        }
        case Follow::Speed:
        case Follow::SpeedTorquePrecontrol: {
            double rpm = inv * speed(user ? t.remote_ref_speed : t.remote_act_speed);
            if (m->setting == Setting::TwdSlaveV1) {
                // Speed-up: P2584 % of the main set-point, at least P2585, signed as the master's torque.
                const double master_torque = torque(t.remote_act_torque);
                double add = std::abs(rpm) * static_cast<double>(t.speed_up) / 100.0;
                add = std::max(add, static_cast<double>(t.speed_up_minimum));
                if (master_torque != 0) rpm += master_torque > 0 ? add : -add;
            }
            a.velocity_cmd = std::clamp(rpm_to_user(rpm), -a.max_velocity(), a.max_velocity());
            if (f == Follow::SpeedTorquePrecontrol)
                a.torque_ff = inv * torque(t.remote_act_torque) / a.nm_per_permille;
            a.loop = LoopMode::Velocity;
            a.demand = {a.actual, a.velocity_cmd, 0.0};
            a.coupled = true;
            break;
        }
        case Follow::Torque: {
            // VE (table 6.10): the master's torque set-point through P2581 MasterTorqueTF, a first-order
            // lag of that time constant (ms; 0 = none), starting from no torque when the slave couples.
            const double target = inv * torque(t.remote_ref_torque) / a.nm_per_permille;
            const double tf = static_cast<double>(t.master_torque_tf) * 1e-3;
            if (!a.coupled) torque_filtered_ = 0;
            if (tf > 0)
                torque_filtered_ += (target - torque_filtered_) * (1.0 - std::exp(-dt / tf));
            else
                torque_filtered_ = target;
            a.torque_cmd = torque_filtered_;
            a.loop = LoopMode::Torque;
            a.coupled = true;
            break;
        }
        case Follow::None:
        case Follow::ByControlMode:
            break;
    }
}

// TX1250 3.3: "the coupling factor arriving via the cyclic interface is therefore smoothed (= filtered).
// Smoothing is parameterized by limiting the amount of the slave axis acceleration" (AccBound, 0x2115).
// The slave moves k x delta in a period of dt in which the master moved delta increments, so a change dk
// of the factor changes its velocity by dk x delta / dt: the applied factor moves towards the commanded
// one by at most AccBound x dt^2 / |delta| per period (|delta| counted as at least one increment), which
// bounds that acceleration by AccBound. The master's own acceleration times the factor is the master's
// profile (3.3 asks for AccBound >= max |factor| x the master's acceleration for stability). 0: at once.
void TwinsyncCoupling::smooth_factor(double commanded, std::int32_t delta, std::uint32_t acc_bound,
                                     double dt) {
    if (acc_bound == 0) {
        factor_ = commanded;
        return;
    }
    const double moved = std::max(1.0, std::abs(static_cast<double>(delta)));
    const double step = static_cast<double>(acc_bound) * dt * dt / moved;
    factor_ += std::clamp(commanded - factor_, -step, step);
}

bool TwinsyncCoupling::continue_motion(Axis& a, double dt) {
    // A new set-point, a new target or a new mode ends the decoupled motion; halt stops it.
    if (a.rising(cw::NewSetpoint) || a.cmd().target_position != continue_target_position_ ||
        a.cmd().target_velocity != continue_target_velocity_) {
        continuing_ = false;
        return false;
    }
    a.loop = LoopMode::Position;
    a.torque_ff = 0;
    if (a.controlword & cw::Halt) {
        if (!continue_halting_) {
            a.profile.reset(a.demand);
            a.profile.stop(std::max<double>(a.par().profile_deceleration, 1.0), a.profile_limits().jerk);
            continue_halting_ = true;
        }
        a.demand = a.profile.step(dt);
        if (a.profile.done()) continuing_ = false;
        return true;
    }
    a.demand = {a.demand.p + continue_velocity_ * dt, continue_velocity_, 0.0};
    return true;
}

twinsync::LocalState TwinsyncCoupling::local(State state, StopKind stop, std::uint16_t controlword,
                                             bool homing_mode, bool synchronised, const Axis& a,
                                             const Mechanics& m) const {
    twinsync::LocalState l;
    l.state = drivecom_state(state);
    l.fault = state == State::Fault || state == State::FaultReactionActive;
    l.homed = homed_;
    l.transition = stop != StopKind::None;
    l.controlword = controlword;
    l.homing_mode = homing_mode;
    l.fieldbus_synchronised = synchronised;
    l.position = a.actual;
    l.speed_rpm = rpm_of_rad(m.velocity());
    l.torque_nm = m.torque();
    l.rated_torque_nm = a.nm_per_permille * 1000.0;
    return l;
}

TwinsyncValues TwinsyncCoupling::values(const Axis& a, const Mechanics& m, double machine_increments,
                                        std::uint16_t active_fault, const TwinsyncInputs& t) const {
    TwinsyncValues v;
    const double torque_ref = static_cast<double>(t.local_torque_reference);
    const double speed_ref = static_cast<double>(t.local_speed_reference);
    const double act_rpm = rpm_of_rad(m.velocity());
    const double demand_v = a.loop == LoopMode::Velocity ? a.velocity_cmd : a.demand.v;
    const double ref_rpm = rpm_of_rad(a.user_velocity_to_rad(demand_v));
    const double ref_torque = a.loop == LoopMode::Torque ? a.torque_cmd * a.nm_per_permille : m.torque();
    v.ref_torque = scaled16(ref_torque, torque_ref);
    v.act_torque = scaled16(m.torque(), torque_ref);
    v.ref_speed = scaled16(ref_rpm, speed_ref);
    v.act_speed = scaled16(act_rpm, speed_ref);
    v.speed_actual_rpm = static_cast<float>(act_rpm);
    v.speed_setpoint_rpm = static_cast<float>(ref_rpm);
    v.ref_pos = wrap32(static_cast<std::int64_t>(std::llround(a.demand.p)));
    v.act_pos = wrap32(static_cast<std::int64_t>(std::floor(a.actual)));
    // Single-turn angle of the motor, 16 bit (the virtual encoder's raw value).
    const double per_rev = a.ratios.per_revolution;
    const double turn = std::fmod(machine_increments, per_rev) / per_rev;
    v.eps = static_cast<std::uint16_t>(std::llround((turn < 0 ? turn + 1.0 : turn) * 65536.0) & 0xFFFF);
    // P2650: the drive's own current error (the adapter leaves it when the receive mapping brings the
    // slave's).
    if (error_) {
        v.error_number = error_->number;
        v.error_location = error_->location;
    } else if (active_fault != 0) {
        v.error_number = static_cast<std::uint16_t>(active_fault >> 8);
        v.error_location = static_cast<std::uint16_t>(active_fault & 0xFF);
    }
    return v;
}

}  // namespace vecat::cia402
