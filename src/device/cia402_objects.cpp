// The CiA 402 (IEC 61800-7-201) objects of the vecat drive, as described data. Their behaviour lives in
// src/cia402; this file only says which objects exist, their types, access, limits and defaults.
#include "protocol/cia402_objects.hpp"
#include "device/device_description.hpp"
#include "device/drive_objects.hpp"

namespace vecat::device {
namespace {

using DT = DataType;

namespace obj = protocol::obj;

ObjectDescription named_array(std::uint16_t index, const char* name, DT t, std::uint16_t acc,
                              std::vector<std::pair<const char*, std::int64_t>> elems) {
    std::vector<std::int64_t> defs;
    for (const auto& e : elems)
        defs.push_back(e.second);
    auto o = make_array(index, name, t, acc, defs);
    for (std::size_t i = 0; i < elems.size(); ++i)
        o.entries[i + 1].name = elems[i].first;
    return o;
}

}  // namespace

std::vector<ObjectDescription> cia402_drive_objects() {
    namespace a = access;
    constexpr std::uint16_t RW = a::RW;
    constexpr std::uint16_t RWM = a::RxMap;  // read/write, RxPDO-mappable
    constexpr std::uint16_t ROM = a::TxMap;  // read-only, TxPDO-mappable
    constexpr std::int64_t kI32Max = 2147483647;
    constexpr std::int64_t kI32Min = -kI32Max - 1;
    std::vector<ObjectDescription> o;

    // Manufacturer area: the simulated motor and a few diagnostic values.
    o.push_back(make_record(mfr::motor::index, "Motor parameters",
                            {make_entry(mfr::motor::rated_speed, "Rated speed (rpm)", RW, 3000),
                             make_entry(mfr::motor::rotor_inertia, "Rotor inertia (g cm2)", RW, 120),
                             make_entry(mfr::motor::torque_constant, "Torque constant (mNm/A)", RW, 600),
                             make_entry(mfr::motor::load_inertia, "Load inertia (g cm2)", RW, 240),
                             make_entry(mfr::motor::viscous_friction, "Viscous friction (uNm s/rad)", RW, 50),
                             make_entry(mfr::motor::coulomb_friction, "Coulomb friction (mNm)", RW, 10),
                             make_entry(mfr::motor::peak_current, "Peak current (mA)", RW, 9000)}));
    // Gains of the cascaded loops; 0 = tuned from the motor parameters when the drive is enabled.
    o.push_back(
        make_record(mfr::gains::index, "Control loop gains",
                    {make_entry(mfr::gains::position_kp, "Position loop gain (0.01/s)", RW, 0),
                     make_entry(mfr::gains::velocity_kp, "Velocity loop gain (uNm s/rad)", RW, 0),
                     make_entry(mfr::gains::velocity_ti, "Velocity loop integral time (us)", RW, 0),
                     make_entry(mfr::gains::current_bandwidth, "Current loop bandwidth (rad/s)", RW, 0)}));
    // The simulated machine around the motor: switches (in increments of the machine position, which
    // homing does not move), the index pulse, an external load, the touch probe inputs.
    {
        namespace m = mfr::machine;
        auto r = make_record(
            m::index, "Simulated machine",
            {make_entry(m::negative_limit_switch, "Negative limit switch (inc)", RW, -(100ll << 20)),
             make_entry(m::positive_limit_switch, "Positive limit switch (inc)", RW, 100ll << 20),
             make_entry(m::home_switch, "Home switch (inc)", RW, 5ll << 20),
             make_entry(m::index_pulse_offset, "Index pulse offset (inc)", RW, 0),
             make_entry(m::load_torque, "Load torque (0.1 %)", RWM, 0),
             make_entry(m::touch_probe_inputs, "Touch probe inputs", RWM, 0),
             make_entry(m::limit_switch_reaction, "Limit switch reaction", RW, 0)});
        set_range(r.entries[m::limit_switch_reaction.subindex], 0, 1);
        o.push_back(r);
    }
    // Fault injection: the error code (0x603F) of a fault condition to simulate (0 = none).
    o.push_back(make_var(mfr::simulated_fault, "Simulated fault", RWM, 0));
    // TwinCAT NC PTP online changes as manufacturer functions of the profile modes.
    o.push_back(
        make_ranged_var(mfr::velocity_override, "Velocity override (ppm)", RWM, 1'000'000, 0, 1'000'000));
    {
        namespace pc = mfr::position_compensation;
        o.push_back(make_record(pc::index, "Position compensation",
                                {make_entry(pc::distance, "Compensation distance", RW, 0),
                                 make_entry(pc::length, "Compensation length", RW, 0),
                                 make_entry(pc::start, "Start compensation", RW, 0),
                                 make_entry(pc::process_velocity, "Process velocity", RW, 0),
                                 make_entry(pc::velocity_increase, "Velocity increase", RW, 0),
                                 make_entry(pc::acceleration, "Compensation acceleration", RW, 0),
                                 make_entry(pc::deceleration, "Compensation deceleration", RW, 0),
                                 make_entry(pc::stop, "Stop compensation", RW, 0)}));
    }
    o.push_back(make_ranged_var(mfr::software_limit_reaction, "Software limit reaction", RW, 0, 0, 2));
    o.push_back(make_ranged_var(mfr::override_type, "Override type", RW, 4, 1, 4));
    o.push_back(make_record(mfr::activation::index, "New velocity at activation position",
                            {make_entry(mfr::activation::position, "Activation position", RW, 0),
                             make_entry(mfr::activation::velocity, "New velocity", RW, 0),
                             make_entry(mfr::activation::mode, "Activation mode", RW, 0)}));
    o.push_back(make_var(mfr::coupling_acc_bound, "Coupling factor acceleration bound (units/s^2)", RW, 0));
    o.push_back(make_var(mfr::drive_temperature, "Drive temperature (0.1 C)", ROM, 350));
    o.push_back(make_var(mfr::dc_bus_voltage, "DC bus voltage (0.1 V)", ROM, 3250));
    {
        auto s = make_string_var(mfr::user_label.index, "User label", "axis");
        s.entries[0].bit_length = 8 * 32;
        s.entries[0].access = RW;
        o.push_back(s);
    }
    {
        // A large read-only value (served by segmented upload).
        ObjectDescription d;
        d.index = mfr::diagnosis_history.index;
        d.name = "Diagnosis history";
        d.code = ObjectCode::Var;
        d.type = DT::OctetString;
        EntryDescription e;
        e.subindex = 0;
        e.name = d.name;
        e.type = DT::OctetString;
        e.bit_length = 8 * 512;
        e.access = a::RO;
        e.default_value.assign(512, 0);
        d.entries.push_back(e);
        o.push_back(d);
    }

    // Device control (CiA 402 part 2, section 8).
    o.push_back(make_var(obj::error_code, "Error code", ROM));
    o.push_back(make_var(obj::controlword, "Controlword", RWM));
    o.push_back(make_var(obj::statusword, "Statusword", ROM));
    o.push_back(make_ranged_var(obj::quick_stop_option_code, "Quick stop option code", RW, 2, 0, 8));
    o.push_back(make_ranged_var(obj::shutdown_option_code, "Shutdown option code", RW, 0, -1, 1));
    o.push_back(
        make_ranged_var(obj::disable_operation_option_code, "Disable operation option code", RW, 1, -1, 1));
    o.push_back(make_ranged_var(obj::halt_option_code, "Halt option code", RW, 1, 1, 4));
    o.push_back(make_ranged_var(obj::fault_reaction_option_code, "Fault reaction option code", RW, 2, 0, 4));
    o.push_back(make_ranged_var(obj::modes_of_operation, "Modes of operation", RWM, 8, -128, 127));
    o.push_back(make_var(obj::modes_of_operation_display, "Modes of operation display", ROM));

    // Position control function and factors.
    o.push_back(make_var(obj::position_demand_value, "Position demand value", ROM));
    o.push_back(make_var(obj::position_actual_internal_value, "Position actual internal value", ROM));
    o.push_back(make_var(obj::position_actual_value, "Position actual value", ROM));
    o.push_back(make_var(obj::following_error_window, "Following error window", RWM, 100000));
    o.push_back(make_var(obj::following_error_time_out, "Following error time out", RW, 10));
    o.push_back(make_var(obj::position_window, "Position window", RWM, 100));
    o.push_back(make_var(obj::position_window_time, "Position window time", RW, 10));
    o.push_back(make_var(obj::velocity_demand_value, "Velocity demand value", ROM));
    o.push_back(make_var(obj::velocity_actual_value, "Velocity actual value", ROM));
    o.push_back(make_var(obj::velocity_window, "Velocity window", RW, 100));
    o.push_back(make_var(obj::velocity_window_time, "Velocity window time", RW, 10));
    o.push_back(make_var(obj::velocity_threshold, "Velocity threshold", RW, 10));
    o.push_back(make_var(obj::velocity_threshold_time, "Velocity threshold time", RW, 10));
    o.push_back(make_var(obj::target_torque, "Target torque", RWM));
    o.push_back(make_var(obj::max_torque, "Max torque", RWM, 3000));
    o.push_back(make_var(obj::torque_demand, "Torque demand", ROM));
    o.push_back(make_var(obj::motor_rated_current, "Motor rated current", RW, 3000));
    o.push_back(make_var(obj::motor_rated_torque, "Motor rated torque", RW, 1270));
    o.push_back(make_var(obj::torque_actual_value, "Torque actual value", ROM));
    o.push_back(make_var(obj::current_actual_value, "Current actual value", ROM));
    o.push_back(make_var(obj::target_position, "Target position", RWM));
    o.push_back(named_array(obj::position_range_limit::index, "Position range limit", DT::Integer32, RW,
                            {{"Min position range limit", kI32Min}, {"Max position range limit", kI32Max}}));
    o.push_back(make_var(obj::home_offset, "Home offset", RWM));
    o.push_back(named_array(obj::software_position_limit::index, "Software position limit", DT::Integer32, RW,
                            {{"Min position limit", kI32Min}, {"Max position limit", kI32Max}}));
    o.push_back(make_var(obj::polarity, "Polarity", RW));
    o.push_back(make_var(obj::max_profile_velocity, "Max profile velocity", RWM, 10'000'000));
    o.push_back(make_var(obj::max_motor_speed, "Max motor speed", RW, 5000));
    o.push_back(make_var(obj::profile_velocity, "Profile velocity", RWM, 1'000'000));
    o.push_back(make_var(obj::end_velocity, "End velocity", RWM));
    o.push_back(make_var(obj::profile_acceleration, "Profile acceleration", RWM, 10'000'000));
    o.push_back(make_var(obj::profile_deceleration, "Profile deceleration", RWM, 10'000'000));
    o.push_back(make_var(obj::quick_stop_deceleration, "Quick stop deceleration", RWM, 50'000'000));
    o.push_back(make_ranged_var(obj::motion_profile_type, "Motion profile type", RW, 0, -1, 3));
    o.push_back(make_var(obj::torque_slope, "Torque slope", RWM, 10000));
    o.push_back(make_var(obj::torque_profile_type, "Torque profile type", RW, 0));
    o.push_back(named_array(obj::position_encoder_resolution::index, "Position encoder resolution",
                            DT::Unsigned32, RW, {{"Encoder increments", 1 << 20}, {"Motor revolutions", 1}}));
    o.push_back(named_array(obj::gear_ratio::index, "Gear ratio", DT::Unsigned32, RW,
                            {{"Motor revolutions", 1}, {"Shaft revolutions", 1}}));
    o.push_back(named_array(obj::feed_constant::index, "Feed constant", DT::Unsigned32, RW,
                            {{"Feed", 1 << 20}, {"Shaft revolutions", 1}}));

    // Homing.
    o.push_back(make_ranged_var(obj::homing_method, "Homing method", RWM, 35, -128, 127));
    o.push_back(
        named_array(obj::homing_speeds::index, "Homing speeds", DT::Unsigned32, RW,
                    {{"Speed during search for switch", 100000}, {"Speed during search for zero", 10000}}));
    o.push_back(make_var(obj::homing_acceleration, "Homing acceleration", RWM, 1'000'000));
    o.push_back(named_array(obj::profile_jerk::index, "Profile jerk", DT::Unsigned32, RW,
                            {{"Profile jerk 1", 1'000'000'000}}));

    // Cyclic modes: offsets, touch probe, interpolation period.
    o.push_back(make_var(obj::position_offset, "Position offset", RWM));
    o.push_back(make_var(obj::velocity_offset, "Velocity offset", RWM));
    o.push_back(make_var(obj::torque_offset, "Torque offset", RWM));
    o.push_back(make_var(obj::touch_probe_function, "Touch probe function", RWM));
    o.push_back(make_var(obj::touch_probe_status, "Touch probe status", ROM));
    o.push_back(make_var(obj::touch_probe_1_positive_value, "Touch probe 1 positive value", ROM));
    o.push_back(make_var(obj::touch_probe_1_negative_value, "Touch probe 1 negative value", ROM));
    o.push_back(make_var(obj::touch_probe_2_positive_value, "Touch probe 2 positive value", ROM));
    o.push_back(make_var(obj::touch_probe_2_negative_value, "Touch probe 2 negative value", ROM));
    {
        auto r = make_record(
            obj::interpolation_time_period::index, "Interpolation time period",
            {make_entry(obj::interpolation_time_period::value, "Interpolation time period value", RW, 1),
             make_entry(obj::interpolation_time_period::time_index, "Interpolation time index", RW, -3)});
        set_range(r.entries[2], -6, 63);
        o.push_back(r);
    }
    o.push_back(make_var(obj::max_acceleration, "Max acceleration", RW, 100'000'000));
    o.push_back(make_var(obj::max_deceleration, "Max deceleration", RW, 100'000'000));
    o.push_back(make_var(obj::positive_torque_limit_value, "Positive torque limit value", RWM, 3000));
    o.push_back(make_var(obj::negative_torque_limit_value, "Negative torque limit value", RWM, 3000));
    o.push_back(make_var(obj::positioning_option_code, "Positioning option code", RW, 0));
    o.push_back(make_var(obj::following_error_actual_value, "Following error actual value", ROM));
    o.push_back(make_var(obj::position_demand_internal_value, "Position demand internal value", ROM));
    o.push_back(make_var(obj::digital_inputs, "Digital inputs", ROM));
    o.push_back(named_array(obj::digital_outputs::index, "Digital outputs", DT::Unsigned32, RWM,
                            {{"Physical outputs", 0}, {"Bit mask", 0}}));
    o.push_back(make_var(obj::target_velocity, "Target velocity", RWM));
    // Supported drive modes: PP (bit 0), PV (2), PT (3), HM (5), CSP (7), CSV (8), CST (9).
    o.push_back(make_var(obj::supported_drive_modes, "Supported drive modes", a::RO, 0x000003AD));
    return o;
}

}  // namespace vecat::device
