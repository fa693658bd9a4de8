// Reads the Ethernet frames of a pcapng file (enhanced and simple packet blocks), for replay tests.
#pragma once

#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "common/bytes.hpp"

namespace vecat::test {

inline std::vector<std::vector<std::uint8_t>> read_pcapng_frames(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    const std::vector<std::uint8_t> d((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    std::vector<std::vector<std::uint8_t>> frames;
    std::size_t off = 0;
    while (off + 12 <= d.size()) {
        const std::uint32_t type = ld_le32(d.data() + off);
        const std::uint32_t len = ld_le32(d.data() + off + 4);
        if (len < 12 || off + len > d.size()) break;
        if (type == 6 && len >= 32) {  // enhanced packet block
            const std::uint32_t cap = ld_le32(d.data() + off + 20);
            if (28 + cap <= len)
                frames.emplace_back(d.begin() + static_cast<std::ptrdiff_t>(off + 28),
                                    d.begin() + static_cast<std::ptrdiff_t>(off + 28 + cap));
        } else if (type == 3 && len >= 16) {  // simple packet block
            frames.emplace_back(d.begin() + static_cast<std::ptrdiff_t>(off + 12),
                                d.begin() + static_cast<std::ptrdiff_t>(off + len - 4));
        }
        off += len;
    }
    return frames;
}

}  // namespace vecat::test
