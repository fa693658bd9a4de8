// The HIWIN D2 servo drive with EtherCAT (CoE) interface, as the HIWIN "Drive User Guide with EtherCAT
// (CoE) Interface" for the D1-N/D1/D2 (../shared/seeds/004_*.txt) describes it: its identity (3.2), PDO
// mapping objects (3.3, 7), SyncManagers (3.4, 4), the CiA 402 objects with HIWIN's types and defaults
// (3.5, 9) and its manufacturer objects 0x2000-0x2101 (3.6, 3.7). The drive core behind it is the vecat
// drive's; what differs is this data and the strategies DriveVariant::HiwinD2 selects in src/cia402.
#pragma once

#include "device/device_description.hpp"

namespace vecat::device {

namespace hiwin {

// 3.2: vendor ID 0x0000AAAA, product codes of the D1N, D1 and D2 CoE drives.
inline constexpr std::uint32_t kVendorId = 0x0000AAAA;
inline constexpr std::uint32_t kProductD1N = 0x00000001;
inline constexpr std::uint32_t kProductD1 = 0x00000002;
inline constexpr std::uint32_t kProductD2 = 0x00000003;

using protocol::ObjectId;
using HDT = protocol::DataType;

// 4: SM0 mailbox out 0x1800, SM1 mailbox in 0x18F6, SM2 RxPDO 0x1000, SM3 TxPDO 0x1100 (the process data
// lengths follow the PDO assignment). The vecat drive keeps the same layout.
std::vector<SyncManagerConfig> sync_managers();

// 3.5: the CiA 402 objects whose type in HIWIN's table differs from IEC 61800-7-201's.
inline constexpr ObjectId<HDT::Unsigned16> homing_method{0x6098};            // INT8 in CiA 402
inline constexpr ObjectId<HDT::Integer32> touch_probe_status{0x60B9};        // UINT16 in CiA 402
inline constexpr ObjectId<HDT::Unsigned32> target_velocity{0x60FF};          // INT32 in CiA 402
inline constexpr ObjectId<HDT::Unsigned16> interpolation_period{0x60C2, 1};  // UINT8 + INT8 index in CiA 402

// 3.6/3.7: the manufacturer objects.
inline constexpr ObjectId<HDT::Unsigned16> motor_type{0x2000};  // 0 linear, 1 torque, 2 AC servo motor
inline constexpr ObjectId<HDT::Integer32> velocity_encoder_resolution{0x2001};
inline constexpr ObjectId<HDT::Integer32> position_encoder_resolution{0x2002};
inline constexpr ObjectId<HDT::Integer32> screw_pitch{0x2003};
inline constexpr ObjectId<HDT::Unsigned16> input_function{0x2010};  // bit 0 error mapping, bit 1 reset
inline constexpr ObjectId<HDT::Integer8> index_signal{0x2020};      // 1: the index has been touched
inline constexpr ObjectId<HDT::Integer32> latched_index_position{0x2021};
inline constexpr ObjectId<HDT::Real32> motor_actual_current{0x2022};  // A
inline constexpr ObjectId<HDT::Unsigned16> second_encoder{0x2040};
inline constexpr ObjectId<HDT::Unsigned16> software_limit_protection{0x2041};
inline constexpr ObjectId<HDT::Unsigned16> hardware_limit_protection{0x2042};
inline constexpr ObjectId<HDT::Real32> common_gain{0x2050};
inline constexpr ObjectId<HDT::Real32> velocity_gain{0x2051};
inline constexpr ObjectId<HDT::Unsigned8> multi_turn_reset{0x2060};  // 0->1 zero, 0->2 clear error
inline constexpr ObjectId<HDT::Unsigned32> error_events_1{0x2100};
inline constexpr ObjectId<HDT::Unsigned32> error_events_2{0x2101};

// 0x2010 bits (3.7; 9.4 "Initiate accuracy compensation" calls bit 0 the trigger of the compensation).
namespace input {
inline constexpr std::uint16_t ErrorMapping = 0x0001;
inline constexpr std::uint16_t ResetDrive = 0x0002;
}  // namespace input

// 0x2100 bits (3.7) the emulated faults set.
namespace events1 {
inline constexpr std::uint32_t Encoder = 1u << 1;
inline constexpr std::uint32_t PositionErrorTooBig = 1u << 6;
inline constexpr std::uint32_t SoftThermal = 1u << 7;
}  // namespace events1

// 9.4: the values of 0x6098 the drive takes ("No homing mode", 1-6, 33, 34).
bool homing_method_supported(std::int64_t method) noexcept;

}  // namespace hiwin

DeviceDescription hiwin_d2();

}  // namespace vecat::device
