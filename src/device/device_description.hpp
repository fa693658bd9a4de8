// The one description of a device. The SII EEPROM image, the CoE object dictionary and the ESI file are
// all generated from it, so they cannot disagree.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "device/object_description.hpp"
#include "device/quirks.hpp"
#include "protocol/sii.hpp"

namespace vecat::device {

// The identity (vendor, product, revision, serial) and the DC operation modes are the SII's: one type each,
// declared with the SII layout in protocol/sii.hpp.
using Identity = protocol::SiiIdentity;

// SII SyncM category type byte (ETG.2010 Table 8).
enum class SmType : std::uint8_t { Unused = 0, MailboxOut = 1, MailboxIn = 2, Outputs = 3, Inputs = 4 };

namespace sm_enable = protocol::sii::sm_enable;  // the SII enable byte's bits

struct SyncManagerConfig {
    std::uint16_t start = 0;
    std::uint16_t length = 0;
    std::uint8_t control = 0;
    std::uint8_t enable = 0;  // sm_enable bits
    SmType type = SmType::Unused;
};

// SII FMMU category usage byte (ETG.2010 Table 7).
enum class FmmuUsage : std::uint8_t { Unused = 0, Outputs = 1, Inputs = 2, MailboxState = 3 };

struct PdoEntry {
    std::uint16_t index = 0;  // 0 with subindex 0: padding (gap)
    std::uint8_t subindex = 0;
    std::uint8_t bit_length = 0;
    DataType type = DataType::Unsigned8;
    std::string name;
};

// A mapping entry of a catalogue object: index, subindex, type and bit length from the catalogue.
template <DataType T>
PdoEntry pdo_entry(protocol::ObjectId<T> id, std::string name) {
    static_assert(protocol::fixed_bit_length(T) > 0, "only fixed-size entries are mapped");
    return PdoEntry{id.index, id.subindex, static_cast<std::uint8_t>(protocol::fixed_bit_length(T)), T,
                    std::move(name)};
}

struct Pdo {
    std::uint16_t index = 0;  // 0x16xx RxPDO, 0x1Axx TxPDO
    std::string name;
    std::uint8_t sm = 0;  // SyncManager it is assigned to by default
    bool fixed = false;
    bool mandatory = false;
    bool assigned = true;  // part of the default assignment
    std::vector<PdoEntry> entries;
    std::uint8_t capacity = 0;            // subindexes of the mapping object; at least entries.size()
    std::vector<std::uint16_t> excludes;  // PDOs that cannot be assigned together with this one (ESI Exclude)
    std::uint8_t max_entries = 0;         // most entries subindex 0 takes (0: capacity)

    unsigned bit_length() const {
        unsigned n = 0;
        for (const auto& e : entries)
            n += e.bit_length;
        return n;
    }
};

// One operation mode of the DC category / ESI Dc element.
using DcOpMode = protocol::SiiDcMode;

// Mailbox protocols word (SII word 0x1C).
namespace mbx_proto {
inline constexpr std::uint16_t AoE = 0x0001;
inline constexpr std::uint16_t EoE = 0x0002;
inline constexpr std::uint16_t CoE = 0x0004;
inline constexpr std::uint16_t FoE = 0x0008;
inline constexpr std::uint16_t SoE = 0x0010;
inline constexpr std::uint16_t VoE = 0x0020;
}  // namespace mbx_proto

// FoE details byte of the SII General category (ETG.2010 General: bit 0 "FoE enabled").
namespace foe_details {
inline constexpr std::uint8_t Enable = 0x01;
}  // namespace foe_details

// EoE details byte of the SII General category (ETG.2010 General: bit 0 "EoE enabled").
namespace eoe_details {
inline constexpr std::uint8_t Enable = 0x01;
}  // namespace eoe_details

// The bootstrap mailbox (ETG.2010 SII words 0x0014-0x0017, ETG.2000 Eeprom/BootStrap): where SM0 (master to
// slave) and SM1 (slave to master) lie in the BOOT state.
struct BootMailbox {
    std::uint16_t out_start = 0;
    std::uint16_t out_length = 0;
    std::uint16_t in_start = 0;
    std::uint16_t in_length = 0;
    friend bool operator==(const BootMailbox&, const BootMailbox&) = default;
};

// CoE details byte of the SII General category.
namespace coe_details {
inline constexpr std::uint8_t Sdo = 0x01;
inline constexpr std::uint8_t SdoInfo = 0x02;
inline constexpr std::uint8_t PdoAssign = 0x04;
inline constexpr std::uint8_t PdoConfig = 0x08;
inline constexpr std::uint8_t Upload = 0x10;
inline constexpr std::uint8_t CompleteAccess = 0x20;
}  // namespace coe_details

// When a master may write the entries of a PDO mapping object (0x16xx/0x1Axx subindex 1-n).
enum class PdoRemapping : std::uint8_t {
    Subindex0Zero,      // ETG.1000.6 / CiA 301 7.4.8: while its subindex 0 is 0 (abort 0x06010003 otherwise)
    AssignmentCleared,  // while the SyncManager's assignment 0x1C1x:0 is 0, whatever its subindex 0 (the
                        // HIWIN guide, chapter 7: 0x1C12:0 = 0, entries 1-5, 0x1600:0 = n, 0x1C12:1, 0x1C12:0
                        // = 1)
};

// Whose behaviour the CiA 402 drive core shows behind this dictionary: the strategies src/cia402 selects
// (homing methods, 0x60C2 format, touch probe trigger, manufacturer objects).
enum class DriveVariant : std::uint8_t {
    Vecat,    // the vecat drive (and a vendor's ESI run on the vecat drive core)
    HiwinD2,  // the HIWIN D2 (device/hiwin_d2.hpp)
};

struct DeviceDescription {
    Identity identity;
    std::string vendor_name;
    std::string name;        // device name, SII string shown by masters
    std::string order_code;  // ESI Type
    std::string group_type;
    std::string group_name;
    std::uint32_t profile_no = 402;
    std::uint32_t device_type = 0x00020192;  // 0x1000: CiA 402 servo drive
    std::string hardware_version = "1.0";
    std::string software_version = "vecat 0.1.0";

