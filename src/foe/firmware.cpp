#include "foe/firmware.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdio>

namespace vecat::foe {

namespace {

std::optional<std::uint32_t> parse_number(std::string_view s) {
    int base = 10;
    if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
        s.remove_prefix(2);
        base = 16;
    }
    std::uint32_t v = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v, base);
    if (ec != std::errc{} || end != s.data() + s.size() || s.empty()) return std::nullopt;
    return v;
}

bool fail(std::string* why, std::string text) {
    if (why) *why = std::move(text);
    return false;
}

}  // namespace

bool is_firmware_name(std::string_view name) noexcept {
    if (name.size() < kFirmwareExtension.size()) return false;
    const auto ext = name.substr(name.size() - kFirmwareExtension.size());
    return std::equal(ext.begin(), ext.end(), kFirmwareExtension.begin(),
                      [](char a, char b) { return std::tolower(static_cast<unsigned char>(a)) == b; });
}

std::optional<FirmwareHeader> parse_firmware(ConstBytes file, std::string* why) {
    const std::string_view all(reinterpret_cast<const char*>(file.data()),
                               std::min(file.size(), kMaxFirmwareHeaderLine));
    const auto eol = all.find('\n');
    if (eol == std::string_view::npos) {
        fail(why, "no header line (\"vecat-firmware revision=...\" and a line feed in the first " +
                      std::to_string(kMaxFirmwareHeaderLine) + " bytes)");
        return std::nullopt;
    }
    std::string_view line = all.substr(0, eol);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.substr(0, kFirmwareMagic.size()) != kFirmwareMagic ||
        (line.size() > kFirmwareMagic.size() && line[kFirmwareMagic.size()] != ' ')) {
        fail(why, "not a vecat firmware file (the first line must start with \"vecat-firmware\")");
        return std::nullopt;
    }
    line.remove_prefix(kFirmwareMagic.size());
    FirmwareHeader h;
    bool have_revision = false;
    while (!line.empty()) {
        while (!line.empty() && line.front() == ' ')
            line.remove_prefix(1);
        if (line.empty()) break;
        const auto end = std::min(line.find(' '), line.size());
        const auto field = line.substr(0, end);
        line.remove_prefix(end);
        const auto eq = field.find('=');
        const auto key = field.substr(0, eq);
        const auto value = eq == std::string_view::npos ? std::optional<std::uint32_t>{}
                                                        : parse_number(field.substr(eq + 1));
        if (!value) {
            fail(why, "header field \"" + std::string(field) + "\" is not key=number");
            return std::nullopt;
        }
        if (key == "revision") {
            h.revision = *value;
            have_revision = true;
        } else if (key == "product") {
            h.product = *value;
        } else {
            fail(why, "unknown header field \"" + std::string(key) + "\"");
            return std::nullopt;
        }
    }
    if (!have_revision) {
        fail(why, "the header names no revision");
        return std::nullopt;
    }
    return h;
}

std::string firmware_header_line(std::uint32_t revision, std::optional<std::uint32_t> product) {
    char buf[96];
    if (product)
        std::snprintf(buf, sizeof buf, "%s revision=0x%08X product=0x%08X\n", kFirmwareMagic.data(), revision,
                      *product);
    else
        std::snprintf(buf, sizeof buf, "%s revision=0x%08X\n", kFirmwareMagic.data(), revision);
    return buf;
}

}  // namespace vecat::foe
