// Consistency checks between an ESI file, an SII image and the dictionary, and schema validation with
// xmllint.
#pragma once

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

}  // namespace vecat::esi
