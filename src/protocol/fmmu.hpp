// The FMMU configuration block (ETG.1000.4 6.6; ESC datasheet section II, registers 0x0600 + 16 n): maps a
// range of the logical address space, bit by bit, onto the physical memory of one ESC.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "common/bytes.hpp"

namespace vecat::protocol {

inline constexpr unsigned kFmmuSize = 16;
inline constexpr unsigned kMaxFmmus = 16;

// Offsets inside one FMMU block; bytes 13..15 are reserved.
namespace fmmu {
inline constexpr unsigned LogicalStart = 0;  // u32
inline constexpr unsigned Length = 4;        // u16, bytes
inline constexpr unsigned LogicalStartBit = 6;
inline constexpr unsigned LogicalStopBit = 7;
inline constexpr unsigned PhysicalStart = 8;  // u16
inline constexpr unsigned PhysicalStartBit = 10;
inline constexpr unsigned Type = 11;
inline constexpr unsigned Activate = 12;

inline constexpr std::uint8_t BitMask = 0x07;  // start/stop bit fields: bits 0..2
inline constexpr std::uint8_t TypeRead = 0x01;
inline constexpr std::uint8_t TypeWrite = 0x02;
inline constexpr std::uint8_t ActivateBit = 0x01;
}  // namespace fmmu

struct FmmuConfig {
    static constexpr std::size_t kSize = kFmmuSize;
    std::uint32_t logical_start = 0;
    std::uint16_t length = 0;  // bytes of the logical range (first and last partly, by the bit fields)
    std::uint8_t logical_start_bit = 0;
    std::uint8_t logical_stop_bit = 7;
    std::uint16_t physical_start = 0;
    std::uint8_t physical_start_bit = 0;
    bool read = false;   // the FMMU serves logical reads (inputs)
    bool write = false;  // ... and logical writes (outputs)
    bool active = false;

    // A byte-aligned mapping of length bytes, as a master configures process data.
    static constexpr FmmuConfig bytes(std::uint32_t logical, std::uint16_t len, std::uint16_t physical,
                                      bool reads, bool writes) noexcept {
        return {logical, len, 0, 7, physical, 0, reads, writes, true};
    }

    void pack(std::span<std::uint8_t, kSize> out) const noexcept {
        std::uint8_t* p = out.data();
        st_le32(p + fmmu::LogicalStart, logical_start);
        st_le16(p + fmmu::Length, length);
        p[fmmu::LogicalStartBit] = logical_start_bit & fmmu::BitMask;
        p[fmmu::LogicalStopBit] = logical_stop_bit & fmmu::BitMask;
        st_le16(p + fmmu::PhysicalStart, physical_start);
        p[fmmu::PhysicalStartBit] = physical_start_bit & fmmu::BitMask;
        p[fmmu::Type] =
            static_cast<std::uint8_t>((read ? fmmu::TypeRead : 0) | (write ? fmmu::TypeWrite : 0));
        p[fmmu::Activate] = active ? fmmu::ActivateBit : 0;
        for (unsigned i = fmmu::Activate + 1; i < kSize; ++i)
            p[i] = 0;
    }

    static FmmuConfig unpack(std::span<const std::uint8_t, kSize> in) noexcept {
        const std::uint8_t* p = in.data();
        return {ld_le32(p + fmmu::LogicalStart),
                ld_le16(p + fmmu::Length),
                static_cast<std::uint8_t>(p[fmmu::LogicalStartBit] & fmmu::BitMask),
                static_cast<std::uint8_t>(p[fmmu::LogicalStopBit] & fmmu::BitMask),
                ld_le16(p + fmmu::PhysicalStart),
                static_cast<std::uint8_t>(p[fmmu::PhysicalStartBit] & fmmu::BitMask),
                (p[fmmu::Type] & fmmu::TypeRead) != 0,
                (p[fmmu::Type] & fmmu::TypeWrite) != 0,
                (p[fmmu::Activate] & fmmu::ActivateBit) != 0};
    }

    friend bool operator==(const FmmuConfig&, const FmmuConfig&) = default;
};

}  // namespace vecat::protocol
