// ESI files read into a device description: identity, names, SyncManagers, FMMUs, PDOs (device level or
// from the default modules of its slots), mailbox and CoE flags, DC op modes, EEPROM config data and
// the dictionary objects the communication area does not generate.
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
