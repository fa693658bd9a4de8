// The CoE adapter of the drive core: binds the DriveIo (drive_io.hpp) to the dictionary once, through the
// named objects, and around each servo period of the core copies the dictionary in and the feedback out,
// runs the TWINsync option card (receive before, transmit after) and raises the core's faults as
// emergencies. The motion itself is drive_core.cpp and the modes; the segment factories drive_segment.cpp.
// About 670 lines: the binding of every drive object (Drive::Objects, about 180 lines) and the copies in and
// out of each servo period, which name the same objects, kept together so that each object is bound once;
// and which periods an advance may skip without that work (Drive::advance).
#include "cia402/drive.hpp"

#include "cia402/drive_variant.hpp"

#include "device/drive_objects.hpp"
#include "protocol/cia402_objects.hpp"
#include "twinsync/parameters.hpp"

namespace vecat::cia402 {

namespace {

using coe::Entry;
namespace obj = protocol::obj;
namespace mfr = device::mfr;

}  // namespace

// The dictionary entries the drive reads and writes, bound once by name (protocol/cia402_objects.hpp,
// device/drive_objects.hpp) as typed handles: an entry of another type than the catalogue's refuses to
// bind. A missing object (a vendor ESI without it) reads as its fallback and is not written.
struct Drive::Objects {
    template <class T>
    using V = coe::Value<T>;
    // vecat: the vecat drive's manufacturer objects are the device's (VariantObjects::vecat_objects).
    Objects(coe::ObjectDictionary& d, bool vecat) : od(d), vecat_objects(vecat) {}
    // The drive also runs on vendors' dictionaries (ESI files), some of which declare a profile object
    // with another integer type (DINT digital inputs, USINT for a UDINT): such an entry is converted as
    // Entry::get/set do (coe::Match::Convert). Reals and strings must match.
    template <protocol::DataType T>
    V<protocol::value_type_t<T>> bind(protocol::ObjectId<T> id) {
        return coe::bind(od, id, coe::Match::Convert);
    }

    // A manufacturer object of the vecat drive: unbound on a device whose 0x2000-0x2FFF are its own.
    template <protocol::DataType T>
    V<protocol::value_type_t<T>> mfr_bind(protocol::ObjectId<T> id) {
        return vecat_objects ? bind(id) : V<protocol::value_type_t<T>>{};
    }

