// CoE wire format (ETG.1000.6 5.6): the CoE header, the SDO header and command specifiers, SDO information
// opcodes and the emergency message.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "common/bytes.hpp"

namespace vecat::protocol {

// CoE header: bits 0..8 number, bits 12..15 service.
enum class CoeService : std::uint8_t {
    Emergency = 0x1,
    SdoRequest = 0x2,
    SdoResponse = 0x3,
    TxPdo = 0x4,
    RxPdo = 0x5,
    TxPdoRemoteRequest = 0x6,
    RxPdoRemoteRequest = 0x7,
    SdoInformation = 0x8,
};

constexpr std::uint16_t coe_header(CoeService s, std::uint16_t number = 0) {
    return static_cast<std::uint16_t>((number & 0x01FF) | (static_cast<unsigned>(s) << 12));
}
constexpr CoeService coe_service(std::uint16_t header) {
    return static_cast<CoeService>(header >> 12);
}

inline constexpr std::size_t kCoeHeaderSize = 2;
inline constexpr std::size_t kSdoHeaderSize = 8;      // command, index, subindex, 4 data bytes
inline constexpr std::size_t kSdoInfoHeaderSize = 4;  // opcode, reserved, fragments left
inline constexpr std::size_t kEmergencySize = 8;      // error code, error register, 5 data bytes

// SDO command byte (CiA 301 7.2.4.3, ETG.1000.6 5.6.2).
namespace sdo {
// Client command specifier (bits 5..7 of a request).
inline constexpr std::uint8_t CcsDownloadSegment = 0;
inline constexpr std::uint8_t CcsInitiateDownload = 1;
inline constexpr std::uint8_t CcsInitiateUpload = 2;
inline constexpr std::uint8_t CcsUploadSegment = 3;
inline constexpr std::uint8_t CcsAbort = 4;
// Server command specifier (bits 5..7 of a response).
inline constexpr std::uint8_t ScsUploadSegment = 0;
inline constexpr std::uint8_t ScsDownloadSegment = 1;
inline constexpr std::uint8_t ScsInitiateUpload = 2;
inline constexpr std::uint8_t ScsInitiateDownload = 3;
// Flag bits.
inline constexpr std::uint8_t SizeIndicated = 0x01;
inline constexpr std::uint8_t Expedited = 0x02;
inline constexpr std::uint8_t CompleteAccess = 0x10;
inline constexpr std::uint8_t Toggle = 0x10;
inline constexpr std::uint8_t LastSegment = 0x01;
inline constexpr std::uint8_t AbortCommand = 0x80;

inline constexpr unsigned CsShift = 5;               // command specifier: bits 5..7
inline constexpr unsigned ExpeditedUnusedShift = 2;  // initiate, expedited: 4 - size in bits 2..3
inline constexpr unsigned SegmentUnusedShift = 1;    // segment: 7 - size in bits 1..3
inline constexpr std::size_t kExpeditedMax = 4;
inline constexpr std::size_t kSegmentMin = 7;         // a segment carries at least 7 bytes (the rest unused)
inline constexpr std::size_t kSegmentHeaderSize = 1;  // a segment: the command byte, then the data

constexpr std::uint8_t ccs(std::uint8_t cmd) {
    return static_cast<std::uint8_t>(cmd >> CsShift);
}
// The command byte of an initiate request/response with its flags.
constexpr std::uint8_t command(std::uint8_t cs, std::uint8_t flags = 0) {
    return static_cast<std::uint8_t>((cs << CsShift) | flags);
}
// Expedited transfer of n (1..4) bytes: the size bits and the flags.
constexpr std::uint8_t expedited_size(std::size_t n) {
    return static_cast<std::uint8_t>(((kExpeditedMax - n) << ExpeditedUnusedShift) | Expedited |
                                     SizeIndicated);
}
constexpr std::size_t expedited_length(std::uint8_t cmd) {
    return (cmd & SizeIndicated) ? kExpeditedMax - ((cmd >> ExpeditedUnusedShift) & 3) : kExpeditedMax;
}
// Segment of n bytes: the unused-bytes field (only when fewer than 7 bytes are sent).
constexpr std::uint8_t segment_unused(std::size_t n) {
    return static_cast<std::uint8_t>(n < kSegmentMin ? (kSegmentMin - n) << SegmentUnusedShift : 0);
}
constexpr std::size_t segment_length(std::uint8_t cmd) {
    return kSegmentMin - ((cmd >> SegmentUnusedShift) & 7);
}
}  // namespace sdo

// SDO information opcodes (ETG.1000.6 5.6.3.2).
namespace sdo_info {
inline constexpr std::uint8_t GetOdListRequest = 0x01;
inline constexpr std::uint8_t GetOdListResponse = 0x02;
inline constexpr std::uint8_t GetObjectDescriptionRequest = 0x03;
inline constexpr std::uint8_t GetObjectDescriptionResponse = 0x04;
inline constexpr std::uint8_t GetEntryDescriptionRequest = 0x05;
inline constexpr std::uint8_t GetEntryDescriptionResponse = 0x06;
inline constexpr std::uint8_t InfoErrorRequest = 0x07;
inline constexpr std::uint8_t Incomplete = 0x80;  // more fragments follow

// OD list types.
inline constexpr std::uint16_t ListLengths = 0;
inline constexpr std::uint16_t ListAll = 1;
inline constexpr std::uint16_t ListRxPdoMappable = 2;
inline constexpr std::uint16_t ListTxPdoMappable = 3;
inline constexpr std::uint16_t ListBackup = 4;
inline constexpr std::uint16_t ListSettings = 5;

// Entry description value info bits.
inline constexpr std::uint8_t ValueUnitType = 0x08;
inline constexpr std::uint8_t ValueDefault = 0x10;
inline constexpr std::uint8_t ValueMinimum = 0x20;
inline constexpr std::uint8_t ValueMaximum = 0x40;
}  // namespace sdo_info

// The SDO header after the CoE header (ETG.1000.6 5.6.2): command byte, index, subindex, and four bytes of
// data (the expedited value, the complete size of a normal transfer, or an abort code).
struct SdoHeader {
    static constexpr std::size_t kSize = kSdoHeaderSize;
    std::uint8_t command = 0;
    std::uint16_t index = 0;
    std::uint8_t subindex = 0;
    std::uint32_t data = 0;

