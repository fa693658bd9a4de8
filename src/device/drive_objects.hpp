// The manufacturer objects (0x2000-0x2FFF) of the vecat drive, named like the catalogue's profile objects
// (protocol/cia402_objects.hpp): the simulated motor, machine and faults, and a few diagnostic values.
// They are this device's, not the profile's; their descriptions are in cia402_objects.cpp.
#pragma once

#include "protocol/objects.hpp"

namespace vecat::device::mfr {

using protocol::ObjectId;
using DT = protocol::DataType;

namespace motor {
inline constexpr std::uint16_t index = 0x2000;
inline constexpr ObjectId<DT::Unsigned32> rated_speed{index, 1};       // rpm
inline constexpr ObjectId<DT::Unsigned32> rotor_inertia{index, 2};     // g cm2
inline constexpr ObjectId<DT::Unsigned32> torque_constant{index, 3};   // mNm/A
inline constexpr ObjectId<DT::Unsigned32> load_inertia{index, 4};      // g cm2
inline constexpr ObjectId<DT::Unsigned32> viscous_friction{index, 5};  // uNm s/rad
inline constexpr ObjectId<DT::Unsigned32> coulomb_friction{index, 6};  // mNm
inline constexpr ObjectId<DT::Unsigned32> peak_current{index, 7};      // mA
}  // namespace motor
inline constexpr ObjectId<DT::Integer16> drive_temperature{0x2001};  // 0.1 C
inline constexpr ObjectId<DT::Unsigned16> dc_bus_voltage{0x2002};    // 0.1 V
// Gains of the cascaded loops; 0 = tuned from the motor parameters.
namespace gains {
inline constexpr std::uint16_t index = 0x2003;
inline constexpr ObjectId<DT::Unsigned32> position_kp{index, 1};        // 0.01/s
inline constexpr ObjectId<DT::Unsigned32> velocity_kp{index, 2};        // uNm s/rad
inline constexpr ObjectId<DT::Unsigned32> velocity_ti{index, 3};        // us
inline constexpr ObjectId<DT::Unsigned32> current_bandwidth{index, 4};  // rad/s
}  // namespace gains
inline constexpr ObjectId<DT::VisibleString> user_label{0x2010};
inline constexpr ObjectId<DT::OctetString> diagnosis_history{0x2020};
// The simulated machine around the motor (positions in increments of the machine position).
namespace machine {
inline constexpr std::uint16_t index = 0x2100;
inline constexpr ObjectId<DT::Integer32> negative_limit_switch{index, 1};
inline constexpr ObjectId<DT::Integer32> positive_limit_switch{index, 2};
inline constexpr ObjectId<DT::Integer32> home_switch{index, 3};
inline constexpr ObjectId<DT::Integer32> index_pulse_offset{index, 4};
inline constexpr ObjectId<DT::Integer16> load_torque{index, 5};  // 0.1 % of rated torque
inline constexpr ObjectId<DT::Unsigned8> touch_probe_inputs{index, 6};
inline constexpr ObjectId<DT::Unsigned8> limit_switch_reaction{index, 7};  // 0 warning, 1 fault
}  // namespace machine
// Fault injection: the 0x603F code of a fault condition to simulate (0 = none).
inline constexpr ObjectId<DT::Unsigned16> simulated_fault{0x2101};
// TwinCAT NC PTP online changes of the profile modes.
inline constexpr ObjectId<DT::Unsigned32> velocity_override{0x2110};  // ppm of 100 %
namespace position_compensation {
inline constexpr std::uint16_t index = 0x2111;
inline constexpr ObjectId<DT::Integer32> distance{index, 1};
inline constexpr ObjectId<DT::Unsigned32> length{index, 2};
inline constexpr ObjectId<DT::Unsigned8> start{index, 3};
// TX1250 2.5 start parameters (0 = the move's own): VP, VK, AK+, AK-; and the compensation stop.
inline constexpr ObjectId<DT::Unsigned32> process_velocity{index, 4};
inline constexpr ObjectId<DT::Unsigned32> velocity_increase{index, 5};
inline constexpr ObjectId<DT::Unsigned32> acceleration{index, 6};
inline constexpr ObjectId<DT::Unsigned32> deceleration{index, 7};
inline constexpr ObjectId<DT::Unsigned8> stop{index, 8};
}  // namespace position_compensation
// A profile position target beyond 0x607D: 0 refused with the fault 0x8612, 1 refused, 2 clamped.
inline constexpr ObjectId<DT::Unsigned8> software_limit_reaction{0x2112};
// The override type of TX1250 2.2 (1-4).
inline constexpr ObjectId<DT::Unsigned8> override_type{0x2113};
// New velocity at an activation position (TX1250 2.4).
namespace activation {
inline constexpr std::uint16_t index = 0x2114;
inline constexpr ObjectId<DT::Integer32> position{index, 1};
inline constexpr ObjectId<DT::Unsigned32> velocity{index, 2};
inline constexpr ObjectId<DT::Unsigned8> mode{index, 3};
}  // namespace activation
// TX1250 3.3 cyclic slave axis: AccBound, the bound of the slave's acceleration that a change of the
// coupling factor causes (user units/s^2; 0 = none: the factor applies at once, a linear slave axis, 3.2).
inline constexpr ObjectId<DT::Unsigned32> coupling_acc_bound{0x2115};

}  // namespace vecat::device::mfr
