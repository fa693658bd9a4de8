// Consistency checks between an ESI file, an SII image and the dictionary, and schema validation with
// xmllint.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "device/device_description.hpp"

namespace vecat::esi {

// Runs `xmllint --noout --schema XSD FILE`; true when valid. Its messages go to *output.
bool validate_with_xmllint(const std::string& file, const std::string& xsd, std::string* output);

// What disagrees between a description (read from an ESI), its dictionary and an SII image, one line
// per finding ("SM2 length: ESI 12, SII 16").
std::vector<std::string> check_consistency(const device::DeviceDescription& d,
                                           const std::vector<std::uint8_t>& sii);

// Byte-by-byte comparison of a generated SII image with a reference image: one entry per differing byte
// (bytes past the shorter image's end are summarised in one entry), with the field or category it falls
// in and why it differs.
struct SiiByteDiff {
    std::size_t offset = 0;
    int generated = -1;  // -1: past the end of that image
    int reference = -1;
    std::string where;  // "word 0x3E EEPROM size", "category Strings +5"...
    std::string why;
};
std::vector<SiiByteDiff> diff_sii(const std::vector<std::uint8_t>& generated,
                                  const std::vector<std::uint8_t>& reference);

}  // namespace vecat::esi
