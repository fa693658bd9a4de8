// The SII EEPROM image (ETG.2010): building it from a device description and reading it back.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/bytes.hpp"
#include "device/device_description.hpp"

namespace vecat::esc {

// SII word addresses (ETG.2010 Table 2).
namespace sii {
inline constexpr unsigned PdiControl = 0x00;
inline constexpr unsigned PdiConfig = 0x01;
inline constexpr unsigned SyncImpulseLen = 0x02;
inline constexpr unsigned PdiConfig2 = 0x03;
inline constexpr unsigned StationAlias = 0x04;
inline constexpr unsigned Checksum = 0x07;
inline constexpr unsigned VendorId = 0x08;
inline constexpr unsigned ProductCode = 0x0A;
inline constexpr unsigned RevisionNo = 0x0C;
inline constexpr unsigned SerialNo = 0x0E;
inline constexpr unsigned BootRxMailboxOffset = 0x14;
inline constexpr unsigned BootRxMailboxSize = 0x15;
inline constexpr unsigned BootTxMailboxOffset = 0x16;
inline constexpr unsigned BootTxMailboxSize = 0x17;
inline constexpr unsigned StdRxMailboxOffset = 0x18;
inline constexpr unsigned StdRxMailboxSize = 0x19;
inline constexpr unsigned StdTxMailboxOffset = 0x1A;
inline constexpr unsigned StdTxMailboxSize = 0x1B;
inline constexpr unsigned MailboxProtocol = 0x1C;
inline constexpr unsigned Size = 0x3E;
inline constexpr unsigned Version = 0x3F;
inline constexpr unsigned FirstCategory = 0x40;

enum class Category : std::uint16_t {
    Nop = 0,
    Strings = 10,
    DataTypes = 20,
    General = 30,
    Fmmu = 40,
    SyncM = 41,
    FmmuX = 42,
    SyncUnit = 43,
    TxPdo = 50,
    RxPdo = 51,
    Dc = 60,
    End = 0xFFFF,
};
inline constexpr unsigned kGeneralSize = 32;
inline constexpr unsigned kDcModeSize = 24;
}  // namespace sii

// CRC-8 of the ESC configuration area (polynomial x^8+x^2+x+1, initial value 0xFF) over words 0..6.
std::uint8_t sii_config_crc(ConstBytes first14bytes);

// Builds the EEPROM image. The returned vector is the full EEPROM (eeprom_size_bytes), unused bytes 0xFF.
std::vector<std::uint8_t> build_sii_image(const device::DeviceDescription& d);

// What a master learns from an SII image (used by the project's master, the ESI tools and tests).
struct SiiPdoEntry {
    std::uint16_t index;
    std::uint8_t subindex;
    std::uint8_t name_idx;
    std::uint8_t data_type;
    std::uint8_t bit_length;
    std::uint16_t flags;
};
struct SiiPdo {
    std::uint16_t index;
    std::uint8_t sm;
    std::uint8_t dc_sync;
    std::uint8_t name_idx;
    std::uint16_t flags;
    std::vector<SiiPdoEntry> entries;
};
struct SiiSyncManager {
    std::uint16_t start;
    std::uint16_t length;
    std::uint8_t control;
    std::uint8_t status;
    std::uint8_t enable;
    std::uint8_t type;
};
struct SiiInfo {
    std::uint16_t pdi_control = 0;
    std::uint16_t station_alias = 0;
    bool checksum_ok = false;
    device::Identity identity;
    std::uint16_t boot_rx_mbx_offset = 0, boot_rx_mbx_size = 0, boot_tx_mbx_offset = 0, boot_tx_mbx_size = 0;
    std::uint16_t std_rx_mbx_offset = 0, std_rx_mbx_size = 0, std_tx_mbx_offset = 0, std_tx_mbx_size = 0;
    std::uint16_t mailbox_protocols = 0;
    std::uint16_t size_word = 0;
    std::uint16_t version = 0;
    std::vector<std::string> strings;  // strings[0] is SII string #1
    bool has_general = false;
    std::uint8_t group_idx = 0, image_idx = 0, order_idx = 0, name_idx = 0;
    std::uint8_t coe_details = 0, foe_details = 0, eoe_details = 0, flags = 0;
    std::int16_t ebus_current = 0;
    std::uint16_t physical_ports = 0;
    std::vector<std::uint8_t> fmmus;
    std::vector<SiiSyncManager> sync_managers;
    std::vector<SiiPdo> tx_pdos;
    std::vector<SiiPdo> rx_pdos;
    std::vector<device::DcOpMode> dc_modes;
    std::vector<std::string> errors;  // structural problems found while parsing

    // SII string by its 1-based index ("" for 0 or out of range).
    std::string string_at(unsigned idx) const;
    std::string device_name() const { return string_at(name_idx); }
};

// Parses an image; never reads past its end. Problems go to SiiInfo::errors.
SiiInfo parse_sii(ConstBytes image);

}  // namespace vecat::esc
