// The object catalogue, drive profile area: the CiA 402 (IEC 61800-7-201, clause 6 and the object
// definitions of IEC 61800-7-201 Annex/CiA 402-2) objects the vecat drive implements, named with their
// index, subindex and data type. The descriptions (names, access, limits, defaults) are in
// src/device/cia402_objects.cpp; the behaviour in src/cia402.
#pragma once

#include "protocol/objects.hpp"

namespace vecat::protocol::obj {

// Device control (6.3 and 6.5).
inline constexpr ObjectId<DT::Unsigned16> error_code{0x603F};
inline constexpr ObjectId<DT::Unsigned16> controlword{0x6040};
inline constexpr ObjectId<DT::Unsigned16> statusword{0x6041};
inline constexpr ObjectId<DT::Integer16> quick_stop_option_code{0x605A};
inline constexpr ObjectId<DT::Integer16> shutdown_option_code{0x605B};
inline constexpr ObjectId<DT::Integer16> disable_operation_option_code{0x605C};
inline constexpr ObjectId<DT::Integer16> halt_option_code{0x605D};
inline constexpr ObjectId<DT::Integer16> fault_reaction_option_code{0x605E};
inline constexpr ObjectId<DT::Integer8> modes_of_operation{0x6060};
inline constexpr ObjectId<DT::Integer8> modes_of_operation_display{0x6061};

// Position control function, profile parameters and factors (6.7, 6.9, 6.2).
inline constexpr ObjectId<DT::Integer32> position_demand_value{0x6062};
inline constexpr ObjectId<DT::Integer32> position_actual_internal_value{0x6063};
inline constexpr ObjectId<DT::Integer32> position_actual_value{0x6064};
inline constexpr ObjectId<DT::Unsigned32> following_error_window{0x6065};
inline constexpr ObjectId<DT::Unsigned16> following_error_time_out{0x6066};
inline constexpr ObjectId<DT::Unsigned32> position_window{0x6067};
inline constexpr ObjectId<DT::Unsigned16> position_window_time{0x6068};
inline constexpr ObjectId<DT::Integer32> velocity_demand_value{0x606B};
inline constexpr ObjectId<DT::Integer32> velocity_actual_value{0x606C};
inline constexpr ObjectId<DT::Unsigned16> velocity_window{0x606D};
inline constexpr ObjectId<DT::Unsigned16> velocity_window_time{0x606E};
inline constexpr ObjectId<DT::Unsigned16> velocity_threshold{0x606F};
inline constexpr ObjectId<DT::Unsigned16> velocity_threshold_time{0x6070};
inline constexpr ObjectId<DT::Integer16> target_torque{0x6071};
inline constexpr ObjectId<DT::Unsigned16> max_torque{0x6072};
inline constexpr ObjectId<DT::Integer16> torque_demand{0x6074};
inline constexpr ObjectId<DT::Unsigned32> motor_rated_current{0x6075};
inline constexpr ObjectId<DT::Unsigned32> motor_rated_torque{0x6076};
inline constexpr ObjectId<DT::Integer16> torque_actual_value{0x6077};
inline constexpr ObjectId<DT::Integer16> current_actual_value{0x6078};
inline constexpr ObjectId<DT::Integer32> target_position{0x607A};
namespace position_range_limit {
inline constexpr std::uint16_t index = 0x607B;
inline constexpr ObjectId<DT::Integer32> min{index, 1};
inline constexpr ObjectId<DT::Integer32> max{index, 2};
}  // namespace position_range_limit
inline constexpr ObjectId<DT::Integer32> home_offset{0x607C};
namespace software_position_limit {
inline constexpr std::uint16_t index = 0x607D;
inline constexpr ObjectId<DT::Integer32> min{index, 1};
inline constexpr ObjectId<DT::Integer32> max{index, 2};
}  // namespace software_position_limit
inline constexpr ObjectId<DT::Unsigned8> polarity{0x607E};
inline constexpr ObjectId<DT::Unsigned32> max_profile_velocity{0x607F};
inline constexpr ObjectId<DT::Unsigned32> max_motor_speed{0x6080};
inline constexpr ObjectId<DT::Unsigned32> profile_velocity{0x6081};
inline constexpr ObjectId<DT::Unsigned32> end_velocity{0x6082};
inline constexpr ObjectId<DT::Unsigned32> profile_acceleration{0x6083};
inline constexpr ObjectId<DT::Unsigned32> profile_deceleration{0x6084};
inline constexpr ObjectId<DT::Unsigned32> quick_stop_deceleration{0x6085};
inline constexpr ObjectId<DT::Integer16> motion_profile_type{0x6086};
inline constexpr ObjectId<DT::Unsigned32> torque_slope{0x6087};
inline constexpr ObjectId<DT::Integer16> torque_profile_type{0x6088};
namespace position_encoder_resolution {
inline constexpr std::uint16_t index = 0x608F;
inline constexpr ObjectId<DT::Unsigned32> encoder_increments{index, 1};
inline constexpr ObjectId<DT::Unsigned32> motor_revolutions{index, 2};
}  // namespace position_encoder_resolution
namespace gear_ratio {
inline constexpr std::uint16_t index = 0x6091;
inline constexpr ObjectId<DT::Unsigned32> motor_revolutions{index, 1};
inline constexpr ObjectId<DT::Unsigned32> shaft_revolutions{index, 2};
}  // namespace gear_ratio
namespace feed_constant {
inline constexpr std::uint16_t index = 0x6092;
inline constexpr ObjectId<DT::Unsigned32> feed{index, 1};
inline constexpr ObjectId<DT::Unsigned32> shaft_revolutions{index, 2};
}  // namespace feed_constant

// Homing (6.6).
inline constexpr ObjectId<DT::Integer8> homing_method{0x6098};
namespace homing_speeds {
inline constexpr std::uint16_t index = 0x6099;
inline constexpr ObjectId<DT::Unsigned32> search_for_switch{index, 1};
inline constexpr ObjectId<DT::Unsigned32> search_for_zero{index, 2};
}  // namespace homing_speeds
inline constexpr ObjectId<DT::Unsigned32> homing_acceleration{0x609A};
namespace profile_jerk {
inline constexpr std::uint16_t index = 0x60A4;
inline constexpr ObjectId<DT::Unsigned32> jerk_1{index, 1};
}  // namespace profile_jerk

// Cyclic synchronous modes (6.10-6.12): offsets, touch probe, interpolation period.
inline constexpr ObjectId<DT::Integer32> position_offset{0x60B0};
inline constexpr ObjectId<DT::Integer32> velocity_offset{0x60B1};
inline constexpr ObjectId<DT::Integer16> torque_offset{0x60B2};
inline constexpr ObjectId<DT::Unsigned16> touch_probe_function{0x60B8};
inline constexpr ObjectId<DT::Unsigned16> touch_probe_status{0x60B9};
inline constexpr ObjectId<DT::Integer32> touch_probe_1_positive_value{0x60BA};
inline constexpr ObjectId<DT::Integer32> touch_probe_1_negative_value{0x60BB};
inline constexpr ObjectId<DT::Integer32> touch_probe_2_positive_value{0x60BC};
inline constexpr ObjectId<DT::Integer32> touch_probe_2_negative_value{0x60BD};
namespace interpolation_time_period {
inline constexpr std::uint16_t index = 0x60C2;
inline constexpr ObjectId<DT::Unsigned8> value{index, 1};
inline constexpr ObjectId<DT::Integer8> time_index{index, 2};
}  // namespace interpolation_time_period
inline constexpr ObjectId<DT::Unsigned32> max_acceleration{0x60C5};
inline constexpr ObjectId<DT::Unsigned32> max_deceleration{0x60C6};
inline constexpr ObjectId<DT::Unsigned16> positive_torque_limit_value{0x60E0};
inline constexpr ObjectId<DT::Unsigned16> negative_torque_limit_value{0x60E1};
// Positioning option code (CiA 402 / ETG.6010 figure 25): bits 6/7 the rotary axis direction option.
inline constexpr ObjectId<DT::Unsigned16> positioning_option_code{0x60F2};
inline constexpr ObjectId<DT::Integer32> following_error_actual_value{0x60F4};
inline constexpr ObjectId<DT::Integer32> position_demand_internal_value{0x60FC};
inline constexpr ObjectId<DT::Unsigned32> digital_inputs{0x60FD};
namespace digital_outputs {
inline constexpr std::uint16_t index = 0x60FE;
inline constexpr ObjectId<DT::Unsigned32> physical_outputs{index, 1};
inline constexpr ObjectId<DT::Unsigned32> bit_mask{index, 2};
}  // namespace digital_outputs
inline constexpr ObjectId<DT::Integer32> target_velocity{0x60FF};
inline constexpr ObjectId<DT::Unsigned32> supported_drive_modes{0x6502};

}  // namespace vecat::protocol::obj