    void pack(std::span<std::uint8_t, kSize> out) const noexcept {
        out[0] = command;
        st_le16(out.data() + 1, index);
        out[3] = subindex;
        st_le32(out.data() + 4, data);
    }
    static SdoHeader unpack(std::span<const std::uint8_t, kSize> in) noexcept {
        return {in[0], ld_le16(in.data() + 1), in[3], ld_le32(in.data() + 4)};
    }
    friend bool operator==(const SdoHeader&, const SdoHeader&) = default;
};

// The SDO information header after the CoE header (ETG.1000.6 5.6.3.2): opcode (bits 0..6), incomplete
// (bit 7: more fragments follow), a reserved byte, fragments left (u16).
struct SdoInfoHeader {
    static constexpr std::size_t kSize = kSdoInfoHeaderSize;
    std::uint8_t opcode = 0;
    bool incomplete = false;
    std::uint16_t fragments_left = 0;

    void pack(std::span<std::uint8_t, kSize> out) const noexcept {
        out[0] = static_cast<std::uint8_t>((opcode & ~sdo_info::Incomplete) |
                                           (incomplete ? sdo_info::Incomplete : 0));
        out[1] = 0;
        st_le16(out.data() + 2, fragments_left);
    }
    static SdoInfoHeader unpack(std::span<const std::uint8_t, kSize> in) noexcept {
        return {static_cast<std::uint8_t>(in[0] & ~sdo_info::Incomplete), (in[0] & sdo_info::Incomplete) != 0,
                ld_le16(in.data() + 2)};
    }
    friend bool operator==(const SdoInfoHeader&, const SdoInfoHeader&) = default;
};

// The fixed part of a Get Object Description response (ETG.1000.6 5.6.3.5); the object's name follows.
struct SdoInfoObject {
    static constexpr std::size_t kSize = 6;
    std::uint16_t index = 0;
    std::uint16_t data_type = 0;
    std::uint8_t max_subindex = 0;
    std::uint8_t object_code = 0;

