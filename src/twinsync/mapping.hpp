// The process data mapping of the TWINsync telegram (P2615 send, P2616 receive) and the operation modes
// of P2580 MPRO_TWIN_Setting with their automatic mappings (specification chapter 6).
//   standard mapping: sub-ID 0 = number of objects (0..7), sub-IDs 1..7 = pppp.SSww
//                     (parameter number, element, width 0x10 or 0x20 bits)
//   extended mapping: sub-IDs 0..7 = pppp.SS.tt (parameter number, element, type 0 parameter / 1 scope);
//                     the width is the parameter's own; 0 = unused.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include "twinsync/parameters.hpp"

namespace vecat::twinsync {

constexpr std::uint32_t mapping_word(std::uint16_t parameter, std::uint8_t element,
                                     std::uint8_t low) noexcept {
    return (static_cast<std::uint32_t>(parameter) << 16) | (static_cast<std::uint32_t>(element) << 8) | low;
}

struct MappedObject {
    std::uint16_t parameter = 0;
    std::uint8_t element = 0;  // MSD sub-ID (array element), CoE subindex element + 1 for arrays
    std::uint8_t bits = 0;     // standard mapping: 16 or 32; extended: 0 (the parameter's own width)
    bool scope = false;        // extended mapping: a scope signal instead of a parameter
    bool operator==(const MappedObject&) const = default;
};

// nullopt: not a valid entry (standard: width other than 0x10/0x20; extended: type other than 0/1).
std::optional<MappedObject> decode_standard(std::uint32_t word) noexcept;
std::optional<MappedObject> decode_extended(std::uint32_t word) noexcept;

// The eight sub-IDs of P2615 or P2616 as the drive stores them.
using MappingWords = std::array<std::uint32_t, 8>;

// P2580 operation modes.
enum class Setting : std::uint8_t {
    User = 0,
    TwdMasterV1 = 1,
    TwdSlaveV1 = 2,
    TwdMasterV2 = 3,
    TwdSlaveV2 = 4,
    SconMaster = 5,
    SconSlave = 6,
    PconMaster = 7,
    PconSlave = 8,
    DiMaster = 9,
    RpdcMaster = 10,
    RpdcSlave = 11,
    VeTconMaster = 12,
    VeTconSlave = 13,
    DspacePwmSlave = 14,
    DspaceTconSlave = 15,
    DspaceSconSlave = 16,
    DspacePcon1Slave = 17,
    DspacePcon2Slave = 18,
    PconIpSlave = 19,
    Plc = 20,
    PconRefposMaster = 21,
    PconRefposSlave = 22,
    SdiPwmMaster = 23,
    PdiPwmMaster = 24,
    SdiPdiPwmSlave = 25,
    SdiCurrMaster = 26,
    PdiCurrMaster = 27,
    SdiPdiCurrSlave = 28,
    PconGantryMaster = 29,
    PconGantrySlave = 30,
    ExtMapMaster = 31,
    ExtMapSlave = 32,
    DswMaster = 33,
    DswSlave = 34,
};
inline constexpr std::uint8_t kLastSetting = 34;

// How a slave drive uses what it receives (master settings: None).
enum class Follow : std::uint8_t {
    None,
    Speed,                  // speed set-point from the master's speed (SCON, TWD V1 with speed-up)
    SpeedTorquePrecontrol,  // TWD V2: speed set-point plus the master's torque at the speed loop output
    Torque,                 // VE: the master's torque set-point
    PositionDelta,          // PCON: master position increments, geared, integrated (coupling offset)
    PositionAbsolute,       // IP, REFPOS, GANTRY: the master position is the set-point
    ByControlMode,          // USER / EXT_MAP: P0300 decides (TCON torque, SCON speed, PCON position)
};

struct ModeInfo {
    Setting setting;
    std::string_view name;     // as in table 6.3
    std::optional<Role> role;  // the P2614 mode the setting is meant for (USER, PLC: either)
    Follow follow;
    bool extended;             // extended mapping telegram
    std::string_view refusal;  // empty: vecat runs it; otherwise why not
};

// nullptr for values above 34.
const ModeInfo* mode_info(std::uint8_t setting) noexcept;

// The slave tables of chapter 6 that require P0301 setpoint mode = IP-Mode (1): TWD V1/V2, SCON, PCON,
// VE, REFPOS and GANTRY slaves (tables 6.5-6.11, 6.14; RPDC 6.9 too, which vecat refuses).
bool requires_ip_mode(Setting s) noexcept;

struct AutoMapping {
    MappingWords send{};
    MappingWords receive{};
};
// The automatic P2615/P2616 of a setting (tables 6.5-6.14); nullopt for settings without one (USER,
// EXT_MAP, PLC and the modes documented elsewhere).
std::optional<AutoMapping> automatic_mapping(Setting s) noexcept;

}  // namespace vecat::twinsync