    // ESC configuration area of the SII (words 0..7).
    std::uint16_t pdi_control = 0x0005;  // 0x05: SPI-like "on-chip bus"/digital I/O; value copied to 0x0140
    std::uint16_t pdi_config = 0x0000;
    std::uint16_t sync_impulse_len = 100;  // in 10 ns
    std::uint16_t station_alias = 0;

    std::uint16_t mailbox_protocols = mbx_proto::CoE;
    std::uint8_t coe_details = 0;
    std::uint8_t foe_details = 0;
    std::uint8_t eoe_details = 0;
    std::uint8_t soe_channels = 0;  // SII General category: the SoE drives (channels) of the device
    std::uint8_t general_flags = 0;
    std::int16_t ebus_current_ma = 0;
    bool bootstrap_supported = false;
    // The bootstrap mailbox when bootstrap_supported; lengths 0: the standard mailbox's area and lengths.
    BootMailbox boot_mailbox{};

    std::vector<SyncManagerConfig> sync_managers;  // SM0.. in order
    std::vector<FmmuUsage> fmmus;
    std::vector<Pdo> rx_pdos;  // outputs (master -> slave)
    std::vector<Pdo> tx_pdos;  // inputs (slave -> master)
    std::vector<DcOpMode> dc_modes;
    PdoRemapping pdo_remapping = PdoRemapping::Subindex0Zero;
    // Subindexes of the PDO assignments 0x1C12/0x1C13 (0: one per PDO of the direction).
    std::uint8_t pdo_assign_slots = 0;
    DriveVariant drive_variant = DriveVariant::Vecat;
    // Synchronisation capabilities reported in 0x1C32/0x1C33.
    std::uint32_t min_cycle_time_ns = 125'000;
    std::uint32_t calc_copy_time_ns = 20'000;
    // The application objects (profile and manufacturer area). The communication area (0x1000-0x1FFF) is
    // generated from the fields above by dictionary_objects(); an object listed here replaces it.
    std::vector<ObjectDescription> objects;
    // A modular device (ETG.2000 Slots, ETG.5001 Modular Device Profile): the ModuleIdent of the module in
    // each slot, in slot order, 0 for an empty slot. Not empty: the dictionary has the Detected Module Ident
    // List 0xF050 (these values) and the Configured Module Ident List 0xF030 a master writes in PREOP.
    std::vector<std::uint32_t> module_idents;

    std::uint32_t eeprom_size_bytes = 4096;

    // What the device does less completely than vecat's drive (device/quirks.hpp); set by apply_quirks,
    // which also makes the flags above agree with them.
    Quirks quirks;

    // Byte sizes of the default process data image for the SM of a given type.
    unsigned output_bytes() const;
    unsigned input_bytes() const;
    const SyncManagerConfig* sm_of_type(SmType t) const;
    std::optional<unsigned> sm_index_of_type(SmType t) const;
    // The bootstrap mailbox in effect (boot_mailbox, or the standard mailbox where it leaves the lengths 0);
    // nullopt when the device has no bootstrap or no mailbox. The SII, the ESI and the slave's BOOT check
    // all take it from here.
    std::optional<BootMailbox> bootstrap_mailbox() const;
};

// Every object of the device's dictionary, sorted by index: the generated communication area
// (0x1000, 0x1001, 0x1008-0x100A, 0x1010, 0x1011, 0x1018, 0x10F1, 0x16xx, 0x1Axx, 0x1C00, 0x1C1x, 0x1C32,
// 0x1C33; 0xF030 and 0xF050 of a modular device) and the application objects. The CoE dictionary, the ESI
// Dictionary and the SDO information come from this.
std::vector<ObjectDescription> dictionary_objects(const DeviceDescription& d);

// The objects of the CiA 402 drive profile the vecat drive core implements (0x603F-0x60FF, 0x6502) and
// its manufacturer objects (0x2000...).
std::vector<ObjectDescription> cia402_drive_objects();
// The TWINsync option's parameters (0x2000 + parameter number) and vecat's TWINsync objects 0x2102-0x2104.
std::vector<ObjectDescription> twinsync_objects();

// The built-in default device: a CiA402 servo drive with HIWIN-like SyncManager layout.
DeviceDescription default_drive();

// The built-in drives by the name `vecat run --device` and a network file's `device:` give them: "drive"
// (default_drive()) and "hiwin-d2" (device/hiwin_d2.hpp). nullopt for another name.
std::optional<DeviceDescription> builtin_drive(std::string_view name);
// Their names, for messages.
std::vector<std::string_view> builtin_drive_names();
// A description read from a file (an ESI) of a device that is also built in, by vendor ID and product code
// (the HIWIN D2's D2COE.xml): takes over what the file cannot say, the built-in's DriveVariant, PDO
// remapping rule, assignment slots and mapping limits. Returns the built-in's name, or nullopt (then d is
// unchanged).
std::optional<std::string_view> adopt_builtin_rules(DeviceDescription& d);

}  // namespace vecat::device