    void pack(std::span<std::uint8_t, kSize> out) const noexcept {
        st_le16(out.data(), index);
        st_le16(out.data() + 2, data_type);
        out[4] = max_subindex;
        out[5] = object_code;
    }
    static SdoInfoObject unpack(std::span<const std::uint8_t, kSize> in) noexcept {
        return {ld_le16(in.data()), ld_le16(in.data() + 2), in[4], in[5]};
    }
    friend bool operator==(const SdoInfoObject&, const SdoInfoObject&) = default;
};

// The fixed part of a Get Entry Description response (ETG.1000.6 5.6.3.6); the values asked for by
// value_info (default, minimum, maximum, each of the entry's size) and the name follow.
struct SdoInfoEntry {
    static constexpr std::size_t kSize = 10;
    std::uint16_t index = 0;
    std::uint8_t subindex = 0;
    std::uint8_t value_info = 0;
    std::uint16_t data_type = 0;
    std::uint16_t bit_length = 0;
    std::uint16_t access = 0;

    void pack(std::span<std::uint8_t, kSize> out) const noexcept {
        st_le16(out.data(), index);
        out[2] = subindex;
        out[3] = value_info;
        st_le16(out.data() + 4, data_type);
        st_le16(out.data() + 6, bit_length);
        st_le16(out.data() + 8, access);
    }
    static SdoInfoEntry unpack(std::span<const std::uint8_t, kSize> in) noexcept {
        return {ld_le16(in.data()),    in[2], in[3], ld_le16(in.data() + 4), ld_le16(in.data() + 6),
                ld_le16(in.data() + 8)};
    }
    friend bool operator==(const SdoInfoEntry&, const SdoInfoEntry&) = default;
};

// An emergency message after the CoE header (ETG.1000.6 5.6.4, CiA 301 7.2.7): the error code, the error
// register (0x1001) and five bytes of manufacturer-specific data.
struct Emergency {
    static constexpr std::size_t kSize = kEmergencySize;
    std::uint16_t error_code = 0;
    std::uint8_t error_register = 0;
    std::array<std::uint8_t, 5> data{};

    void pack(std::span<std::uint8_t, kSize> out) const noexcept {
        st_le16(out.data(), error_code);
        out[2] = error_register;
        std::copy(data.begin(), data.end(), out.begin() + 3);
    }
    static Emergency unpack(std::span<const std::uint8_t, kSize> in) noexcept {
        Emergency e;
        e.error_code = ld_le16(in.data());
        e.error_register = in[2];
        std::copy_n(in.begin() + 3, e.data.size(), e.data.begin());
        return e;
    }
    friend bool operator==(const Emergency&, const Emergency&) = default;
};

// Error register 0x1001 bits (CiA 301 7.5.2.2), also the emergency's second field.
namespace error_register {
inline constexpr std::uint8_t Generic = 0x01;
inline constexpr std::uint8_t Current = 0x02;
inline constexpr std::uint8_t Voltage = 0x04;
inline constexpr std::uint8_t Temperature = 0x08;
inline constexpr std::uint8_t Communication = 0x10;
inline constexpr std::uint8_t DeviceProfile = 0x20;
inline constexpr std::uint8_t Manufacturer = 0x80;
}  // namespace error_register

}  // namespace vecat::protocol
