// The CiA 402 drive (about 1,400 lines): still the god file that issue 24 asks to split into a DriveCore,
// one class per operation mode, the TWINsync coupling and a thin CoE adapter (started on branch `drive`).
#include "cia402/drive.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include "cia402/homing.hpp"
#include "cia402/touch_probe.hpp"
#include "device/drive_objects.hpp"
#include "protocol/cia402_objects.hpp"

namespace vecat::cia402 {

bool supported(Mode m) noexcept {
    switch (m) {
        case Mode::ProfilePosition:
        case Mode::ProfileVelocity:
        case Mode::ProfileTorque:
        case Mode::Homing:
        case Mode::CyclicPosition:
        case Mode::CyclicVelocity:
        case Mode::CyclicTorque:
            return true;
        default:
            return false;
    }
}

bool fault::injectable(std::uint16_t code) noexcept {
    return code == OverCurrent || code == Encoder || code == FollowingError || code == ReferenceLimit;
}

namespace {

using coe::Entry;
namespace obj = protocol::obj;
namespace mfr = device::mfr;

std::int32_t wrap32(std::int64_t v) {
    return static_cast<std::int32_t>(static_cast<std::uint32_t>(static_cast<std::uint64_t>(v)));
}

// floor() as a 64-bit integer, saturated: with absurd parameters the simulated machine can run away past
// the 64-bit range, and converting such a double is undefined (found by the random-values test under UBSan).
std::int64_t floor64(double v) {
    if (!(v == v)) return 0;
    return static_cast<std::int64_t>(std::floor(std::clamp(v, -9.2e18, 9.2e18)));
}

// std::lround for |v| < 2^52 without the library call (several per servo step): halves away from zero.
// v - trunc(v) is exact, so the result is the same.
double round_half_away(double v) {
    double r = std::trunc(v);
    const double frac = v - r;
    if (frac >= 0.5)
        r += 1.0;
    else if (frac <= -0.5)
        r -= 1.0;
    return r;
}

std::int32_t sat32(double v) {
    if (!(v == v)) return 0;
    v = std::clamp(v, -2147483648.0, 2147483647.0);
    return static_cast<std::int32_t>(round_half_away(v));
}

std::int16_t sat16(double v) {
    if (!(v == v)) return 0;
    return static_cast<std::int16_t>(round_half_away(std::clamp(v, -32768.0, 32767.0)));
}

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

// Controlword bits of the modes (protocol/cia402.hpp).
namespace cw = protocol::cia402::cw;
constexpr std::uint16_t kNewSetpoint = cw::NewSetpoint;
constexpr std::uint16_t kChangeImmediately = cw::ChangeSetImmediately;
constexpr std::uint16_t kRelative = cw::Relative;
constexpr std::uint16_t kHalt = cw::Halt;
constexpr std::uint16_t kChangeOnSetpoint = cw::ChangeOnSetpoint;
constexpr std::uint16_t kHomingStart = cw::HomingStart;

}  // namespace

// The dictionary entries the drive reads and writes, bound once by name (protocol/cia402_objects.hpp,
// device/drive_objects.hpp) as typed handles: an entry of another type than the catalogue's refuses to
// bind. A missing object (a vendor ESI without it) reads as its fallback and is not written.
struct Drive::Objects {
    template <class T>
    using V = coe::Value<T>;
    explicit Objects(coe::ObjectDictionary& d) : od(d) {}
    // The drive also runs on vendors' dictionaries (ESI files), some of which declare a profile object
    // with another integer type (DINT digital inputs, USINT for a UDINT): such an entry is converted as
    // Entry::get/set do (coe::Match::Convert). Reals and strings must match.
    template <protocol::DataType T>
    V<protocol::value_type_t<T>> bind(protocol::ObjectId<T> id) {
        return coe::bind(od, id, coe::Match::Convert);
    }

