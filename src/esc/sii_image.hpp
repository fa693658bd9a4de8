// The SII EEPROM image (ETG.2010) of a device description: what the emulated ESC holds in its EEPROM. The
// layout and its parse are in protocol/sii.hpp.
#pragma once

#include <cstdint>
#include <vector>

#include "common/bytes.hpp"
#include "device/device_description.hpp"
#include "protocol/sii.hpp"

namespace vecat::esc {

// Builds the EEPROM image. The returned vector is the full EEPROM (eeprom_size_bytes), unused bytes 0xFF.
std::vector<std::uint8_t> build_sii_image(const device::DeviceDescription& d);

}  // namespace vecat::esc
