// CoE wire format (ETG.1000.6 5.6): the CoE header, SDO command specifiers and SDO information opcodes.
#pragma once

#include <cstdint>

namespace vecat::coe {

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

constexpr std::uint8_t ccs(std::uint8_t cmd) {
    return static_cast<std::uint8_t>(cmd >> 5);
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

}  // namespace vecat::coe
