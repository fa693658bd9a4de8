// ESI files read into a device description: identity, names, SyncManagers, FMMUs, PDOs (device level or
// from the modules in its slots: the default ones or those chosen), mailbox and CoE flags, DC op modes,
// EEPROM config data and the dictionary objects the communication area does not generate.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "device/device_description.hpp"

namespace vecat::esi {

struct EsiError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Which device of a file: by its Type text, its product code (and revision), or the first one.
struct DeviceSelector {
    std::optional<std::string> type;
    std::optional<std::uint32_t> product_code;
    std::optional<std::uint32_t> revision;
    // A modular device (ETG.2000 Slots): the module of each slot in slot order, by its Type text or its
    // ModuleIdent (decimal, 0x or #x hexadecimal); nullopt: the slot stays empty. Slots after the list keep
    // their default module. No list: every slot its default module.
    std::optional<std::vector<std::optional<std::string>>> modules;
};

// A module choice the device refuses: entry is the index in DeviceSelector::modules of the refused one,
// nullopt when the list as a whole is refused (a device without slots).
struct ModuleError : EsiError {
    ModuleError(std::optional<std::size_t> at, const std::string& what) : EsiError(what), entry(at) {}
    std::optional<std::size_t> entry;
};

struct DeviceSummary {
    std::string type;
    std::string name;
    std::uint32_t product_code = 0;
    std::uint32_t revision = 0;
};

struct ImportResult {
    device::DeviceDescription desc;
    std::vector<std::string> notes;  // what was guessed or left out, one line each
};

// "#x1A00", "6656", "-5": the ESI HexDecValue; nullopt if it is not one.
std::optional<std::int64_t> parse_hexdec(const std::string& s);
// "UINT" -> Unsigned16, "STRING(8)" -> VisibleString... nullopt for unknown names.
std::optional<device::DataType> parse_esi_type(const std::string& name);

std::vector<DeviceSummary> list_devices_text(const std::string& xml);
ImportResult import_esi_text(const std::string& xml, const DeviceSelector& sel = {});
// Makes an imported description runnable: every object a PDO maps exists and is mappable in its direction
// (vendor files often leave them out or unflagged). Returns one line per change.
std::vector<std::string> complete_for_emulation(device::DeviceDescription& d);

ImportResult import_esi_file(const std::string& path, const DeviceSelector& sel = {});

}  // namespace vecat::esi
