#include "twinsync/mapping.hpp"

namespace vecat::twinsync {

std::optional<MappedObject> decode_standard(std::uint32_t w) noexcept {
    const auto ww = static_cast<std::uint8_t>(w & 0xFF);
    if (ww != 0x10 && ww != 0x20) return std::nullopt;
    return MappedObject{static_cast<std::uint16_t>(w >> 16), static_cast<std::uint8_t>(w >> 8), ww, false};
}

std::optional<MappedObject> decode_extended(std::uint32_t w) noexcept {
    const auto tt = static_cast<std::uint8_t>(w & 0xFF);
    if (tt > 1) return std::nullopt;
    return MappedObject{static_cast<std::uint16_t>(w >> 16), static_cast<std::uint8_t>(w >> 8), 0, tt == 1};
}

namespace {

constexpr std::string_view kDspace =
    "the dSPACE rapid-prototyping interface (P2580 = 14..18) needs a dSPACE system, which vecat does not "
    "emulate";
constexpr std::string_view kDoubleInverter =
    "double inverter operation (P2580 = 9, 23..28) drives one motor winding from two power stages, which "
    "vecat does not emulate";
constexpr std::string_view kDsw = "a dual stator winding motor (P2580 = 33/34) is not emulated by vecat";
constexpr std::string_view kPlc =
    "the iPLC data exchange (P2580 = 20) needs an MSD PLC program, which vecat "
    "does not emulate";
constexpr std::string_view kRpdc =
    "rack-and-pinion drive control (P2580 = 10/11) needs the process controller P4200-P4204/P2659-P2683, "
    "which vecat does not emulate";

using R = Role;
using F = Follow;
using S = Setting;

constexpr std::array<ModeInfo, kLastSetting + 1> kModes = {{
    {S::User, "USER", std::nullopt, F::ByControlMode, false, {}},
    {S::TwdMasterV1, "TWD_MASTER_V1", R::Master, F::None, false, {}},
    {S::TwdSlaveV1, "TWD_SLAVE_V1", R::Slave, F::Speed, false, {}},
    {S::TwdMasterV2, "TWD_MASTER_V2", R::Master, F::None, false, {}},
    {S::TwdSlaveV2, "TWD_SLAVE_V2", R::Slave, F::SpeedTorquePrecontrol, false, {}},
    {S::SconMaster, "SCON_MASTER", R::Master, F::None, false, {}},
    {S::SconSlave, "SCON_SLAVE", R::Slave, F::Speed, false, {}},
    {S::PconMaster, "PCON_MASTER", R::Master, F::None, false, {}},
    {S::PconSlave, "PCON_SLAVE", R::Slave, F::PositionDelta, false, {}},
    {S::DiMaster, "DI_MASTER", R::Master, F::None, false, kDoubleInverter},
    {S::RpdcMaster, "RPDC_MASTER", R::Master, F::None, false, kRpdc},
    {S::RpdcSlave, "RPDC_SLAVE", R::Slave, F::Speed, false, kRpdc},
    {S::VeTconMaster, "VE_TCON_MASTER", R::Master, F::None, false, {}},
    {S::VeTconSlave, "VE_TCON_SLAVE", R::Slave, F::Torque, false, {}},
    {S::DspacePwmSlave, "PWM_SLAVE", R::Slave, F::None, false, kDspace},
    {S::DspaceTconSlave, "TCON_SLAVE", R::Slave, F::None, false, kDspace},
    {S::DspaceSconSlave, "SCON_SLAVE (dSPACE)", R::Slave, F::None, false, kDspace},
    {S::DspacePcon1Slave, "PCON_1_SLAVE", R::Slave, F::None, false, kDspace},
    {S::DspacePcon2Slave, "PCON_2_SLAVE", R::Slave, F::None, false, kDspace},
    {S::PconIpSlave, "PCON_IP_SLAVE", R::Slave, F::PositionAbsolute, false, {}},
    {S::Plc, "PLC", std::nullopt, F::None, false, kPlc},
    {S::PconRefposMaster, "PCON_REFPOS_MASTER", R::Master, F::None, false, {}},
    {S::PconRefposSlave, "PCON_REFPOS_SLAVE", R::Slave, F::PositionAbsolute, false, {}},
    {S::SdiPwmMaster, "SDI_PWM_MASTER", R::Master, F::None, false, kDoubleInverter},
    {S::PdiPwmMaster, "PDI_PWM_MASTER", R::Master, F::None, false, kDoubleInverter},
    {S::SdiPdiPwmSlave, "SDI_PDI_PWM_SLAVE", R::Slave, F::None, false, kDoubleInverter},
    {S::SdiCurrMaster, "SDI_CURR_MASTER", R::Master, F::None, false, kDoubleInverter},
    {S::PdiCurrMaster, "PDI_CURR_MASTER", R::Master, F::None, false, kDoubleInverter},
    {S::SdiPdiCurrSlave, "SDI_PDI_CURR_SLAVE", R::Slave, F::None, false, kDoubleInverter},
    {S::PconGantryMaster, "PCON_GANTRY_MASTER", R::Master, F::None, false, {}},
    {S::PconGantrySlave, "PCON_GANTRY_SLAVE", R::Slave, F::PositionAbsolute, false, {}},
    {S::ExtMapMaster, "EXT_MAP_MASTER", R::Master, F::ByControlMode, true, {}},
    {S::ExtMapSlave, "EXT_MAP_SLAVE", R::Slave, F::ByControlMode, true, {}},
    {S::DswMaster, "DSW_MASTER", R::Master, F::None, false, kDsw},
    {S::DswSlave, "DSW_SLAVE", R::Slave, F::None, false, kDsw},
}};

}  // namespace

bool requires_ip_mode(Setting s) noexcept {
    switch (s) {
        case S::TwdSlaveV1:
        case S::TwdSlaveV2:
        case S::SconSlave:
        case S::PconSlave:
        case S::RpdcSlave:
        case S::VeTconSlave:
        case S::PconRefposSlave:
        case S::PconGantrySlave:
            return true;
        default:
            return false;
    }
}

namespace {

constexpr std::uint32_t w(std::uint16_t parameter, std::uint8_t element, std::uint8_t bits) {
    return mapping_word(parameter, element, bits);
}

// Standard mapping list: sub-ID 0 = count, then the objects.
template <class... W>
constexpr MappingWords list(W... words) {
    MappingWords m{};
    m[0] = sizeof...(words);
    std::size_t i = 1;
    ((m[i++] = words), ...);
    return m;
}

// The objects that recur in the tables.
constexpr std::uint32_t kErrorNumber = w(p::CurrentError, 0, 0x10);    // 0A5A.0010
constexpr std::uint32_t kErrorLocation = w(p::CurrentError, 1, 0x10);  // 0A5A.0110

}  // namespace

const ModeInfo* mode_info(std::uint8_t setting) noexcept {
    return setting <= kLastSetting ? &kModes[setting] : nullptr;
}

std::optional<AutoMapping> automatic_mapping(Setting s) noexcept {
    // Speed/torque masters: table 6.5 (TWD V1), 6.6 (TWD V2), 6.7 (SCON), 6.10 (VE).
    const MappingWords speed_master_send =
        list(w(p::LocalActTorque, 0, 0x10), w(p::LocalActSpeed, 0, 0x10), w(p::LocalActEps, 0, 0x10));
    const MappingWords error_words = list(kErrorNumber, kErrorLocation);
    const MappingWords speed_slave_receive =
        list(w(p::RemoteActTorque, 0, 0x10), w(p::RemoteActSpeed, 0, 0x10), w(p::RemoteActEps, 0, 0x10));
    switch (s) {
        case S::TwdMasterV1:
        case S::TwdMasterV2:
        case S::SconMaster:
            return AutoMapping{speed_master_send, error_words};
        case S::TwdSlaveV1:
        case S::TwdSlaveV2:
        case S::SconSlave:
            return AutoMapping{error_words, speed_slave_receive};
        case S::PconMaster:  // table 6.8
            return AutoMapping{list(w(p::PositionActual, 0, 0x20), w(p::LocalActSpeed, 0, 0x10)),
                               error_words};
        case S::PconSlave:
        case S::PconIpSlave:  // 6.2.8: the counterpart of PCON_MASTER, the position taken as absolute
            return AutoMapping{error_words, list(w(p::RemoteActPos, 0, 0x20), w(p::RemoteActSpeed, 0, 0x10))};
        case S::RpdcMaster:  // table 6.9
            return AutoMapping{list(w(p::RpdcCurrentTx, 0, 0x10), w(p::RpdcSpeed, 0, 0x10)),
                               list(w(p::RpdcCurrentRx, 0, 0x10))};
        case S::RpdcSlave:
            return AutoMapping{list(w(p::RpdcCurrentTx, 0, 0x10)),
                               list(w(p::RpdcCurrentRx, 0, 0x10), w(p::RemoteRefSpeed, 0, 0x10))};
        case S::VeTconMaster:  // table 6.10
            return AutoMapping{
                list(w(p::LocalRefTorque, 0, 0x10), w(p::LocalActSpeed, 0, 0x10), w(p::LocalActEps, 0, 0x10)),
                error_words};
        case S::VeTconSlave:
            return AutoMapping{error_words, list(w(p::RemoteRefTorque, 0, 0x10),
                                                 w(p::RemoteActSpeed, 0, 0x10), w(p::RemoteActEps, 0, 0x10))};
        case S::PconRefposMaster:  // table 6.11; the table prints 0A30.0010 for the 32-bit RemoteActPos
                                   // the slave sends as 0A29.0020: the width must match, so 0x20 here
            return AutoMapping{list(w(p::LocalRefPos, 0, 0x20), w(p::LocalRefFFSpeed, 0, 0x10)),
                               list(w(p::RemoteActPos, 0, 0x20))};
        case S::PconRefposSlave:
            return AutoMapping{list(w(p::LocalActPos, 0, 0x20)),
                               list(w(p::RemoteRefPos, 0, 0x20), w(p::RemoteRefSpeed, 0, 0x10))};
        case S::PconGantryMaster:  // table 6.14
            return AutoMapping{list(w(p::LocalRefPos, 0, 0x20), w(p::SpeedSetpointRpm, 0, 0x20),
                                    w(p::TorqueActualScaled, 0, 0x10)),
                               list(w(p::RemoteActPos, 0, 0x20), w(p::ActSpeedMaster, 0, 0x20))};
        case S::PconGantrySlave:
            return AutoMapping{list(w(p::LocalActPos, 0, 0x20), w(p::SpeedActualRpm, 0, 0x20)),
                               list(w(p::RemoteRefPos, 0, 0x20), w(p::ActSpeedMaster, 0, 0x20),
                                    w(p::RemoteActTorque, 0, 0x10))};
        default:
            return std::nullopt;
    }
}

}  // namespace vecat::twinsync
