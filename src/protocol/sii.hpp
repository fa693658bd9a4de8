// The SII EEPROM image (ETG.2010): word addresses of the header, the category ids and layouts, and the parse
// of an image as a master reads it. The image is built from a device description in esc/sii_image.hpp.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/bytes.hpp"

namespace vecat::protocol {

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
inline constexpr std::uint16_t kEndMarker = 0xFFFF;       // category id that ends the list
inline constexpr std::uint16_t kCategoryIdMask = 0x7FFF;  // bit 15: vendor specific
inline constexpr unsigned kCategoryHeaderSize = 4;        // id, length in words
inline constexpr unsigned kConfigAreaSize = 14;           // words 0..6, covered by the checksum in word 7
inline constexpr unsigned kGeneralSize = 32;
inline constexpr unsigned kSyncMSize = 8;  // per SyncManager: start, length, control, status, enable, type
inline constexpr unsigned kPdoSize = 8;    // per PDO: index, entries, SM, DC sync, name, flags
inline constexpr unsigned kPdoEntrySize =
    8;  // per entry: index, subindex, name, data type, bit length, flags
inline constexpr unsigned kDcModeSize = 24;

// Byte offsets inside the General category (ETG.2010).
namespace general {
inline constexpr unsigned GroupIdx = 0;
inline constexpr unsigned ImgIdx = 1;
inline constexpr unsigned OrderIdx = 2;
inline constexpr unsigned NameIdx = 3;
inline constexpr unsigned CoeDetails = 5;
inline constexpr unsigned FoeDetails = 6;
inline constexpr unsigned EoeDetails = 7;
inline constexpr unsigned Flags = 11;
inline constexpr unsigned EbusCurrent = 12;  // i16, mA
inline constexpr unsigned PhysicalPorts = 16;
}  // namespace general

// SyncM category type byte (ETG.2010 Table 8).
inline constexpr std::uint8_t SmTypeUnused = 0;
inline constexpr std::uint8_t SmTypeMailboxOut = 1;
inline constexpr std::uint8_t SmTypeMailboxIn = 2;
inline constexpr std::uint8_t SmTypeOutputs = 3;
inline constexpr std::uint8_t SmTypeInputs = 4;

// SyncM category "enable synch manager" byte (ETG.2010 SyncM; the ESI Sm attributes Enable, Virtual and
// OpOnly of ETG.2000).
namespace sm_enable {
inline constexpr std::uint8_t Enable = 0x01;        // the master enables the SyncManager
inline constexpr std::uint8_t FixedContent = 0x02;  // information for a configuration tool
inline constexpr std::uint8_t Virtual = 0x04;       // no hardware SyncManager: read through an FMMU only
inline constexpr std::uint8_t OpOnly = 0x08;        // enabled in OP only
}  // namespace sm_enable

// Mailbox protocols word (word 0x1C).
inline constexpr std::uint16_t MailboxCoE = 0x0004;
inline constexpr std::uint16_t MailboxSoE = 0x0010;
}  // namespace sii

// CRC-8 of the ESC configuration area (polynomial x^8+x^2+x+1, initial value 0xFF) over words 0..6.
std::uint8_t sii_config_crc(ConstBytes first14bytes);

// What a master learns from an SII image (used by the project's master, the ESI tools and tests). The
// identity and the DC modes are also the device description's (device::Identity, device::DcOpMode).
struct SiiIdentity {
    std::uint32_t vendor_id = 0;
    std::uint32_t product_code = 0;
    std::uint32_t revision = 0;
    std::uint32_t serial = 0;
};
// One DC operation mode of the DC category (ETG.2010), names resolved from the string table.
struct SiiDcMode {
    std::string name;
    std::string description;
    std::uint16_t assign_activate = 0;
    std::uint32_t cycle_time0 = 0;
    std::uint32_t shift_time0 = 0;
    std::uint32_t shift_time1 = 0;
    std::int16_t sync0_cycle_factor = 1;
    std::int16_t sync1_cycle_factor = 0;
};
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
    SiiIdentity identity;
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
    std::vector<SiiDcMode> dc_modes;
    std::vector<std::string> errors;  // structural problems found while parsing

    // SII string by its 1-based index ("" for 0 or out of range).
    std::string string_at(unsigned idx) const;
    std::string device_name() const { return string_at(name_idx); }
};

// Parses an image; never reads past its end. Problems go to SiiInfo::errors. Its strings are UTF-8
// (sii_text_to_utf8).
SiiInfo parse_sii(ConstBytes image);

// The text of SII strings is 8-bit, ISO 8859-1 as Beckhoff's devices and TwinCAT write it (the EL2262's
// name says "1 µs" with the byte 0xB5): the parser gives it as UTF-8, and the SII writer (esc/sii_image)
// stores UTF-8 text as ISO 8859-1, a character beyond it as '?'. A byte that starts no valid UTF-8 sequence
// is taken as the ISO 8859-1 character it is.
std::string sii_text_to_utf8(std::string_view latin1);
std::string utf8_to_sii_text(std::string_view utf8);

}  // namespace vecat::protocol