    coe::ObjectDictionary& od;
    const bool vecat_objects;
    // The handles a servo period reads and writes first, together: few cache lines per period (a line of
    // hundreds of drives runs each period out of the caches).
    V<std::uint32_t> digital_inputs = bind(obj::digital_inputs);
    V<std::uint16_t> statusword = bind(obj::statusword);
    V<std::int8_t> modes_display = bind(obj::modes_of_operation_display);
    V<std::int32_t> position_demand = bind(obj::position_demand_value);
    V<std::int32_t> position_demand_internal = bind(obj::position_demand_internal_value);
    V<std::int32_t> position_internal = bind(obj::position_actual_internal_value);
    V<std::int32_t> position_actual = bind(obj::position_actual_value);
    V<std::int32_t> following_error_actual = bind(obj::following_error_actual_value);
    V<std::int32_t> velocity_demand = bind(obj::velocity_demand_value);
    V<std::int32_t> velocity_actual = bind(obj::velocity_actual_value);
    V<std::int16_t> torque_demand = bind(obj::torque_demand);
    V<std::int16_t> torque_actual = bind(obj::torque_actual_value);
    V<std::int16_t> current_actual = bind(obj::current_actual_value);
    V<std::int16_t> temperature = mfr_bind(mfr::drive_temperature);
    V<std::int16_t> tw_local_ref_torque = tw<std::int16_t>(twinsync::p::LocalRefTorque);
    V<std::int16_t> tw_local_act_torque = tw<std::int16_t>(twinsync::p::LocalActTorque);
    V<std::int16_t> tw_torque_actual_scaled = tw<std::int16_t>(twinsync::p::TorqueActualScaled);
    V<std::int16_t> tw_local_ref_speed = tw<std::int16_t>(twinsync::p::LocalRefSpeed);
    V<std::int16_t> tw_local_ff_speed = tw<std::int16_t>(twinsync::p::LocalRefFFSpeed);
    V<std::int16_t> tw_local_act_speed = tw<std::int16_t>(twinsync::p::LocalActSpeed);
    V<float> tw_speed_actual_rpm = tw<float>(twinsync::p::SpeedActualRpm);
    V<float> tw_speed_setpoint_rpm = tw<float>(twinsync::p::SpeedSetpointRpm);
    V<std::int32_t> tw_local_ref_pos = tw<std::int32_t>(twinsync::p::LocalRefPos);
    V<std::int32_t> tw_local_act_pos = tw<std::int32_t>(twinsync::p::LocalActPos);
    V<std::int32_t> tw_position_actual = tw<std::int32_t>(twinsync::p::PositionActual);
    V<std::uint16_t> tw_local_eps = tw<std::uint16_t>(twinsync::p::LocalActEps);
    V<std::uint16_t> tw_error_number = tw<std::uint16_t>(twinsync::p::CurrentError, 1);
    V<std::uint16_t> tw_error_location = tw<std::uint16_t>(twinsync::p::CurrentError, 2);
    V<std::uint16_t> controlword = bind(obj::controlword);
    V<std::int8_t> modes = bind(obj::modes_of_operation);
    V<std::int32_t> target_position = bind(obj::target_position);
    V<std::int32_t> target_velocity = bind(obj::target_velocity);
    V<std::int16_t> target_torque = bind(obj::target_torque);
    V<std::int32_t> position_offset = bind(obj::position_offset);
    V<std::int32_t> velocity_offset = bind(obj::velocity_offset);
    V<std::int16_t> torque_offset = bind(obj::torque_offset);
    V<std::uint16_t> probe_function = bind(obj::touch_probe_function);
    V<std::uint32_t> digital_outputs = bind(obj::digital_outputs::physical_outputs);
    V<std::uint32_t> digital_output_mask = bind(obj::digital_outputs::bit_mask);
    V<std::uint16_t> tw_switching_frequency = tw<std::uint16_t>(twinsync::p::SwitchingFrequency);
    // The rest.
    V<std::int16_t> quick_stop_option = bind(obj::quick_stop_option_code);
    V<std::int16_t> shutdown_option = bind(obj::shutdown_option_code);
    V<std::int16_t> disable_operation_option = bind(obj::disable_operation_option_code);
    V<std::int16_t> halt_option = bind(obj::halt_option_code);
    V<std::int16_t> fault_reaction_option = bind(obj::fault_reaction_option_code);
    V<std::uint32_t> following_error_window = bind(obj::following_error_window);
    V<std::uint16_t> following_error_timeout = bind(obj::following_error_time_out);
    V<std::uint32_t> position_window = bind(obj::position_window);
    V<std::uint16_t> position_window_time = bind(obj::position_window_time);
    V<std::uint16_t> velocity_window = bind(obj::velocity_window);
    V<std::uint16_t> velocity_window_time = bind(obj::velocity_window_time);
    V<std::uint16_t> velocity_threshold = bind(obj::velocity_threshold);
    V<std::uint16_t> velocity_threshold_time = bind(obj::velocity_threshold_time);
    V<std::uint16_t> max_torque = bind(obj::max_torque);
    V<std::uint32_t> rated_current = bind(obj::motor_rated_current);
    V<std::uint32_t> rated_torque = bind(obj::motor_rated_torque);
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
    V<std::uint16_t> probe_status = bind(obj::touch_probe_status);
    V<std::int32_t> probe1_positive = bind(obj::touch_probe_1_positive_value);
    V<std::int32_t> probe1_negative = bind(obj::touch_probe_1_negative_value);
    V<std::int32_t> probe2_positive = bind(obj::touch_probe_2_positive_value);
    V<std::int32_t> probe2_negative = bind(obj::touch_probe_2_negative_value);
    // 0x60C2:1 is a UINT8 in CiA 402 and a UINT16 on the HIWIN D2 (DriveStrategy::interpolation).
    V<std::uint16_t> interpolation_value =
        coe::bind<std::uint16_t>(od, obj::interpolation_time_period::index,
                                 obj::interpolation_time_period::value.subindex, coe::Match::Convert);
    V<std::int8_t> interpolation_index = bind(obj::interpolation_time_period::time_index);
    V<std::uint32_t> max_acceleration = bind(obj::max_acceleration);
    V<std::uint32_t> max_deceleration = bind(obj::max_deceleration);
    V<std::uint16_t> positive_torque_limit = bind(obj::positive_torque_limit_value);
    V<std::uint16_t> negative_torque_limit = bind(obj::negative_torque_limit_value);
    // The manufacturer objects of the vecat drive.
    V<std::uint16_t> simulated_fault = mfr_bind(mfr::simulated_fault);
    V<std::uint32_t> velocity_override = mfr_bind(mfr::velocity_override);
    V<std::int32_t> compensation_distance = mfr_bind(mfr::position_compensation::distance);
    V<std::uint32_t> compensation_length = mfr_bind(mfr::position_compensation::length);
    V<std::uint8_t> compensation_start = mfr_bind(mfr::position_compensation::start);
    V<std::uint32_t> compensation_vp = mfr_bind(mfr::position_compensation::process_velocity);
    V<std::uint32_t> compensation_vk = mfr_bind(mfr::position_compensation::velocity_increase);
    V<std::uint32_t> compensation_acc = mfr_bind(mfr::position_compensation::acceleration);
    V<std::uint32_t> compensation_dec = mfr_bind(mfr::position_compensation::deceleration);
    V<std::uint8_t> compensation_stop = mfr_bind(mfr::position_compensation::stop);
    V<std::uint8_t> software_limit_reaction = mfr_bind(mfr::software_limit_reaction);
    V<std::uint8_t> override_type = mfr_bind(mfr::override_type);
    V<std::int32_t> activation_position = mfr_bind(mfr::activation::position);
    V<std::uint32_t> activation_velocity = mfr_bind(mfr::activation::velocity);
    V<std::uint8_t> activation_mode = mfr_bind(mfr::activation::mode);
    V<std::uint32_t> coupling_acc_bound = mfr_bind(mfr::coupling_acc_bound);
    V<std::int32_t> position_range_min = bind(obj::position_range_limit::min);
    V<std::int32_t> position_range_max = bind(obj::position_range_limit::max);
    V<std::uint16_t> positioning_option = bind(obj::positioning_option_code);
    V<std::uint32_t> motor_rotor_inertia = mfr_bind(mfr::motor::rotor_inertia);
    V<std::uint32_t> motor_torque_constant = mfr_bind(mfr::motor::torque_constant);
    V<std::uint32_t> motor_load_inertia = mfr_bind(mfr::motor::load_inertia);
    V<std::uint32_t> motor_viscous_friction = mfr_bind(mfr::motor::viscous_friction);
    V<std::uint32_t> motor_coulomb_friction = mfr_bind(mfr::motor::coulomb_friction);
    V<std::uint32_t> motor_peak_current = mfr_bind(mfr::motor::peak_current);
    V<std::uint32_t> gain_position_kp = mfr_bind(mfr::gains::position_kp);
    V<std::uint32_t> gain_velocity_kp = mfr_bind(mfr::gains::velocity_kp);
    V<std::uint32_t> gain_velocity_ti = mfr_bind(mfr::gains::velocity_ti);
    V<std::uint32_t> gain_current_bandwidth = mfr_bind(mfr::gains::current_bandwidth);
    V<std::int32_t> negative_limit_switch = mfr_bind(mfr::machine::negative_limit_switch);
    V<std::int32_t> positive_limit_switch = mfr_bind(mfr::machine::positive_limit_switch);
    V<std::int32_t> home_switch = mfr_bind(mfr::machine::home_switch);
    V<std::int32_t> index_pulse_offset = mfr_bind(mfr::machine::index_pulse_offset);
    V<std::int16_t> load_torque = mfr_bind(mfr::machine::load_torque);
    V<std::uint8_t> probe_inputs = mfr_bind(mfr::machine::touch_probe_inputs);
    V<std::uint8_t> limit_switch_reaction = mfr_bind(mfr::machine::limit_switch_reaction);
    // TWINsync: the local values the drive provides and the remote values it uses (MSD parameters
    // Pnnnn as objects 0x2000 + nnnn, twinsync/parameters.hpp).
    template <class T>
    V<T> tw(std::uint16_t parameter, std::uint8_t sub = 0) {
        return coe::bind<T>(od, twinsync::object_index(parameter), sub, coe::Match::Convert);
    }
    V<std::uint16_t> tw_control_mode = tw<std::uint16_t>(twinsync::p::ControlMode);
    V<std::uint16_t> tw_setpoint_mode = tw<std::uint16_t>(twinsync::p::SetpointMode);
    V<float> tw_master_torque_tf = tw<float>(twinsync::p::MasterTorqueTF);
    V<std::uint32_t> tw_config = tw<std::uint32_t>(twinsync::p::Config);
    V<std::int16_t> tw_inverted = tw<std::int16_t>(twinsync::p::SlaveInverted);
    V<float> tw_speed_up = tw<float>(twinsync::p::SpeedUp);
    V<float> tw_speed_up_min = tw<float>(twinsync::p::SpeedUpMinimum);
    V<float> tw_act_speed_master = tw<float>(twinsync::p::ActSpeedMaster);
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
    : CoeApplication(d, std::move(objects)),
      variant_(VariantObjects::make(d.drive_variant, dictionary())),
      o_(std::make_unique<Objects>(dictionary(), variant_->vecat_objects())) {
    io_.parameters.strategy = drive_strategy(d.drive_variant);
    simulated_machine(d.drive_variant, io_.parameters);
    for_each_parameter([this](auto& v, auto&) {
        if (v.entry()) v.entry()->hooks().writes = &parameter_writes_;
    });
    for_each_command([this](auto& v, auto&) {
        if (v.entry()) v.entry()->hooks().writes = &command_writes_;
    });
    for (coe::Entry* e : variant_->parameter_entries())
        if (e) e->hooks().writes = &parameter_writes_;
    for (coe::Entry* e : variant_->command_entries())
        if (e) e->hooks().writes = &command_writes_;
    // P0302 and the synchronisation are read with the parameters (configure()).
    if (o_->tw_switching_frequency.bound())
        o_->tw_switching_frequency.entry()->hooks().writes = &parameter_writes_;
    watch_synchronisation(&parameter_writes_);
    variant_->install([this] { core_->zero_position(); });
    core_ = std::make_unique<DriveCore>(motor_from(*o_));
    configure();
    twin_ = std::make_unique<twinsync::Port>(dictionary(), period_ns_);
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
            auto u = [](const coe::Value<std::uint32_t>& v) { return static_cast<double>(v.get_or(0)); };
            core_->compensate(static_cast<double>(o_->compensation_distance.get_or(0)),
                              u(o_->compensation_length),
                              {u(o_->compensation_vk), u(o_->compensation_acc), u(o_->compensation_dec),
                               u(o_->compensation_vp)});
        };
    if (o_->compensation_stop.bound())
        o_->compensation_stop.entry()->hooks().after_download = [this](Entry& e) {
            if (e.get<std::uint8_t>() == 0) return;
            e.set(std::uint8_t{0});
            core_->stop_compensation();
        };
    read_command();
    core_->start(io_);
    write_feedback();
}

Drive::~Drive() {
    // A drive that goes (a slave powered off and rebuilt) leaves its partner with a dead cable, not with a
    // dangling partner.
    if (twin_partner_) twin_partner_->twin_partner_ = nullptr;
}

bool Drive::simulates_faults() {
    return o_->simulated_fault.bound() || !o_->vecat_objects;
}

void Drive::simulate_fault(std::uint16_t code) {
    if (o_->simulated_fault.bound()) return CoeApplication::simulate_fault(code);
    if (!o_->vecat_objects && (code == 0 || fault::injectable(code))) {
        io_.parameters.simulated_fault = code;
        ++parameter_writes_;  // (read_parameters keeps it: there is no object)
    }
}

void Drive::tick(std::uint64_t now_ns) {
    advance(now_ns);
    CoeApplication::tick(now_ns);  // the SYNC supervision and the SDO server's timeout
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
    if (now_ns - sim_ns_ < period_ns_) return;
    Drive* partner = twin_partner_;
    const bool first = !partner || twin_->end() == 0;
    // The dictionary cannot change while the steps run (frames and SDO requests come in between calls).
    // (The synchronisation changes only with a count in parameter_writes_: configure().)
    const bool unread = parameter_writes_ != parameters_read_ || command_writes_ != command_read_;
    configure();
    // Only the last period's feedback values reach the dictionary: nothing reads them in between (the
    // periods before it publish their events only). Coupled drives, and a drive whose TWINsync link is on,
    // publish every period: the partner and the option card's telegram read the objects.
    const bool each = partner || twin_->active();
    // A period that finds the DriveIo's inputs as the last period left them, and the TWINsync link off: the
    // dictionary had no write the drive has not read (entries, process data outputs that changed a byte),
    // the synchronisation and the port's state are the same. A settled core skips it without a look at
    // them; the adapter's work of the period would write what it wrote already. Within this loop that holds
    // after any period that ran with the link off (nothing writes the dictionary in between); for the
    // first, the writes since the last advance are looked at, and the drive must have no TWINsync cable: the
    // port's state in the DriveIo cannot change then (the link is on only with a cable, and what it received
    // moves only while it is on), and the port's status, which its work of a period keeps, has no reader.
    bool unchanged = quiet_ && !unread && parameter_writes_ == parameters_read_ &&
                     command_writes_ == command_read_ && !twin_->channel();
    while (now_ns - sim_ns_ >= period_ns_) {
        sim_ns_ += period_ns_;
        const bool publish = each || now_ns - sim_ns_ < period_ns_;
        if (unchanged && same_probe_inputs() && core_->skip_unchanged_period(io_, publish)) {
            if (publish || io_.feedback.twinsync) write_feedback(publish);
            write_digital_outputs();  // (0x60FE is written by SDO without a count)
            continue;
        }
        if (partner && !first) partner->step_to(sim_ns_);
        servo_step(publish);
        if (partner && first) partner->step_to(sim_ns_);
        unchanged = !partner && !twin_->active() && parameter_writes_ == parameters_read_ &&
                    command_writes_ == command_read_;
    }
    quiet_ = unchanged;
}

// The touch probe inputs of a wire or signal (wired_probe_inputs) are what the DriveIo holds.
bool Drive::same_probe_inputs() {
    const auto wired = wired_probe_inputs(sim_ns_);
    return !wired ||
           static_cast<std::uint8_t>(probe_inputs_object_ | (*wired & 3u)) == io_.parameters.probe_inputs;
}

void Drive::step_to(std::uint64_t t_ns) {
    if (!started_) {
        started_ = true;
        sim_ns_ = t_ns;
        return;
    }
    if (t_ns > sim_ns_ + 200'000'000) sim_ns_ = t_ns - 200'000'000;
    if (sim_ns_ + period_ns_ <= t_ns) configure();
    while (sim_ns_ + period_ns_ <= t_ns) {
        sim_ns_ += period_ns_;
        servo_step();
    }
}

// One servo period: the TWINsync telegram of the partner's last cycle (its receive mapping writes
// parameters), the set-points, the core's step, the feedback, and this drive's telegram.
void Drive::servo_step(bool publish) {
    twin_->receive(sim_ns_, twinsync_local());
    // (A receive mapping may write parameters, the manufacturer objects 0x2000 + P: read again.)
    if (parameter_writes_ != parameters_read_) read_parameters();
    if (command_writes_ != command_read_) read_command();
    if (const auto wired = wired_probe_inputs(sim_ns_))
        io_.parameters.probe_inputs = static_cast<std::uint8_t>(probe_inputs_object_ | (*wired & 3u));
    read_twinsync();
    core_->step(io_, publish);
    write_feedback(publish);
    write_digital_outputs();
    twin_->set_error(core_->twinsync_error());
    twin_->transmit(sim_ns_, twinsync_local());
}

void Drive::write_digital_outputs() {
    if (!digital_output_image_.empty())
        st_le32(digital_output_image_.data(),
                o_->digital_outputs.get_or(0) & o_->digital_output_mask.get_or(0));
}

// The drive's state for its option card (only while TWINsync is on).
twinsync::LocalState Drive::twinsync_local() const {
    if (!twin_->active()) return {};
    return core_->twinsync_local(o_->controlword.get_or(0), io_.parameters.fieldbus_synchronised);
}

// Every parameter of the DriveIo with its handle, once: read_parameters() copies them, the constructor
// watches them (a write through Entry::set/assign counts in parameter_writes_), configure() finds those
// mapped into the RxPDOs.
template <class F>
void Drive::for_each_parameter(F&& f) {
    Objects& o = *o_;
    DriveParameters& p = io_.parameters;
    f(o.quick_stop_option, p.options.quick_stop);
    f(o.shutdown_option, p.options.shutdown);
    f(o.disable_operation_option, p.options.disable_operation);
    f(o.halt_option, p.options.halt);
    f(o.fault_reaction_option, p.options.fault_reaction);
    f(o.encoder_increments, p.factors.encoder_increments);
    f(o.encoder_revolutions, p.factors.motor_revolutions);
    f(o.gear_motor, p.factors.gear_motor_revolutions);
    f(o.gear_shaft, p.factors.gear_shaft_revolutions);
    f(o.feed, p.factors.feed);
    f(o.feed_shaft, p.factors.feed_shaft_revolutions);
    f(o.rated_current, p.rated_current);
    f(o.rated_torque, p.rated_torque);
    f(o.following_error_window, p.following_error_window);
    f(o.following_error_timeout, p.following_error_timeout);
    f(o.position_window, p.position_window);
    f(o.position_window_time, p.position_window_time);
    f(o.velocity_window, p.velocity_window);
    f(o.velocity_window_time, p.velocity_window_time);
    f(o.velocity_threshold, p.velocity_threshold);
    f(o.velocity_threshold_time, p.velocity_threshold_time);
    f(o.max_torque, p.max_torque);
    f(o.positive_torque_limit, p.positive_torque_limit);
    f(o.negative_torque_limit, p.negative_torque_limit);
    f(o.max_profile_velocity, p.max_profile_velocity);
    f(o.max_motor_speed, p.max_motor_speed);
    f(o.profile_velocity, p.profile_velocity);
    f(o.profile_acceleration, p.profile_acceleration);
    f(o.profile_deceleration, p.profile_deceleration);
    f(o.quick_stop_deceleration, p.quick_stop_deceleration);
    f(o.max_acceleration, p.max_acceleration);
    f(o.max_deceleration, p.max_deceleration);
    f(o.motion_profile_type, p.motion_profile_type);
    f(o.profile_jerk, p.profile_jerk);
    f(o.torque_slope, p.torque_slope);
    f(o.software_limit_min, p.software_limit_min);
    f(o.software_limit_max, p.software_limit_max);
    f(o.home_offset, p.home_offset);
    f(o.homing_method, p.homing_method);
    f(o.homing_speed_switch, p.homing_speed_switch);
    f(o.homing_speed_zero, p.homing_speed_zero);
    f(o.homing_acceleration, p.homing_acceleration);
    f(o.interpolation_value, p.interpolation_value);
    f(o.interpolation_index, p.interpolation_index);
    f(o.gain_position_kp, p.gain_position_kp);
    f(o.gain_velocity_kp, p.gain_velocity_kp);
    f(o.gain_velocity_ti, p.gain_velocity_ti);
    f(o.gain_current_bandwidth, p.gain_current_bandwidth);
    f(o.negative_limit_switch, p.negative_limit_switch);
    f(o.positive_limit_switch, p.positive_limit_switch);
    f(o.home_switch, p.home_switch);
    f(o.index_pulse_offset, p.index_pulse_offset);
    f(o.load_torque, p.load_torque);
    f(o.probe_inputs, p.probe_inputs);
    f(o.limit_switch_reaction, p.limit_switch_reaction);
    f(o.simulated_fault, p.simulated_fault);
    f(o.velocity_override, p.velocity_override);
    f(o.software_limit_reaction, p.software_limit_reaction);
    f(o.override_type, p.override_type);
    f(o.activation_position, p.activation_position);
    f(o.activation_velocity, p.activation_velocity);
    f(o.activation_mode, p.activation_mode);
    f(o.coupling_acc_bound, p.coupling_acc_bound);
    f(o.position_range_min, p.position_range_min);
    f(o.position_range_max, p.position_range_max);
    f(o.positioning_option, p.positioning_option);
    // The local TWINsync references (P2602), written with the parameters.
    f(o.tw_local_torque_ref, io_.twinsync.local_torque_reference);
    f(o.tw_local_speed_ref, io_.twinsync.local_speed_reference);
}

void Drive::read_parameters() {
    parameters_read_ = parameter_writes_;
    // An absent object leaves the field at its default (drive_io.hpp); an absent software limit is empty.
    for_each_parameter([]<class T, class V>(const coe::Value<T>& v, V& field) {
        if constexpr (std::is_same_v<V, std::optional<T>>) {
            if (v.bound()) field = v.get();
        } else {
            field = v.get_or(field);
        }
    });
    variant_->read_parameters(io_.parameters);
    probe_inputs_object_ = io_.parameters.probe_inputs;
}

void Drive::configure() {
    // Process data outputs write the entries they map without Entry::set: the command, and a parameter
    // mapped into the RxPDOs, count as written whenever the outputs were copied.
    const coe::ProcessDataMap& pd = process_data();
    if (pd.mapping_changes() != mapping_seen_) {
        mapping_seen_ = pd.mapping_changes();
        maps_parameters_ = false;
        for_each_parameter([&](auto& v, auto&) {
            if (v.entry() && pd.is_rx_mapped(*v.entry())) maps_parameters_ = true;
        });
        if (const coe::Entry* e = o_->tw_switching_frequency.entry(); e && pd.is_rx_mapped(*e))
            maps_parameters_ = true;
    }
    if (pd.outputs_changed() != outputs_seen_) {
        outputs_seen_ = pd.outputs_changed();
        ++command_writes_;
        if (maps_parameters_) ++parameter_writes_;
    }
    // The rest only when a parameter was written since they were read, or the AL state changed (the
    // synchronisation changes only then: watch_synchronisation; P0302 counts as a parameter): a run that
    // finds nothing written looks at none of their cache lines.
    if (parameter_writes_ == parameters_read_) return;
    const bool dc = dc_mode();
    // A device that takes its interpolation period from SYNC0 (HIWIN 9.1.2) writes it now.
    if (variant_->synchronised(dc ? static_cast<std::uint32_t>(cycle_time_ns()) : 0)) ++parameter_writes_;
    io_.parameters.fieldbus_synchronised = dc;
    // The parameters, and the core's settings that follow from them (DriveCore::configure reads nothing
    // else).
    read_parameters();
    core_->configure(io_);
    // The servo period is the speed control's sampling time, the TWIN sampling time of the switching
    // frequency P0302 (TWINsync specification chapter 2: 250 us, 125 us at 8 kHz); the option card
    // exchanges its telegram in the same cycle. A device without P0302 keeps 250 us. Worked out again
    // when P0302 changed.
    const std::uint32_t switching =
        o_->tw_switching_frequency.bound() ? o_->tw_switching_frequency.get() : kNoSwitchingFrequency;
    if (switching == switching_seen_) return;
    switching_seen_ = switching;
    const auto period =
        switching != kNoSwitchingFrequency
            ? twinsync::sampling_time_ns(static_cast<std::uint8_t>(switching)).value_or(kServoPeriodNs)
            : kServoPeriodNs;
    if (period != period_ns_) {
        period_ns_ = period;
        core_->set_period_ns(period);
        if (twin_) twin_->set_period_ns(period);
    }
}

template <class F>
void Drive::for_each_command(F&& f) {
    Objects& o = *o_;
    DriveCommand& c = io_.command;
    f(o.controlword, c.controlword);
    f(o.modes, c.mode);
    f(o.target_position, c.target_position);
    f(o.target_velocity, c.target_velocity);
    f(o.target_torque, c.target_torque);
    f(o.position_offset, c.position_offset);
    f(o.velocity_offset, c.velocity_offset);
    f(o.torque_offset, c.torque_offset);
    f(o.probe_function, c.probe_function);
}

void Drive::read_command() {
    command_read_ = command_writes_;
    // An absent object leaves the field at its default.
    for_each_command([](const auto& v, auto& field) { field = v.get_or(field); });
    variant_->read_command(io_.command);
}

void Drive::read_twinsync() {
    const Objects& o = *o_;
    const twinsync::Port& port = *twin_;
    TwinsyncInputs& t = io_.twinsync;
    t.active = port.active();
    t.follows = port.follows();
    t.has_data = port.has_data();
    t.fresh = port.received_fresh();
    t.controlled_by_twinsync = port.controlled_by_twinsync();
    t.received_control_word = port.received_control_word();
    t.pending_error = port.pending_error();
    if (!t.active) return;  // the rest matters only while the link is on
    t.link_ok = port.link_ok();
    t.role = port.role();
    t.partner_role = port.partner().mode;
    t.partner_enabled = port.partner_enabled();
    t.mode = port.mode();
    t.control_mode = o.tw_control_mode.get_or(3);
    t.config = o.tw_config.get_or(0);
    t.inverted = o.tw_inverted.get_or(1);
    t.speed_up = o.tw_speed_up.get_or(0.0f);
    t.speed_up_minimum = o.tw_speed_up_min.get_or(0.0f);
    t.act_speed_master = o.tw_act_speed_master.get_or(0.0f);
    t.remote_torque_reference = o.tw_remote_torque_ref.get_or(1.0f);
    t.remote_speed_reference = o.tw_remote_speed_ref.get_or(1.0f);
    t.remote_ref_torque = o.tw_remote_ref_torque.get_or(0);
    t.remote_act_torque = o.tw_remote_act_torque.get_or(0);
    t.remote_ref_speed = o.tw_remote_ref_speed.get_or(0);
    t.remote_act_speed = o.tw_remote_act_speed.get_or(0);
    t.remote_ref_pos = o.tw_remote_ref_pos.get_or(0);
    t.remote_act_pos = o.tw_remote_act_pos.get_or(0);
    t.local_resolution = o.tw_local_resolution.get_or(1);
    t.remote_resolution = o.tw_remote_resolution.get_or(1);
    t.gear_numerator = o.tw_gear_numerator.get_or(1);
    t.gear_denominator = o.tw_gear_denominator.get_or(1);
    t.master_torque_tf = o.tw_master_torque_tf.get_or(0.0f);
}

void Drive::write_feedback(bool publish) {
    Objects& o = *o_;
    DriveFeedback& f = io_.feedback;
    // The faults of the period, in the order they happened.
    if (f.raised) raise_fault(f.raised->code, f.raised->register_bits, f.raised->data);
    if (f.cleared) clear_faults();
    if (f.probe) {
        coe::Value<std::int32_t>* values[2][2] = {{&o.probe1_positive, &o.probe1_negative},
                                                  {&o.probe2_positive, &o.probe2_negative}};
        for (int n = 0; n < 2; ++n)
            for (int edge = 0; edge < 2; ++edge)
                if (f.probe_latched.set[n][edge]) {
                    // Without an object of its own (HIWIN 10: "Latch Position is always stored to the Touch
                    // Probe Position Value (0x60BA)") the negative edge's value goes to the positive's.
                    auto* to = values[n][edge]->bound() ? values[n][edge] : values[n][0];
                    to->set(f.probe_latched.value[n][edge]);
                }
        o.probe_status.set(f.probe_status);
    }
    if (publish) {
        o.digital_inputs.set(f.digital_inputs);
        o.statusword.set(f.statusword);
        o.modes_display.set(f.mode_display);
        o.position_demand.set(f.position_demand);
        o.position_demand_internal.set(f.position_demand_internal);
        o.position_internal.set(f.position_internal);
        o.position_actual.set(f.position_actual);
        o.following_error_actual.set(f.following_error);
        o.velocity_demand.set(f.velocity_demand);
        o.velocity_actual.set(f.velocity_actual);
        o.torque_demand.set(f.torque_demand);
        o.torque_actual.set(f.torque_actual);
        o.current_actual.set(f.current_actual);
        o.temperature.set(f.temperature);
    }
    // The variant's objects: its events, and values of the last published feedback.
    variant_->write_feedback(io_);
    if (f.twinsync) write_twinsync_values();
}

void Drive::write_twinsync_values() {
    Objects& o = *o_;
    const TwinsyncValues& v = io_.feedback.twinsync_values;
    o.tw_local_ref_torque.set(v.ref_torque);
    o.tw_local_act_torque.set(v.act_torque);
    o.tw_torque_actual_scaled.set(v.act_torque);
    o.tw_local_ref_speed.set(v.ref_speed);
    o.tw_local_ff_speed.set(v.ref_speed);
    o.tw_local_act_speed.set(v.act_speed);
    o.tw_speed_actual_rpm.set(v.speed_actual_rpm);
    o.tw_speed_setpoint_rpm.set(v.speed_setpoint_rpm);
    o.tw_local_ref_pos.set(v.ref_pos);
    o.tw_local_act_pos.set(v.act_pos);
    o.tw_position_actual.set(v.act_pos);
    o.tw_local_eps.set(v.eps);
    // P2650: the drive's own current error, unless the receive mapping brings the slave's (TWD, SCON,
    // PCON, VE masters: "interpreted as the error of the slave drive").
    if (!twin_->receives(twinsync::p::CurrentError)) {
        o.tw_error_number.set(v.error_number);
        o.tw_error_location.set(v.error_location);
    }
}

}  // namespace vecat::cia402
