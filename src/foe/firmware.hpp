// vecat's firmware file: what a device in BOOT accepts as new firmware (src/foe/README.md).
//
// A firmware file is one an FoE write names "*.efw" (the extension of EtherCAT firmware files, case
// insensitive). Its first line, up to a line feed, is the header:
//
//     vecat-firmware revision=0x00020000 product=0x00000402
//
// "vecat-firmware", then key=value fields separated by spaces: revision (required) is the revision the
// device reports after the update, in the SII (words 0x000C/0x000D) and in 0x1018:03; product (optional)
// must be the device's product code. Numbers are decimal or 0x-hexadecimal. Whatever follows the header
// is the "image": stored with the file, not interpreted.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "common/bytes.hpp"

namespace vecat::foe {

inline constexpr std::string_view kFirmwareMagic = "vecat-firmware";
inline constexpr std::string_view kFirmwareExtension = ".efw";
inline constexpr std::size_t kMaxFirmwareHeaderLine = 256;

struct FirmwareHeader {
    std::uint32_t revision = 0;
    std::optional<std::uint32_t> product;
};

// True when a file of this name is a firmware file (only written in BOOT).
bool is_firmware_name(std::string_view name) noexcept;

// The header of a firmware file; nullopt (and why) when the file is not a vecat firmware file.
std::optional<FirmwareHeader> parse_firmware(ConstBytes file, std::string* why = nullptr);

// The header line of a firmware file for this revision (and product), with its line feed (tests, tools).
std::string firmware_header_line(std::uint32_t revision, std::optional<std::uint32_t> product = std::nullopt);

}  // namespace vecat::foe
