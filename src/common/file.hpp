// Reading a whole input file (network, dictionary, scenario, ENI and ESI files, SII dumps) with a limit: a
// path to a device that never ends (/dev/zero) or a huge file is refused when the limit is passed, instead
// of filling the memory or reading for ever; a pipe (a shell's <(...)) reads like a file.
#pragma once

#include <cstddef>
#include <fstream>
#include <optional>
#include <string>

namespace vecat {

// Sizes for the kinds of input (generous for real files of each kind).
inline constexpr std::size_t kMaxTextFileBytes = 16u << 20;  // YAML: network, dictionary, scenario files
inline constexpr std::size_t kMaxXmlFileBytes = 256u << 20;  // ESI and ENI files
inline constexpr std::size_t kMaxSiiFileBytes = 4u << 20;    // SII dumps (an SII EEPROM is at most 4 MiB)

// The file's bytes, or nullopt with why: "cannot be read" or "is larger than N MiB".
inline std::optional<std::string> read_whole_file(const std::string& path, std::size_t max_bytes,
                                                  std::string& why) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        why = "cannot be read";
        return std::nullopt;
    }
    std::string out;
    char chunk[65536];
    while (in.read(chunk, sizeof chunk) || in.gcount() > 0) {
        out.append(chunk, static_cast<std::size_t>(in.gcount()));
        if (out.size() > max_bytes) {
            why = "is larger than " + std::to_string(max_bytes >> 20) + " MiB";
            return std::nullopt;
        }
    }
    if (in.bad()) {
        why = "cannot be read";
        return std::nullopt;
    }
    return out;
}

}  // namespace vecat