    coe::ObjectDictionary& od;
    V<std::uint16_t> controlword = bind(obj::controlword);
    V<std::uint16_t> statusword = bind(obj::statusword);
    V<std::int16_t> quick_stop_option = bind(obj::quick_stop_option_code);
    V<std::int16_t> shutdown_option = bind(obj::shutdown_option_code);
    V<std::int16_t> disable_operation_option = bind(obj::disable_operation_option_code);
    V<std::int16_t> halt_option = bind(obj::halt_option_code);
    V<std::int16_t> fault_reaction_option = bind(obj::fault_reaction_option_code);
    V<std::int8_t> modes = bind(obj::modes_of_operation);
    V<std::int8_t> modes_display = bind(obj::modes_of_operation_display);
    V<std::int32_t> position_demand = bind(obj::position_demand_value);
    V<std::int32_t> position_internal = bind(obj::position_actual_internal_value);
    V<std::int32_t> position_actual = bind(obj::position_actual_value);
    V<std::uint32_t> following_error_window = bind(obj::following_error_window);
    V<std::uint16_t> following_error_timeout = bind(obj::following_error_time_out);
    V<std::uint32_t> position_window = bind(obj::position_window);
    V<std::uint16_t> position_window_time = bind(obj::position_window_time);
    V<std::int32_t> velocity_demand = bind(obj::velocity_demand_value);
    V<std::int32_t> velocity_actual = bind(obj::velocity_actual_value);
    V<std::uint16_t> velocity_window = bind(obj::velocity_window);
    V<std::uint16_t> velocity_window_time = bind(obj::velocity_window_time);
    V<std::uint16_t> velocity_threshold = bind(obj::velocity_threshold);
    V<std::uint16_t> velocity_threshold_time = bind(obj::velocity_threshold_time);
    V<std::int16_t> target_torque = bind(obj::target_torque);
    V<std::uint16_t> max_torque = bind(obj::max_torque);
    V<std::int16_t> torque_demand = bind(obj::torque_demand);
    V<std::uint32_t> rated_current = bind(obj::motor_rated_current);
    V<std::uint32_t> rated_torque = bind(obj::motor_rated_torque);
    V<std::int16_t> torque_actual = bind(obj::torque_actual_value);
    V<std::int16_t> current_actual = bind(obj::current_actual_value);
    V<std::int32_t> target_position = bind(obj::target_position);
    V<std::int32_t> home_offset = bind(obj::home_offset);
    V<std::int32_t> software_limit_min = bind(obj::software_position_limit::min);
    V<std::int32_t> software_limit_max = bind(obj::software_position_limit::max);
    V<std::uint32_t> max_profile_velocity = bind(obj::max_profile_velocity);
    V<std::uint32_t> max_motor_speed = bind(obj::max_motor_speed);
    V<std::uint32_t> profile_velocity = bind(obj::profile_velocity);
    V<std::uint32_t> profile_acceleration = bind(obj::profile_acceleration);
    V<std::uint32_t> profile_deceleration = bind(obj::profile_deceleration);
    V<std::uint32_t> quick_stop_deceleration = bind(obj::quick_stop_deceleration);
    V<std::int16_t> motion_profile_type = bind(obj::motion_profile_type);
    V<std::uint32_t> torque_slope = bind(obj::torque_slope);
    V<std::uint32_t> encoder_increments = bind(obj::position_encoder_resolution::encoder_increments);
    V<std::uint32_t> encoder_revolutions = bind(obj::position_encoder_resolution::motor_revolutions);
    V<std::uint32_t> gear_motor = bind(obj::gear_ratio::motor_revolutions);
    V<std::uint32_t> gear_shaft = bind(obj::gear_ratio::shaft_revolutions);
    V<std::uint32_t> feed = bind(obj::feed_constant::feed);
    V<std::uint32_t> feed_shaft = bind(obj::feed_constant::shaft_revolutions);
    V<std::int8_t> homing_method = bind(obj::homing_method);
    V<std::uint32_t> homing_speed_switch = bind(obj::homing_speeds::search_for_switch);
    V<std::uint32_t> homing_speed_zero = bind(obj::homing_speeds::search_for_zero);
    V<std::uint32_t> homing_acceleration = bind(obj::homing_acceleration);
    V<std::uint32_t> profile_jerk = bind(obj::profile_jerk::jerk_1);
    V<std::int32_t> position_offset = bind(obj::position_offset);
    V<std::int32_t> velocity_offset = bind(obj::velocity_offset);
    V<std::int16_t> torque_offset = bind(obj::torque_offset);
    V<std::uint16_t> probe_function = bind(obj::touch_probe_function);
    V<std::uint16_t> probe_status = bind(obj::touch_probe_status);
    V<std::int32_t> probe1_positive = bind(obj::touch_probe_1_positive_value);
    V<std::int32_t> probe1_negative = bind(obj::touch_probe_1_negative_value);
    V<std::int32_t> probe2_positive = bind(obj::touch_probe_2_positive_value);
    V<std::int32_t> probe2_negative = bind(obj::touch_probe_2_negative_value);
    V<std::uint8_t> interpolation_value = bind(obj::interpolation_time_period::value);
    V<std::int8_t> interpolation_index = bind(obj::interpolation_time_period::time_index);
    V<std::uint32_t> max_acceleration = bind(obj::max_acceleration);
    V<std::uint32_t> max_deceleration = bind(obj::max_deceleration);
    V<std::uint16_t> positive_torque_limit = bind(obj::positive_torque_limit_value);
    V<std::uint16_t> negative_torque_limit = bind(obj::negative_torque_limit_value);
    V<std::int32_t> following_error_actual = bind(obj::following_error_actual_value);
    V<std::int32_t> position_demand_internal = bind(obj::position_demand_internal_value);
    V<std::uint32_t> digital_inputs = bind(obj::digital_inputs);
    V<std::int32_t> target_velocity = bind(obj::target_velocity);
    // The manufacturer objects of the vecat drive.
    V<std::int16_t> temperature = bind(mfr::drive_temperature);
    V<std::uint16_t> simulated_fault = bind(mfr::simulated_fault);
    V<std::uint32_t> velocity_override = bind(mfr::velocity_override);
    V<std::int32_t> compensation_distance = bind(mfr::position_compensation::distance);
    V<std::uint32_t> compensation_length = bind(mfr::position_compensation::length);
    V<std::uint8_t> compensation_start = bind(mfr::position_compensation::start);
    V<std::uint32_t> motor_rotor_inertia = bind(mfr::motor::rotor_inertia);
    V<std::uint32_t> motor_torque_constant = bind(mfr::motor::torque_constant);
    V<std::uint32_t> motor_load_inertia = bind(mfr::motor::load_inertia);
    V<std::uint32_t> motor_viscous_friction = bind(mfr::motor::viscous_friction);
    V<std::uint32_t> motor_coulomb_friction = bind(mfr::motor::coulomb_friction);
    V<std::uint32_t> motor_peak_current = bind(mfr::motor::peak_current);
    V<std::uint32_t> gain_position_kp = bind(mfr::gains::position_kp);
    V<std::uint32_t> gain_velocity_kp = bind(mfr::gains::velocity_kp);
    V<std::uint32_t> gain_velocity_ti = bind(mfr::gains::velocity_ti);
    V<std::uint32_t> gain_current_bandwidth = bind(mfr::gains::current_bandwidth);
    V<std::int32_t> negative_limit_switch = bind(mfr::machine::negative_limit_switch);
    V<std::int32_t> positive_limit_switch = bind(mfr::machine::positive_limit_switch);
    V<std::int32_t> home_switch = bind(mfr::machine::home_switch);
    V<std::int32_t> index_pulse_offset = bind(mfr::machine::index_pulse_offset);
    V<std::int16_t> load_torque = bind(mfr::machine::load_torque);
    V<std::uint8_t> probe_inputs = bind(mfr::machine::touch_probe_inputs);
    V<std::uint8_t> limit_switch_reaction = bind(mfr::machine::limit_switch_reaction);
    // TWINsync: the local values the drive provides and the remote values it uses (MSD parameters
    // Pnnnn as objects 0x2000 + nnnn, twinsync/parameters.hpp).
    template <class T>
    V<T> tw(std::uint16_t parameter, std::uint8_t sub = 0) {
        return coe::bind<T>(od, twinsync::object_index(parameter), sub, coe::Match::Convert);
    }
    V<std::uint16_t> tw_control_mode = tw<std::uint16_t>(twinsync::p::ControlMode);
    V<std::uint32_t> tw_config = tw<std::uint32_t>(twinsync::p::Config);
    V<std::int16_t> tw_inverted = tw<std::int16_t>(twinsync::p::SlaveInverted);
    V<float> tw_speed_up = tw<float>(twinsync::p::SpeedUp);
    V<float> tw_speed_up_min = tw<float>(twinsync::p::SpeedUpMinimum);
    V<float> tw_act_speed_master = tw<float>(twinsync::p::ActSpeedMaster);
    V<std::int16_t> tw_local_ref_torque = tw<std::int16_t>(twinsync::p::LocalRefTorque);
    V<std::int16_t> tw_local_act_torque = tw<std::int16_t>(twinsync::p::LocalActTorque);
    V<std::int16_t> tw_local_ref_speed = tw<std::int16_t>(twinsync::p::LocalRefSpeed);
    V<std::int16_t> tw_local_act_speed = tw<std::int16_t>(twinsync::p::LocalActSpeed);
    V<std::int32_t> tw_local_ref_pos = tw<std::int32_t>(twinsync::p::LocalRefPos);
    V<std::int32_t> tw_local_act_pos = tw<std::int32_t>(twinsync::p::LocalActPos);
    V<float> tw_local_torque_ref = tw<float>(twinsync::p::LocalScaling, 1);
    V<float> tw_local_speed_ref = tw<float>(twinsync::p::LocalScaling, 2);
    V<std::int16_t> tw_remote_ref_torque = tw<std::int16_t>(twinsync::p::RemoteRefTorque);
    V<std::int16_t> tw_remote_act_torque = tw<std::int16_t>(twinsync::p::RemoteActTorque);
    V<std::int16_t> tw_remote_ref_speed = tw<std::int16_t>(twinsync::p::RemoteRefSpeed);
    V<std::int16_t> tw_remote_act_speed = tw<std::int16_t>(twinsync::p::RemoteActSpeed);
    V<std::int32_t> tw_remote_ref_pos = tw<std::int32_t>(twinsync::p::RemoteRefPos);
    V<std::int32_t> tw_remote_act_pos = tw<std::int32_t>(twinsync::p::RemoteActPos);
    V<float> tw_remote_torque_ref = tw<float>(twinsync::p::RemoteScaling, 1);
    V<float> tw_remote_speed_ref = tw<float>(twinsync::p::RemoteScaling, 2);
    V<std::uint32_t> tw_local_resolution = tw<std::uint32_t>(twinsync::p::LocalResolution);
    V<std::uint32_t> tw_remote_resolution = tw<std::uint32_t>(twinsync::p::RemoteResolution);
    V<std::int32_t> tw_gear_numerator = tw<std::int32_t>(twinsync::p::GearNumerator);
    V<std::int32_t> tw_gear_denominator = tw<std::int32_t>(twinsync::p::GearDenominator);
    V<float> tw_speed_actual_rpm = tw<float>(twinsync::p::SpeedActualRpm);
    V<float> tw_speed_setpoint_rpm = tw<float>(twinsync::p::SpeedSetpointRpm);
    V<std::int32_t> tw_position_actual = tw<std::int32_t>(twinsync::p::PositionActual);
    V<std::int16_t> tw_torque_actual_scaled = tw<std::int16_t>(twinsync::p::TorqueActualScaled);
    V<std::int16_t> tw_local_ff_speed = tw<std::int16_t>(twinsync::p::LocalRefFFSpeed);
    V<std::uint16_t> tw_local_eps = tw<std::uint16_t>(twinsync::p::LocalActEps);
    V<std::uint16_t> tw_error_number = tw<std::uint16_t>(twinsync::p::CurrentError, 1);
    V<std::uint16_t> tw_error_location = tw<std::uint16_t>(twinsync::p::CurrentError, 2);
};

namespace {

MotorParameters motor_from(const Drive::Objects& o) {
    MotorParameters p;
    // A parameter of 0 (or a missing object) keeps the model's default where 0 would be meaningless.
    auto u = [](const coe::Value<std::uint32_t>& v, double scale, double fallback) {
        const double x = static_cast<double>(v.get_or(0)) * scale;
        return x > 0 ? x : fallback;
    };
    auto any = [](const coe::Value<std::uint32_t>& v, double scale, double fallback) {
        return v.bound() ? static_cast<double>(v.get()) * scale : fallback;
    };
    p.rotor_inertia = u(o.motor_rotor_inertia, 1e-7, p.rotor_inertia);
    p.torque_constant = u(o.motor_torque_constant, 1e-3, p.torque_constant);
    p.load_inertia = any(o.motor_load_inertia, 1e-7, p.load_inertia);
    p.viscous_friction = any(o.motor_viscous_friction, 1e-6, p.viscous_friction);
    p.coulomb_friction = any(o.motor_coulomb_friction, 1e-3, p.coulomb_friction);
    p.peak_current = u(o.motor_peak_current, 1e-3, p.peak_current);
    if (o.rated_current.get_or(0) > 0) p.rated_current = o.rated_current.get() * 1e-3;
    return p;
}

}  // namespace

Drive::Drive(const device::DeviceDescription& d,
             std::shared_ptr<const std::vector<device::ObjectDescription>> objects)
    : CoeApplication(d, std::move(objects)), o_(std::make_unique<Objects>(dictionary())) {
    read_configuration();
    const MotorParameters mp = motor_from(*o_);
    mech_ = std::make_unique<Mechanics>(mp, ControlGains{});
    inertia_ = mp.rotor_inertia + mp.load_inertia;
    homing_ = std::make_unique<Homing>();
    twin_ = std::make_unique<twinsync::Port>(dictionary(), kServoPeriodNs);
    // Fault injection is refused for codes the drive does not simulate.
    if (o_->simulated_fault.bound())
        o_->simulated_fault.entry()->hooks().on_download = [](const Entry&, ConstBytes v) {
            const std::uint16_t code = v.size() >= 2 ? ld_le16(v.data()) : 0;
            return (code == 0 || fault::injectable(code)) ? protocol::SdoAbort::None
                                                          : protocol::SdoAbort::ValueRange;
        };
    if (o_->compensation_start.bound())
        o_->compensation_start.entry()->hooks().after_download = [this](Entry& e) {
            if (e.get<std::uint8_t>() == 0) return;
            e.set(std::uint8_t{0});
            // The move now ends at its target plus the achievable part of the compensation.
            if (profile_.compensate(static_cast<double>(o_->compensation_distance.get_or(0)),
                                    static_cast<double>(o_->compensation_length.get_or(0))) &&
                pp_moving_)
                pp_target_ = profile_.target();
        };
    update_inputs();
    write_feedback();
}

Drive::~Drive() {
    // A drive that goes (a slave powered off and rebuilt) leaves its partner with a dead cable, not with a
    // dangling partner.
    if (twin_partner_) twin_partner_->twin_partner_ = nullptr;
}

void Drive::tick(std::uint64_t now_ns) {
    advance(now_ns);
}

void Drive::cycle(std::uint64_t now_ns, bool) {
    advance(now_ns);
}

void Drive::advance(std::uint64_t now_ns) {
    if (!started_) {
        started_ = true;
        sim_ns_ = now_ns;
        return;
    }
    if (now_ns <= sim_ns_) return;
    // After a long pause (a debugger, a stopped master) the simulation skips ahead instead of running
    // thousands of steps at once.
    constexpr std::uint64_t kMaxCatchUp = 200'000'000;
    if (now_ns - sim_ns_ > kMaxCatchUp) sim_ns_ = now_ns - kMaxCatchUp;
    // Drives coupled by TWINsync step in lockstep, end 0 before end 1 at every instant, so that each
    // receives the other's telegram of the previous control cycle whatever order the line runs them in.
    Drive* partner = twin_partner_;
    const bool first = twin_->end() == 0;
    // The dictionary cannot change while the steps run (frames and SDO requests come in between calls).
    if (now_ns - sim_ns_ >= kServoPeriodNs) read_configuration();
    while (now_ns - sim_ns_ >= kServoPeriodNs) {
        sim_ns_ += kServoPeriodNs;
        if (partner && !first) partner->step_to(sim_ns_);
        servo_step();
        if (partner && first) partner->step_to(sim_ns_);
    }
}

void Drive::step_to(std::uint64_t t_ns) {
    if (!started_) {
        started_ = true;
        sim_ns_ = t_ns;
        return;
    }
    if (t_ns > sim_ns_ + 200'000'000) sim_ns_ = t_ns - 200'000'000;
    if (sim_ns_ + kServoPeriodNs <= t_ns) read_configuration();
    while (sim_ns_ + kServoPeriodNs <= t_ns) {
        sim_ns_ += kServoPeriodNs;
        servo_step();
    }
}

void Drive::apply_gains() {
    // 0x2003: a non-zero entry replaces the gain tuned from the motor parameters.
    ControlGains g = Mechanics::tuned_for(mech_->parameters());
    auto u = [](const coe::Value<std::uint32_t>& v) { return static_cast<double>(v.get_or(0)); };
    if (u(o_->gain_position_kp) > 0) g.position_kp = u(o_->gain_position_kp) * 0.01;
    if (u(o_->gain_velocity_kp) > 0) g.velocity_kp = u(o_->gain_velocity_kp) * 1e-6;
    if (u(o_->gain_velocity_ti) > 0) g.velocity_ti = u(o_->gain_velocity_ti) * 1e-6;
    if (u(o_->gain_current_bandwidth) > 0) g.current_bandwidth = u(o_->gain_current_bandwidth);
    mech_->set_gains(g);
}

void Drive::read_configuration() {
    options_.quick_stop = o_->quick_stop_option.get_or(2);
    options_.shutdown = o_->shutdown_option.get_or(0);
    options_.disable_operation = o_->disable_operation_option.get_or(1);
    options_.halt = o_->halt_option.get_or(1);
    options_.fault_reaction = o_->fault_reaction_option.get_or(2);
    FactorGroup f;
    f.encoder_increments = o_->encoder_increments.get_or(f.encoder_increments);
    f.motor_revolutions = o_->encoder_revolutions.get_or(1);
    f.gear_motor_revolutions = o_->gear_motor.get_or(1);
    f.gear_shaft_revolutions = o_->gear_shaft.get_or(1);
    f.feed = o_->feed.get_or(f.feed);
    f.feed_shaft_revolutions = o_->feed_shaft.get_or(1);
    // factors_ only ever holds a valid group, so an unchanged one needs no check.
    const bool same = f.encoder_increments == factors_.encoder_increments &&
                      f.motor_revolutions == factors_.motor_revolutions &&
                      f.gear_motor_revolutions == factors_.gear_motor_revolutions &&
                      f.gear_shaft_revolutions == factors_.gear_shaft_revolutions &&
                      f.feed == factors_.feed && f.feed_shaft_revolutions == factors_.feed_shaft_revolutions;
    if (!same && f.valid()) {
        factors_ = f;
        ratios_ = f.ratios();
    }
    const double rated = static_cast<double>(o_->rated_torque.get_or(1000)) * 1e-3;  // Nm
    nm_per_permille_ = rated / 1000.0;
    // Velocity threshold 0x606F, at least one unit per second.
    standstill_velocity_ = std::max<double>(o_->velocity_threshold.get_or(10), 1.0);
}

double Drive::max_velocity() const {
    double v = static_cast<double>(o_->max_profile_velocity.get_or(0xFFFFFFFFu));
    // Max motor speed 0x6080 (rpm) converted to user units/s.
    const double rpm = static_cast<double>(o_->max_motor_speed.get_or(0));
    if (rpm > 0) v = std::min(v, ratios_.radians_to_user(rpm / 60.0 * 2.0 * std::numbers::pi));
    return std::max(v, 1.0);
}

ProfileLimits Drive::profile_limits() const {
    ProfileLimits l;
    l.velocity = std::min(static_cast<double>(o_->profile_velocity.get_or(1)), max_velocity());
    l.acceleration = static_cast<double>(o_->profile_acceleration.get_or(1));
    l.deceleration = static_cast<double>(o_->profile_deceleration.get_or(1));
    if (o_->max_acceleration.get_or(0) > 0)
        l.acceleration = std::min(l.acceleration, static_cast<double>(o_->max_acceleration.get()));
    if (o_->max_deceleration.get_or(0) > 0)
        l.deceleration = std::min(l.deceleration, static_cast<double>(o_->max_deceleration.get()));
    const std::int16_t type = o_->motion_profile_type.get_or(0);
    l.jerk = type == 0 ? 0.0 : static_cast<double>(o_->profile_jerk.get_or(0));
    return l;
}

double Drive::interpolation_period() const {
    const double value = o_->interpolation_value.get_or(1);
    const std::int8_t index = o_->interpolation_index.get_or(-3);
    const double t = value * pow10_of(index);
    return t > 0 ? std::max(t, kServoPeriodNs * 1e-9) : 1e-3;
}

bool Drive::software_limits_enabled() const {
    const auto lo = o_->software_limit_min.get_or(std::numeric_limits<std::int32_t>::min());
    const auto hi = o_->software_limit_max.get_or(std::numeric_limits<std::int32_t>::max());
    return lo < hi;
}

double Drive::clamp_to_software_limits(double p) const {
    if (!software_limits_enabled()) return p;
    const double lo = o_->software_limit_min.get_or(0);
    const double hi = o_->software_limit_max.get_or(0);
    return std::clamp(p, lo, hi);
}

double Drive::machine_increments() const {
    return mech_->position() / (2.0 * std::numbers::pi) * ratios_.per_revolution;
}

void Drive::update_inputs() {
    // Machine position in increments (homing does not move it).
    const double inc = machine_increments();
    negative_limit_ = inc <= o_->negative_limit_switch.get_or(std::numeric_limits<std::int32_t>::min());
    positive_limit_ = inc >= o_->positive_limit_switch.get_or(std::numeric_limits<std::int32_t>::max());
    home_switch_ = inc >= o_->home_switch.get_or(std::numeric_limits<std::int32_t>::max());
    probe_inputs_ = o_->probe_inputs.get_or(0);
    std::uint32_t di = 0;
    if (negative_limit_) di |= 1u << 0;
    if (positive_limit_) di |= 1u << 1;
    if (home_switch_) di |= 1u << 2;
    if (probe_inputs_ & 1) di |= 1u << 16;  // manufacturer bits: touch probe inputs 1 and 2
    if (probe_inputs_ & 2) di |= 1u << 17;
    o_->digital_inputs.set(di);
}

void Drive::enter_fault(std::uint16_t code, std::uint8_t bits) {
    if (active_fault_ != 0) return;
    active_fault_ = code;
    raise_fault(code, bits);
}

void Drive::check_faults(double dt) {
    const std::uint16_t injected = o_->simulated_fault.get_or(0);
    // Encoder and over-current faults are injected into the mechanics, which the drive then monitors
    // (the encoder freezes; the power stage reports over-current, also from its I2t protection).
    mech_->inject_encoder_fault(injected == fault::Encoder);
    mech_->inject_overcurrent(injected == fault::OverCurrent);
    if (mech_->overcurrent()) enter_fault(fault::OverCurrent, coe::error_register::Current);
    if (!mech_->encoder_ok()) enter_fault(fault::Encoder, coe::error_register::Manufacturer);
    if (injected == fault::FollowingError)
        enter_fault(fault::FollowingError, coe::error_register::DeviceProfile);
    if (injected == fault::ReferenceLimit)
        enter_fault(fault::ReferenceLimit, coe::error_register::DeviceProfile);

    // Following error (position loop): window 0xFFFFFFFF switches the monitoring off.
    const std::uint32_t window = o_->following_error_window.get_or(0xFFFFFFFFu);
    const double timeout = o_->following_error_timeout.get_or(0) * 1e-3;
    if (loop_ == LoopMode::Position && window != 0xFFFFFFFFu && std::abs(following_error_) > window) {
        following_error_time_ += dt;
        if (following_error_time_ > timeout)
            enter_fault(fault::FollowingError, coe::error_register::DeviceProfile);
    } else {
        following_error_time_ = 0;
    }
    // Limit switch with reaction "fault".
    if (o_->limit_switch_reaction.get_or(0) == 1 && sm_.drive_enabled() && mode_ != Mode::Homing &&
        (negative_limit_ || positive_limit_))
        enter_fault(fault::ReferenceLimit, coe::error_register::DeviceProfile);
}

void Drive::on_mode_change() {
    continuing_ = false;
    // A new mode starts from where the axis is.
    profile_.reset({actual_user_, velocity_user_, 0.0});
    demand_ = {actual_user_, velocity_user_, 0.0};
    pp_moving_ = false;
    pending_target_.reset();
    setpoint_ack_ = false;
    csp_valid_ = false;
    pv_running_ = false;
    torque_cmd_ = 0;
    homing_bits_ = 0;
    homing_active_ = homing_error_ = false;
    homing_velocity_ = 0;
    homing_->abort();
}

void Drive::hold_disabled() {
    // No torque: the demand follows the actual position, so enabling starts without a jump.
    loop_ = LoopMode::Off;
    demand_ = {actual_user_, velocity_user_, 0.0};
    profile_.reset(demand_);
    velocity_cmd_ = 0;
    torque_cmd_ = 0;
    torque_ff_ = 0;
    pp_moving_ = false;
    pending_target_.reset();
    csp_valid_ = false;
    pv_running_ = false;
}

void Drive::run_stop(StopKind k, double dt) {
    if (k == StopKind::Coast) {
        hold_disabled();
        return;
    }
    if (k == StopKind::CurrentLimit || k == StopKind::VoltageLimit) {
        // Brake at the torque limit: velocity loop with a zero set-point.
        loop_ = LoopMode::Velocity;
        velocity_cmd_ = 0;
        torque_ff_ = 0;
        demand_ = {actual_user_, 0.0, 0.0};
        profile_.reset(demand_);
        return;
    }
    const double dec =
        static_cast<double>(k == StopKind::QuickStopRamp ? o_->quick_stop_deceleration.get_or(1)
                                                         : o_->profile_deceleration.get_or(1));
    if (stopping_ != k) {
        // Starts from the current demand in position modes, from the actual motion otherwise. A slave that
        // followed TWINsync has a demand the profile never made: it brakes from its actual motion too
        // (the profile left from its enable would make the ramp jump back there).
        if (loop_ != LoopMode::Position || coupled_) profile_.reset({actual_user_, velocity_user_, 0.0});
        profile_.stop(std::max(dec, 1.0), profile_limits().jerk);
        stopping_ = k;
    }
    demand_ = profile_.step(dt);
    loop_ = LoopMode::Position;
    velocity_cmd_ = demand_.v;
    torque_ff_ = 0;
}

void Drive::servo_step() {
    const double dt = kServoPeriodNs * 1e-9;
    ++steps_;
    const std::uint16_t own_controlword = o_->controlword.get_or(0);
    controlword_ = own_controlword;

    // TWINsync: the telegram of the partner drive's last cycle. A slave controlled through TWINsync obeys
    // the master drive's control word (P2611) instead of 0x6040.
    // (The drive's own state matters to the port only while TWINsync is on.)
    twin_->receive(sim_ns_, twin_->active() ? twinsync_local() : twinsync::LocalState{});
    previous_twin_control_ = twin_control_;
    twin_control_ = twin_->received_control_word();
    if (twin_->controlled_by_twinsync() && twin_->has_data())
        controlword_ = twinsync::cia402_from_control_word(twin_control_);
    // A master drive switches on its control once its slave is in state Control (unless P2651 bit 2).
    if (twin_->active() && twin_->role() == twinsync::Role::Master && twin_->link_ok() &&
        twin_->partner().mode == twinsync::Role::Slave && !twin_->partner_enabled() &&
        !(o_->tw_config.get_or(0) & twinsync::kConfigNoSlaveStateCheck) &&
        sm_.state() != State::OperationEnabled)
        controlword_ = static_cast<std::uint16_t>(controlword_ & ~cw::EnableOperation);

    update_inputs();
    check_faults(dt);
    // TWINsync errors become faults in state Control (chapter 7).
    if (const auto e = twin_->pending_error(); e && sm_.state() == State::OperationEnabled)
        enter_twinsync_fault(*e);

    const State before = sm_.state();
    const bool twin_cause = twin_error_ && twin_->pending_error() == twin_error_;
    const bool fault_present =
        active_fault_ != 0 && (o_->simulated_fault.get_or(0) != 0 || mech_->overcurrent() ||
                               !mech_->encoder_ok() || twin_cause || sm_.state() != State::Fault);
    const bool at_rest =
        std::abs(velocity_user_) <= standstill_velocity() && (loop_ != LoopMode::Position || profile_.done());
    sm_.update(controlword_, fault_present, at_rest, options_);
    const State now = sm_.state();
    if (now != before) {
        if (before == State::Fault && now == State::SwitchOnDisabled) {
            active_fault_ = 0;
            twin_error_.reset();
            twin_->set_error(std::nullopt);
            clear_faults();
        }
        if (now == State::OperationEnabled) {
            apply_gains();
            on_mode_change();
        }
    }
    if (sm_.stop() == StopKind::None) stopping_ = StopKind::None;

    // Velocity override (TwinCAT NC PTP online change) of the profile modes, in ppm of 100 %.
    const std::uint32_t ov = std::min<std::uint32_t>(o_->velocity_override.get_or(1'000'000), 1'000'000);
    if (ov != override_ppm_) {
        override_ppm_ = ov;
        profile_.set_override(ov * 1e-6);
    }

    // Modes of operation: a supported mode takes effect at once; 0x6061 shows it.
    const auto requested = static_cast<Mode>(o_->modes.get_or(0));
    if (requested != mode_ && supported(requested)) {
        mode_ = requested;
        on_mode_change();
    }

    internal_limit_ = false;
    const bool follow = twin_->follows() && twin_->has_data();
    if (coupled_ && !follow) {
        // Decoupled: in motion, the axis goes on as if it were still coupled until it is stopped.
        coupled_ = false;
        if (sm_.following_setpoints() && std::abs(demand_.v) > standstill_velocity()) {
            continuing_ = true;
            continue_halting_ = false;
            continue_velocity_ = demand_.v;
            continue_target_position_ = o_->target_position.get_or(0);
            continue_target_velocity_ = o_->target_velocity.get_or(0);
        }
    }
    if (!sm_.drive_enabled()) {
        hold_disabled();
        coupled_ = continuing_ = false;
    } else if (sm_.stop() != StopKind::None) {
        run_stop(sm_.stop(), dt);
        coupled_ = continuing_ = false;
    } else if (follow) {
        run_twinsync(dt);
    } else if (continuing_) {
        run_decoupled(dt);
    } else {
        run_mode(dt);
    }
    if (mode_ == Mode::Homing && (homing_bits_ & sw::Bit12) && !(homing_bits_ & sw::Bit13)) homed_ = true;

    // The loops and the mechanics.
    const double torque_limit_pos =
        std::min(o_->max_torque.get_or(3000), o_->positive_torque_limit.get_or(3000)) * nm_per_permille();
    const double torque_limit_neg =
        std::min(o_->max_torque.get_or(3000), o_->negative_torque_limit.get_or(3000)) * nm_per_permille();
    mech_->set_torque_limits(torque_limit_pos, torque_limit_neg);
    mech_->set_load_torque(o_->load_torque.get_or(0) * nm_per_permille());
    const double inertia = inertia_;
    switch (loop_) {
        case LoopMode::Off:
            mech_->command(LoopMode::Off, 0, 0, 0);
            break;
        case LoopMode::Position:
            mech_->command(LoopMode::Position, user_to_rad(demand_.p), user_velocity_to_rad(demand_.v),
                           inertia * user_velocity_to_rad(demand_.a) + torque_ff_ * nm_per_permille());
            break;
        case LoopMode::Velocity:
            mech_->command(LoopMode::Velocity, 0, user_velocity_to_rad(velocity_cmd_),
                           torque_ff_ * nm_per_permille());
            break;
        case LoopMode::Torque:
            mech_->command(LoopMode::Torque, 0, 0, torque_cmd_ * nm_per_permille());
            break;
    }
    const double previous_inc = previous_machine_inc_;
    mech_->step(dt);
    const double machine_inc = machine_increments();
    previous_machine_inc_ = machine_inc;
    increments_ = floor64(machine_inc);
    actual_user_ = static_cast<double>(ratios_.increments_to_user(increments_)) + home_shift_;
    velocity_user_ = ratios_.radians_to_user(mech_->velocity());
    if (loop_ != LoopMode::Position)
        demand_ = {actual_user_, loop_ == LoopMode::Velocity ? velocity_cmd_ : velocity_user_, 0.0};
    following_error_ = loop_ == LoopMode::Position ? demand_.p - actual_user_ : 0.0;

    run_touch_probe(previous_inc, machine_inc);
    write_feedback();
    // The TWINsync values every cycle while the link is on; otherwise only for SDO reads, every 4 ms.
    if (twin_->active() || steps_ % 16 == 0) write_twinsync_values();
    twinsync::LocalState local;
    if (twin_->active()) {
        local = twinsync_local();
        local.controlword = own_controlword;
    }
    twin_->transmit(sim_ns_, local);
    previous_controlword_ = controlword_;
}

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

twinsync::LocalState Drive::twinsync_local() const {
    twinsync::LocalState l;
    l.state = drivecom_state(sm_.state());
    l.fault = sm_.state() == State::Fault || sm_.state() == State::FaultReactionActive;
    l.homed = homed_;
    l.transition = sm_.stop() != StopKind::None;
    l.controlword = o_->controlword.get_or(0);
    l.homing_mode = mode_ == Mode::Homing;
    l.fieldbus_synchronised = sync_mode() == coe::SyncMode::DcSync0 || sync_mode() == coe::SyncMode::DcSync1;
    l.position = actual_user_;
    l.speed_rpm = rpm_of_rad(mech_->velocity());
    l.torque_nm = mech_->torque();
    l.rated_torque_nm = nm_per_permille() * 1000.0;
    return l;
}

void Drive::write_twinsync_values() {
    const double torque_ref = static_cast<double>(o_->tw_local_torque_ref.get_or(1.0f));
    const double speed_ref = static_cast<double>(o_->tw_local_speed_ref.get_or(1.0f));
    const double act_rpm = rpm_of_rad(mech_->velocity());
    const double demand_v = loop_ == LoopMode::Velocity ? velocity_cmd_ : demand_.v;
    const double ref_rpm = rpm_of_rad(user_velocity_to_rad(demand_v));
    const double ref_torque = loop_ == LoopMode::Torque ? torque_cmd_ * nm_per_permille() : mech_->torque();
    o_->tw_local_ref_torque.set(scaled16(ref_torque, torque_ref));
    o_->tw_local_act_torque.set(scaled16(mech_->torque(), torque_ref));
    o_->tw_torque_actual_scaled.set(scaled16(mech_->torque(), torque_ref));
    o_->tw_local_ref_speed.set(scaled16(ref_rpm, speed_ref));
    o_->tw_local_ff_speed.set(scaled16(ref_rpm, speed_ref));
    o_->tw_local_act_speed.set(scaled16(act_rpm, speed_ref));
    o_->tw_speed_actual_rpm.set(static_cast<float>(act_rpm));
    o_->tw_speed_setpoint_rpm.set(static_cast<float>(ref_rpm));
    o_->tw_local_ref_pos.set(wrap32(static_cast<std::int64_t>(std::llround(demand_.p))));
    const std::int32_t act = wrap32(static_cast<std::int64_t>(std::floor(actual_user_)));
    o_->tw_local_act_pos.set(act);
    o_->tw_position_actual.set(act);
    // Single-turn angle of the motor, 16 bit (the virtual encoder's raw value).
    const double per_rev = ratios_.per_revolution;
    const double turn = std::fmod(machine_increments(), per_rev) / per_rev;
    o_->tw_local_eps.set(
        static_cast<std::uint16_t>(std::llround((turn < 0 ? turn + 1.0 : turn) * 65536.0) & 0xFFFF));
    // P2650: the drive's own current error, unless the receive mapping brings the slave's (TWD, SCON,
    // PCON, VE masters: "interpreted as the error of the slave drive").
    if (!twin_->receives(twinsync::p::CurrentError)) {
        std::uint16_t number = 0, location = 0;
        if (twin_error_) {
            number = twin_error_->number;
            location = twin_error_->location;
        } else if (active_fault_ != 0) {
            number = static_cast<std::uint16_t>(active_fault_ >> 8);
            location = static_cast<std::uint16_t>(active_fault_ & 0xFF);
        }
        o_->tw_error_number.set(number);
        o_->tw_error_location.set(location);
    }
}

void Drive::enter_twinsync_fault(twinsync::ErrorId e) {
    if (active_fault_ != 0) return;
    // 0x603F: serial interface 2 for the link (40-xx) and the other axis (39-02); the speed and torque
    // monitoring of the gantry as velocity and torque control faults. The emergency's manufacturer bytes
    // carry the MSD error number and location.
    std::uint16_t code = 0x7520;
    std::uint8_t bits = coe::error_register::Communication | coe::error_register::Manufacturer;
    if (e == twinsync::error::SpeedDifference) {
        code = 0x8400;
        bits = coe::error_register::Manufacturer;
    } else if (e == twinsync::error::TorqueDifference) {
        code = 0x8300;
        bits = coe::error_register::Manufacturer;
    }
    active_fault_ = code;
    twin_error_ = e;
    twin_->set_error(e);
    raise_fault(code, bits, {e.number, e.location, 0, 0, 0});
}

void Drive::hold_for_coupling() {
    loop_ = LoopMode::Position;
    demand_.v = demand_.a = 0;
    torque_ff_ = 0;
}

void Drive::run_twinsync(double dt) {
    (void)dt;
    using twinsync::Follow;
    using twinsync::Setting;
    const auto* m = twin_->mode();
    Follow f = m->follow;
    if (f == Follow::ByControlMode) {
        const auto cm = o_->tw_control_mode.get_or(3);
        f = cm == 1 ? Follow::Torque : cm == 2 ? Follow::Speed : Follow::PositionAbsolute;
    }
    const bool user = m->follow == Follow::ByControlMode;
    const double inv = o_->tw_inverted.get_or(1) < 0 ? -1.0 : 1.0;
    const double remote_speed_ref = static_cast<double>(o_->tw_remote_speed_ref.get_or(1.0f));
    const double remote_torque_ref = static_cast<double>(o_->tw_remote_torque_ref.get_or(1.0f));
    using I16 = coe::Value<std::int16_t>;
    auto speed = [&](const I16& e) { return e.get_or(0) / 32768.0 * remote_speed_ref; };    // rpm
    auto torque = [&](const I16& e) { return e.get_or(0) / 32768.0 * remote_torque_ref; };  // Nm
    auto rpm_to_user = [&](double rpm) {
        return ratios_.radians_to_user(rpm / 60.0 * 2.0 * std::numbers::pi);
    };
    const double still = standstill_velocity();
    // The master's speed arrives as a 16-bit fraction of P2609: standstill within two of its steps.
    const double still_remote = std::max(still, 2.0 * std::abs(rpm_to_user(remote_speed_ref / 32768.0)));
    torque_ff_ = 0;
    cyclic_following_ =
        true;  // statusword bit 12 of the cyclic modes: the drive follows (TWINsync's) command

    switch (f) {
        case Follow::PositionAbsolute: {
            // IP: the master's actual position; REFPOS and GANTRY (and USER/EXT_MAP): its set-point.
            const bool ip = m->setting == Setting::PconIpSlave;
            const double master = (ip ? o_->tw_remote_act_pos : o_->tw_remote_ref_pos).get_or(0);
            const double ff_rpm = m->setting == Setting::PconGantrySlave
                                      ? static_cast<double>(o_->tw_act_speed_master.get_or(0))
                                      : speed(ip ? o_->tw_remote_act_speed : o_->tw_remote_ref_speed);
            const double v = inv * rpm_to_user(ff_rpm);
            if (!coupled_) {
                // Coupling only at standstill of both axes.
                if (std::abs(v) > still_remote || std::abs(velocity_user_) > still)
                    return hold_for_coupling();
                coupled_ = true;
            }
            demand_ = {clamp_to_software_limits(inv * master), v, 0.0};
            loop_ = LoopMode::Position;
            if (m->setting == Setting::PconGantrySlave)
                torque_ff_ = inv * torque(o_->tw_remote_act_torque) / nm_per_permille();
            break;
        }
        case Follow::PositionDelta: {
            // PCON: increments of the master's actual position, corrected by the resolution factors
            // (P0270/P2652), geared (P2653/P2654), reversed by P2583, integrated onto the coupling position.
            const std::int32_t master = o_->tw_remote_act_pos.get_or(0);
            const double k = inv * static_cast<double>(o_->tw_local_resolution.get_or(1)) /
                             std::max<double>(o_->tw_remote_resolution.get_or(1), 1.0) *
                             static_cast<double>(o_->tw_gear_numerator.get_or(1)) /
                             std::max<double>(o_->tw_gear_denominator.get_or(1), 1.0);
            const double v = k * rpm_to_user(speed(o_->tw_remote_act_speed));
            if (!coupled_) {
                if (std::abs(v) > still_remote || std::abs(velocity_user_) > still)
                    return hold_for_coupling();
                coupled_ = true;
                twin_master_last_ = master;
            }
            const auto delta = static_cast<std::int32_t>(static_cast<std::uint32_t>(master) -
                                                         static_cast<std::uint32_t>(twin_master_last_));
            twin_master_last_ = master;
            double p = demand_.p + k * delta;
            // Re-synchronisation (P2611 bit 12, rising): the slave takes the master position itself.
            if ((twin_control_ & twinsync::control::ReSyncPosition) &&
                !(previous_twin_control_ & twinsync::control::ReSyncPosition))
                p = k * master;
            demand_ = {clamp_to_software_limits(p), v, 0.0};
            loop_ = LoopMode::Position;
            break;
        }
        case Follow::Speed:
        case Follow::SpeedTorquePrecontrol: {
            double rpm = inv * speed(user ? o_->tw_remote_ref_speed : o_->tw_remote_act_speed);
            if (m->setting == Setting::TwdSlaveV1) {
                // Speed-up: P2584 % of the main set-point, at least P2585, signed as the master's torque.
                const double master_torque = torque(o_->tw_remote_act_torque);
                double add = std::abs(rpm) * static_cast<double>(o_->tw_speed_up.get_or(0)) / 100.0;
                add = std::max(add, static_cast<double>(o_->tw_speed_up_min.get_or(0)));
                if (master_torque != 0) rpm += master_torque > 0 ? add : -add;
            }
            velocity_cmd_ = std::clamp(rpm_to_user(rpm), -max_velocity(), max_velocity());
            if (f == Follow::SpeedTorquePrecontrol)
                torque_ff_ = inv * torque(o_->tw_remote_act_torque) / nm_per_permille();
            loop_ = LoopMode::Velocity;
            demand_ = {actual_user_, velocity_cmd_, 0.0};
            coupled_ = true;
            break;
        }
        case Follow::Torque:
            torque_cmd_ = inv * torque(o_->tw_remote_ref_torque) / nm_per_permille();
            loop_ = LoopMode::Torque;
            coupled_ = true;
            break;
        case Follow::None:
        case Follow::ByControlMode:
            break;
    }
}

void Drive::run_decoupled(double dt) {
    // A new set-point, a new target or a new mode ends the decoupled motion; halt stops it.
    const bool new_setpoint = (controlword_ & kNewSetpoint) && !(previous_controlword_ & kNewSetpoint);
    if (new_setpoint || o_->target_position.get_or(0) != continue_target_position_ ||
        o_->target_velocity.get_or(0) != continue_target_velocity_) {
        continuing_ = false;
        on_mode_change();
        run_mode(dt);
        return;
    }
    loop_ = LoopMode::Position;
    torque_ff_ = 0;
    if (controlword_ & kHalt) {
        if (!continue_halting_) {
            profile_.reset(demand_);
            profile_.stop(std::max<double>(o_->profile_deceleration.get_or(1), 1.0), profile_limits().jerk);
            continue_halting_ = true;
        }
        demand_ = profile_.step(dt);
        if (profile_.done()) continuing_ = false;
        return;
    }
    demand_ = {demand_.p + continue_velocity_ * dt, continue_velocity_, 0.0};
}

void Drive::run_mode(double dt) {
    halted_ = (controlword_ & kHalt) && mode_ != Mode::CyclicTorque && mode_ != Mode::ProfileTorque;
    switch (mode_) {
        case Mode::ProfilePosition:
            run_profile_position(dt);
            break;
        case Mode::ProfileVelocity:
            run_profile_velocity(dt);
            break;
        case Mode::ProfileTorque:
            run_torque(dt, true);
            break;
        case Mode::Homing:
            run_homing(dt);
            break;
        case Mode::CyclicPosition:
            run_cyclic_position(dt);
            break;
        case Mode::CyclicVelocity:
            run_cyclic_velocity(dt);
            break;
        case Mode::CyclicTorque:
            run_torque(dt, false);
            break;
        default:
            // No mode selected yet: hold the position.
            loop_ = LoopMode::Position;
            demand_.v = demand_.a = 0;
            break;
    }
}

bool Drive::blocked(double direction) const {
    // A hardware limit switch blocks motion towards it (motion away from it is allowed).
    return (direction > 0 && positive_limit_) || (direction < 0 && negative_limit_);
}

void Drive::start_move(double target) {
    pp_target_ = target;
    pp_moving_ = true;
    profile_.move_to(target, profile_limits());
}

void Drive::run_profile_position(double dt) {
    const bool edge = (controlword_ & kNewSetpoint) && !(previous_controlword_ & kNewSetpoint);
    if (edge && !pending_target_) {
        double target = static_cast<double>(o_->target_position.get_or(0));
        if (controlword_ & kRelative) target += pp_target_;
        const double clamped = clamp_to_software_limits(target);
        if (clamped != target) internal_limit_ = true;
        setpoint_ack_ = true;
        if (!blocked(clamped - actual_user_)) {
            if (!pp_moving_ || (controlword_ & kChangeImmediately) || halted_)
                start_move(clamped);
            else
                pending_target_ = clamped;  // set of set-points: executed after the current one
        }
    }
    // Set-point acknowledge: cleared once the master took bit 4 back and the buffer is free again.
    if (!(controlword_ & kNewSetpoint) && !pending_target_) setpoint_ack_ = false;

    if (halted_) {
        run_stop(stop_for(StopOption::Halt, options_), dt);
        return;
    }
    if (stopping_ != StopKind::None) {
        // Halt released: continue to the target.
        stopping_ = StopKind::None;
        if (pp_moving_) start_move(pp_target_);
    }
    if (pending_target_ && (controlword_ & kChangeOnSetpoint)) {
        // Change on set-point: go on to the next target without stopping at this one.
        start_move(*pending_target_);
        pending_target_.reset();
    }
    // A hardware limit switch in the direction of travel stops the move.
    if (pp_moving_ && blocked(demand_.v) && stopping_ == StopKind::None) {
        profile_.stop(static_cast<double>(std::max<std::uint32_t>(o_->quick_stop_deceleration.get_or(1), 1)),
                      profile_limits().jerk);
        pp_target_ = profile_.target();
        pp_moving_ = false;
        pending_target_.reset();
    }
    loop_ = LoopMode::Position;
    torque_ff_ = 0;
    demand_ = profile_.step(dt);
    if (pp_moving_ && profile_.done()) {
        pp_moving_ = false;
        if (pending_target_) {
            start_move(*pending_target_);
            pending_target_.reset();
        }
    }
    if (positive_limit_ || negative_limit_) internal_limit_ = true;
    if (software_limits_enabled() && (actual_user_ <= o_->software_limit_min.get_or(0) ||
                                      actual_user_ >= o_->software_limit_max.get_or(0)))
        internal_limit_ = true;
}

void Drive::run_profile_velocity(double dt) {
    double target = static_cast<double>(o_->target_velocity.get_or(0));
    target = std::clamp(target, -max_velocity(), max_velocity());
    if (halted_) {
        run_stop(stop_for(StopOption::Halt, options_), dt);
        if (loop_ == LoopMode::Position) {
            loop_ = LoopMode::Velocity;
            velocity_cmd_ = demand_.v;
        }
        pv_running_ = false;
        return;
    }
    if (blocked(target)) {
        internal_limit_ = true;
        target = 0;
    }
    if (stopping_ != StopKind::None || target != pv_target_ || !pv_running_) {
        if (stopping_ != StopKind::None) profile_.reset({actual_user_, velocity_user_, 0.0});
        stopping_ = StopKind::None;
        ProfileLimits l = profile_limits();
        profile_.run_at(target, l);
        pv_target_ = target;
        pv_running_ = true;
    }
    const Kinematics k = profile_.step(dt);
    loop_ = LoopMode::Velocity;
    velocity_cmd_ = k.v;
    torque_ff_ = inertia_ * user_velocity_to_rad(k.a) / nm_per_permille();
}

void Drive::run_torque(double dt, bool profile) {
    double target = o_->target_torque.get_or(0);
    if (!profile) target += o_->torque_offset.get_or(0);
    const double max = o_->max_torque.get_or(3000);
    target = std::clamp(target, -max, max);
    if (blocked(target)) {
        internal_limit_ = true;
        target = 0;
    }
    if (profile) {
        // Profile torque: the demand moves to the target at the torque slope (per mille per second).
        const double slope = std::max<double>(o_->torque_slope.get_or(0), 1.0);
        const double step = slope * dt;
        torque_cmd_ += std::clamp(target - torque_cmd_, -step, step);
    } else {
        torque_cmd_ = target;
    }
    loop_ = LoopMode::Torque;
    // Speed limit: above the maximum motor speed the velocity loop takes over at that speed, with the
    // torque demand as the limit.
    const double vmax = max_velocity();
    if (std::abs(velocity_user_) > vmax && torque_cmd_ * velocity_user_ > 0) {
        loop_ = LoopMode::Velocity;
        velocity_cmd_ = std::copysign(vmax, velocity_user_);
        internal_limit_ = true;
    }
}

void Drive::run_cyclic_position(double dt) {
    const std::int32_t raw = o_->target_position.get_or(0);
    const double offset = o_->position_offset.get_or(0);
    if (!csp_valid_ || raw != csp_raw_) {
        csp_from_ = csp_valid_ ? demand_.p : actual_user_;
        csp_to_ = static_cast<double>(raw) + offset;
        csp_raw_ = raw;
        csp_since_ = 0;
        csp_valid_ = true;
    }
    if (halted_) {
        run_stop(stop_for(StopOption::Halt, options_), dt);
        csp_valid_ = false;
        return;
    }
    stopping_ = StopKind::None;
    const double period = interpolation_period();
    csp_since_ += dt;
    const double frac = std::min(1.0, csp_since_ / period);
    double p = csp_from_ + (csp_to_ - csp_from_) * frac;
    // The velocity feed-forward is the demand's own change over this servo period.
    double v = (p - demand_.p) / dt;
    const double limited = clamp_to_software_limits(p);
    if (limited != p) {
        internal_limit_ = true;
        p = limited;
        v = 0;
    }
    if (blocked(p - demand_.p)) {
        internal_limit_ = true;
        p = demand_.p;
        v = 0;
    }
    cyclic_following_ = !internal_limit_;
    const double a = (v - demand_.v) / dt;
    demand_ = {p, v, std::abs(a) < 1e12 ? a : 0.0};
    demand_.v += o_->velocity_offset.get_or(0);
    loop_ = LoopMode::Position;
    torque_ff_ = o_->torque_offset.get_or(0);
}

void Drive::run_cyclic_velocity(double dt) {
    if (halted_) {
        run_stop(stop_for(StopOption::Halt, options_), dt);
        if (loop_ == LoopMode::Position) {
            loop_ = LoopMode::Velocity;
            velocity_cmd_ = demand_.v;
        }
        pv_running_ = false;
        return;
    }
    stopping_ = StopKind::None;
    double v = static_cast<double>(o_->target_velocity.get_or(0)) + o_->velocity_offset.get_or(0);
    v = std::clamp(v, -max_velocity(), max_velocity());
    if (blocked(v)) {
        internal_limit_ = true;
        v = 0;
    }
    cyclic_following_ = !internal_limit_;
    loop_ = LoopMode::Velocity;
    velocity_cmd_ = v;
    torque_ff_ = o_->torque_offset.get_or(0);
}

void Drive::run_homing(double dt) {
    // Bit 4 rising starts the homing method 0x6098; bit 4 falling or halt interrupts it.
    const bool edge = (controlword_ & kHomingStart) && !(previous_controlword_ & kHomingStart);
    if (edge) {
        const double ipu = ratios_.per_user;
        HomingParameters hp;
        hp.speed_switch = o_->homing_speed_switch.get_or(0);
        hp.speed_zero = o_->homing_speed_zero.get_or(0);
        hp.acceleration = o_->homing_acceleration.get_or(0);
        hp.home_offset = o_->home_offset.get_or(0);
        hp.index_period = ratios_.per_revolution / ipu;
        hp.index_phase = o_->index_pulse_offset.get_or(0) / ipu + home_shift_;
        hp.standstill_velocity = standstill_velocity();
        homing_active_ = homing_->start(o_->homing_method.get_or(0), hp, actual_user_);
        homing_error_ = !homing_active_;
        homing_velocity_ = 0;
    }
    if (homing_active_ && (!(controlword_ & kHomingStart) || halted_)) {
        homing_->halt();
        homing_active_ = false;
    }
    HomingOutput out;
    if (homing_active_) {
        out = homing_->update(actual_user_, velocity_user_, {negative_limit_, positive_limit_, home_switch_});
        if (out.home_found) {
            // The coordinate system: the home position now reads as the home offset 0x607C.
            const double shift = homing_->position_shift();
            home_shift_ += shift;
            actual_user_ += shift;
            demand_.p += shift;
            profile_.reset(demand_);
            homing_velocity_ = std::numeric_limits<double>::quiet_NaN();  // re-plan from the shifted state
        }
        if (out.status == HomingStatus::Attained && out.target_reached) homing_active_ = false;
        if (out.status == HomingStatus::Error && out.target_reached) homing_active_ = false;
    }
    if (halted_ && !homing_active_) {
        run_stop(stop_for(StopOption::Halt, options_), dt);
    } else {
        stopping_ = StopKind::None;
        const double v = homing_active_ ? out.velocity : 0.0;
        const double acc = (homing_active_ && out.acceleration > 0)
                               ? out.acceleration
                               : std::max<double>(o_->homing_acceleration.get_or(1), 1.0);
        if (!(v == homing_velocity_)) {
            ProfileLimits l{std::max(std::abs(v), 1.0), acc, acc, 0.0};
            profile_.run_at(v, l);
            homing_velocity_ = v;
        }
        demand_ = profile_.step(dt);
        loop_ = LoopMode::Position;
        torque_ff_ = 0;
    }
    homing_bits_ = homing_error_ ? static_cast<std::uint16_t>(sw::Bit13 | sw::TargetReached)
                                 : homing_->statusword_bits();
}

void Drive::run_touch_probe(double previous_inc, double machine_inc) {
    TouchProbe::Period p;
    p.function = o_->probe_function.get_or(0);
    p.inputs = probe_inputs_;
    p.previous_inc = previous_inc;
    p.machine_inc = machine_inc;
    p.index_offset = o_->index_pulse_offset.get_or(0);
    const TouchProbe::Latched l = probe_.step(p, ratios_, home_shift_);
    coe::Value<std::int32_t>* values[2][2] = {{&o_->probe1_positive, &o_->probe1_negative},
                                              {&o_->probe2_positive, &o_->probe2_negative}};
    for (int n = 0; n < 2; ++n)
        for (int edge = 0; edge < 2; ++edge)
            if (l.set[n][edge]) values[n][edge]->set(l.value[n][edge]);
    o_->probe_status.set(probe_.status());
}

void Drive::write_feedback() {
    std::uint16_t status = sm_.statusword_bits() | sw::Remote;
    const State st = sm_.state();
    const bool enabled = st == State::OperationEnabled && sm_.stop() == StopKind::None;
    const double dt = kServoPeriodNs * 1e-9;

    // Target reached (bit 10) and the mode-specific bits 12/13.
    bool reached = false;
    bool bit12 = false, bit13 = false;
    const double threshold = standstill_velocity();
    const bool standing = std::abs(velocity_user_) <= threshold;
    speed_zero_time_ = standing ? speed_zero_time_ + dt : 0.0;
    const std::uint32_t fe_window = o_->following_error_window.get_or(0xFFFFFFFFu);
    const bool fe_exceeded = fe_window != 0xFFFFFFFFu && std::abs(following_error_) > fe_window &&
                             following_error_time_ > o_->following_error_timeout.get_or(0) * 1e-3;
    if (enabled) {
        switch (mode_) {
            case Mode::ProfilePosition: {
                const bool in_window = std::abs(pp_target_ - actual_user_) <= o_->position_window.get_or(0);
                position_window_time_ =
                    (in_window && !pp_moving_ && profile_.done()) ? position_window_time_ + dt : 0.0;
                reached = halted_ ? (standing && profile_.done())
                                  : !pp_moving_ && !pending_target_ &&
                                        position_window_time_ >= o_->position_window_time.get_or(0) * 1e-3;
                bit12 = setpoint_ack_;
                bit13 = fe_exceeded;
                break;
            }
            case Mode::ProfileVelocity: {
                const double target = o_->target_velocity.get_or(0);
                const bool in_window = std::abs(target - velocity_user_) <= o_->velocity_window.get_or(0);
                velocity_window_time_ = in_window ? velocity_window_time_ + dt : 0.0;
                reached =
                    halted_ ? standing : velocity_window_time_ >= o_->velocity_window_time.get_or(0) * 1e-3;
                bit12 = speed_zero_time_ >= o_->velocity_threshold_time.get_or(0) * 1e-3;
                break;
            }
            case Mode::ProfileTorque:
                reached = std::abs(torque_cmd_ - o_->target_torque.get_or(0)) < 0.5;
                break;
            case Mode::Homing: {
                const std::uint16_t hb = homing_bits_;
                reached = hb & sw::TargetReached;
                bit12 = hb & sw::Bit12;
                bit13 = hb & sw::Bit13;
                break;
            }
            case Mode::CyclicPosition:
                reached = std::abs(csp_to_ - actual_user_) <= o_->position_window.get_or(0);
                bit12 = cyclic_following_ && !halted_;
                bit13 = fe_exceeded;
                break;
            case Mode::CyclicVelocity:
            case Mode::CyclicTorque:
                bit12 = cyclic_following_ && !halted_;
                break;
            default:
                break;
        }
    } else if (st == State::QuickStopActive) {
        reached = standing;  // the quick stop has ended
    }
    if (mode_ == Mode::Homing && !enabled) {
        reached = homing_bits_ & sw::TargetReached;
        bit12 = homing_bits_ & sw::Bit12;
        bit13 = homing_bits_ & sw::Bit13;
    }
    if (reached) status |= sw::TargetReached;
    if (bit12) status |= sw::Bit12;
    if (bit13) status |= sw::Bit13;
    if (internal_limit_ || positive_limit_ || negative_limit_) status |= sw::InternalLimit;
    if (positive_limit_ || negative_limit_ || (enabled && mech_->torque_limited())) status |= sw::Warning;

    o_->statusword.set(status);
    o_->modes_display.set(static_cast<std::int8_t>(mode_));
    o_->position_demand.set(sat32(demand_.p));
    o_->position_demand_internal.set(
        wrap32(ratios_.user_to_increments(static_cast<std::int64_t>(std::llround(demand_.p - home_shift_)))));
    o_->position_internal.set(wrap32(increments_));
    o_->position_actual.set(wrap32(floor64(actual_user_)));
    o_->following_error_actual.set(sat32(following_error_));
    o_->velocity_demand.set(sat32(loop_ == LoopMode::Velocity ? velocity_cmd_ : demand_.v));
    o_->velocity_actual.set(sat32(velocity_user_));
    const double per = nm_per_permille();
    o_->torque_demand.set(sat16(loop_ == LoopMode::Torque ? torque_cmd_ : mech_->torque() / per));
    o_->torque_actual.set(sat16(mech_->torque() / per));
    const double rated_a = std::max<double>(o_->rated_current.get_or(3000), 1.0) * 1e-3;
    o_->current_actual.set(sat16(mech_->current() / rated_a * 1000.0));
    // Drive temperature: 35 C plus a rise with the square of the current.
    const double i_rel = mech_->current() / rated_a;
    temperature_ += (350.0 + 300.0 * i_rel * i_rel - temperature_) * dt / 60.0;
    o_->temperature.set(sat16(temperature_));
}

}  // namespace vecat::cia402
