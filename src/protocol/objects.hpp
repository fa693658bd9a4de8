// The object catalogue: every object the tree reads or writes by number, named once with its index,
// subindex and data type (ETG.1000.6 5.6.3). This file: the identifier type and the communication area
// 0x1000-0x1FFF (CiA 301 7.5, ETG.1000.6 5.6.7, ETG.1020) and the module ident lists of the Modular Device
// Profile (ETG.5001.1); protocol/cia402_objects.hpp: the drive profile
// 0x6000-0x6FFF. The dictionary description (src/device) builds its objects from these names, and the
// typed dictionary handles (coe::Value) take their C++ type from the data type given here.
#pragma once

#include <cstddef>
#include <cstdint>

#include "protocol/data_type.hpp"

namespace vecat::protocol {

// One entry of an object, without its type in the C++ type (for tables and run-time indexes).
struct ObjectRef {
    std::uint16_t index = 0;
    std::uint8_t subindex = 0;
    DataType type = DataType::Unsigned8;
    friend constexpr bool operator==(const ObjectRef&, const ObjectRef&) = default;
};

// One entry of an object with its data type: what the catalogue names.
template <DataType T>
struct ObjectId {
    static constexpr DataType type = T;
    std::uint16_t index = 0;
    std::uint8_t subindex = 0;
    constexpr operator ObjectRef() const { return {index, subindex, T}; }
    // The bit length of a fixed-size entry: what a PDO mapping entry of it says.
    static constexpr unsigned bit_length() { return fixed_bit_length(T); }
};

namespace obj {
using DT = DataType;

// The areas of the dictionary (CiA 301 7.4.1, Table 40).
struct Area {
    std::uint16_t first, last;
    constexpr bool contains(std::uint16_t index) const { return index >= first && index <= last; }
};
inline constexpr Area communication_area{0x1000, 0x1FFF};
inline constexpr Area manufacturer_area{0x2000, 0x5FFF};
inline constexpr Area profile_area{0x6000, 0x9FFF};  // standardised device profiles (CiA 402: 0x6000-0x67FF)

inline constexpr ObjectId<DT::Unsigned32> device_type{0x1000};
inline constexpr ObjectId<DT::Unsigned8> error_register{0x1001};
inline constexpr ObjectId<DT::VisibleString> device_name{0x1008};
inline constexpr ObjectId<DT::VisibleString> hardware_version{0x1009};
inline constexpr ObjectId<DT::VisibleString> software_version{0x100A};
// CiA 301 7.5.2.13/14: sub 1 all parameters, 2 communication, 3 application, 4 manufacturer.
namespace store_parameters {
inline constexpr std::uint16_t index = 0x1010;
inline constexpr ObjectId<DT::Unsigned32> all{index, 1};
}  // namespace store_parameters
namespace restore_default_parameters {
inline constexpr std::uint16_t index = 0x1011;
inline constexpr ObjectId<DT::Unsigned32> all{index, 1};
}  // namespace restore_default_parameters
namespace identity {
inline constexpr std::uint16_t index = 0x1018;
inline constexpr ObjectId<DT::Unsigned32> vendor_id{index, 1};
inline constexpr ObjectId<DT::Unsigned32> product_code{index, 2};
inline constexpr ObjectId<DT::Unsigned32> revision{index, 3};
inline constexpr ObjectId<DT::Unsigned32> serial_number{index, 4};
}  // namespace identity
// ETG.1020 14.2: error settings.
namespace error_settings {
inline constexpr std::uint16_t index = 0x10F1;
inline constexpr ObjectId<DT::Unsigned32> local_error_reaction{index, 1};
inline constexpr ObjectId<DT::Unsigned16> sync_error_counter_limit{index, 2};
}  // namespace error_settings
// PDO mapping objects (ETG.1000.6 5.6.7.4.7/8): a range each, of records of UNSIGNED32 mapping entries.
inline constexpr std::uint16_t rx_pdo_mapping_first = 0x1600, rx_pdo_mapping_last = 0x17FF;
inline constexpr std::uint16_t tx_pdo_mapping_first = 0x1A00, tx_pdo_mapping_last = 0x1BFF;
// Sync manager communication type (ETG.1000.6 5.6.7.4.9) and PDO assignment, 0x1C10 + SM number (10).
inline constexpr std::uint16_t sync_manager_type = 0x1C00;
inline constexpr std::uint16_t sm_pdo_assign_first = 0x1C10;
// SM output / input parameter (ETG.1020 21.1, ETG.1000.6 5.6.7.4.11).
namespace sync_parameter {
inline constexpr std::uint16_t outputs = 0x1C32, inputs = 0x1C33;
inline constexpr std::uint8_t sync_mode = 1, cycle_time = 2, shift_time = 3, sync_modes_supported = 4,
                              minimum_cycle_time = 5, calc_and_copy_time = 6, minimum_delay_time = 7,
                              get_cycle_time = 8, delay_time = 9, sync0_cycle_time = 10, sm_event_missed = 11,
                              cycle_time_too_small = 12, shift_time_too_short = 13, sync_error = 32;
}  // namespace sync_parameter

// The device area of the Modular Device Profile (ETG.5001.1, Table "Device area"): ARRAYs of UNSIGNED32,
// one ModuleIdent per slot (subindex n: slot n), 0 for an empty slot.
namespace modular_device {
inline constexpr std::uint16_t configured_module_ident_list = 0xF030;  // written by the master in PREOP
inline constexpr std::uint16_t detected_module_ident_list = 0xF050;    // what the device has, read-only
// The largest slot count these arrays describe (subindexes 1..255).
inline constexpr std::size_t max_slots = 255;
}  // namespace modular_device

}  // namespace obj
}  // namespace vecat::protocol
