// The dictionary file: a device's CoE object dictionary as read from the device (vecat clone writes it,
// a network file's sii: device serves it with `dictionary: FILE`). YAML; the format is documented in
// docs/clone.md:
//
//   sdo_information: true        # false: the device refused SDO information (the copy refuses it too)
//   missing:                     # what could not be read, one line each
//     - "0x2000:01: upload refused (0x06010001)"
//   objects:
//     - index: 0x1018
//       name: "Identity"
//       code: record             # ETG.1000.6 Table 46: var, array, record, domain, deftype, defstruct
//       type: 0x0023             # object data type (ETG.1000.6 Table 64), or its name (IDENTITY)
//       max_subindex: 4
//       entries:
//         - subindex: 1
//           name: "Vendor ID"
//           type: 0x0007         # UDINT
//           bits: 32
//           access: 0x0007       # ETG.1000.6 Table 47 bits (read/write per state, mappable, ...)
//           value: "9a 00 00 00" # the value uploaded, little-endian bytes; absent: not read
//           default: "00 00 00 00"   # the entry description's default/minimum/maximum, when read
//
// The reader refuses a bad file with a DictionaryFileError "FILE:LINE: what is wrong"; nothing half-read is
// returned. write_dictionary() and read_dictionary() are each other's inverse (tests/network).
#pragma once

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "device/object_description.hpp"

namespace vecat::network {

struct DeviceDictionary {
    // The objects as described (SDO information), sorted by index. An entry's default_value, minimum and
    // maximum are those the entry description gave (empty: not read).
    std::vector<device::ObjectDescription> objects;
    // The values uploaded, per (index, subindex): what the served device holds at start-up.
    std::map<std::pair<std::uint16_t, std::uint8_t>, std::vector<std::uint8_t>> values;
    // Whether the device answered SDO information (false: the copy refuses it as the original did).
    bool sdo_information = true;
    // What the reading could not get, one line each (written as comments and as the missing: list).
    std::vector<std::string> missing;
};

class DictionaryFileError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

// Reads a file, or the text of one (name: used in the messages). Throws DictionaryFileError.
DeviceDictionary read_dictionary_file(const std::string& path);
DeviceDictionary parse_dictionary(const std::string& yaml_text, const std::string& name = "<dictionary>");

// The text of a dictionary file; header: comment lines put at the top (without '#').
std::string write_dictionary(const DeviceDictionary& d, const std::vector<std::string>& header = {});

// "9a 00 00 00" and back; parse_hex returns false for anything but pairs of hex digits with spaces.
std::string to_hex(const std::vector<std::uint8_t>& bytes);
bool parse_hex(const std::string& text, std::vector<std::uint8_t>& out);

}  // namespace vecat::network
