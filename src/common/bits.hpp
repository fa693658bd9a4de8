// Copying bit fields between byte buffers (LSB first, as EtherCAT maps process data and FMMUs do).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace vecat {

// The general case of copy_bits below: any bit offsets and lengths (out of line, so that the common case
// inlines).
[[gnu::noinline]] inline void copy_bits_unaligned(std::uint8_t* dst, std::size_t dst_off,
                                                  const std::uint8_t* src, std::size_t src_off,
                                                  std::size_t n) noexcept {
    if (n == 0) return;
    if ((dst_off | src_off) % 8 == 0) {
        std::memcpy(dst + dst_off / 8, src + src_off / 8, n / 8);
        if (n % 8 == 0) return;
        const std::size_t done = n - n % 8;
        dst_off += done;
        src_off += done;
        n -= done;
    }
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t s = src_off + i;
        const std::size_t d = dst_off + i;
        const auto bit = static_cast<std::uint8_t>((src[s / 8] >> (s % 8)) & 1u);
        const auto mask = static_cast<std::uint8_t>(1u << (d % 8));
        dst[d / 8] = static_cast<std::uint8_t>(bit ? (dst[d / 8] | mask) : (dst[d / 8] & ~mask));
    }
}

// Copies n bits from src (starting at bit src_off) to dst (starting at bit dst_off). Whole bytes at byte
// boundaries are copied with memcpy. The caller guarantees both ranges lie inside their buffers.
inline void copy_bits(std::uint8_t* dst, std::size_t dst_off, const std::uint8_t* src, std::size_t src_off,
                      std::size_t n) noexcept {
    if ((dst_off | src_off | n) % 8 != 0) {
        copy_bits_unaligned(dst, dst_off, src, src_off, n);
        return;
    }
    // Whole objects of 1, 2, 4 or 8 bytes (nearly every mapped entry, every cycle): fixed-size copies the
    // compiler inlines, instead of a library call per entry.
    std::uint8_t* d = dst + dst_off / 8;
    const std::uint8_t* s = src + src_off / 8;
    switch (n / 8) {
        case 0:
            return;
        case 1:
            *d = *s;
            return;
        case 2:
            std::memcpy(d, s, 2);
            return;
        case 4:
            std::memcpy(d, s, 4);
            return;
        case 8:
            std::memcpy(d, s, 8);
            return;
        default:
            std::memcpy(d, s, n / 8);
            return;
    }
}

}  // namespace vecat
