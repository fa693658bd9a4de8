// SoE wire format (ETG.1000.6 5.6, Servo drive profile over EtherCAT; the IDN model of IEC 61800-7-204,
// the SERCOS profile): the 4-byte SoE header after the mailbox header (opcode, incomplete, error, drive
// number, element flags, IDN or fragments left), the element flags, the IDN number and the attribute word,
// and the error codes with their texts. Shared by the slave's SoE server (src/soe) and the project's master
// (src/master/soe_client).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "common/bytes.hpp"

namespace vecat::protocol {

// SoE opcodes (ETG.1000.6 5.6.2, the 3 low bits of the first header byte).
enum class SoeOpCode : std::uint8_t {
    ReadRequest = 0x01,
    ReadResponse = 0x02,
    WriteRequest = 0x03,
    WriteResponse = 0x04,
    Notification = 0x05,  // slave to master: the data state of an IDN changed
    SlaveInfo = 0x06,     // slave to master (emergency-like information)
    Reserved = 0x07,
};

// The SoE header: byte 0 = opcode (bits 0-2), incomplete (bit 3), error (bit 4), drive number (bits 5-7);
// byte 1 = element flags; bytes 2-3 = the IDN, or the fragments still to come when incomplete is set.
inline constexpr std::size_t kSoeHeaderSize = 4;
inline constexpr std::uint8_t kSoeMaxDrives = 8;  // 3 bits of drive number

// Element flags (ETG.1000.6 5.6.2): which elements of an IDN a request reads or writes. A read response
// carries the requested elements in this order (lowest bit first).
namespace soe_element {
inline constexpr std::uint8_t DataState = 0x01;
inline constexpr std::uint8_t Name = 0x02;
inline constexpr std::uint8_t Attribute = 0x04;
inline constexpr std::uint8_t Unit = 0x08;
inline constexpr std::uint8_t Min = 0x10;
inline constexpr std::uint8_t Max = 0x20;
inline constexpr std::uint8_t Value = 0x40;
inline constexpr std::uint8_t Default = 0x80;
}  // namespace soe_element

// The IDN number (IEC 61800-7-204): bit 15 S (standard, 0) or P (product specific, 1), bits 12-14 the
// parameter set, bits 0-11 the data block number. S-0-0024 is 24, P-0-0100 is 0x8064.
struct Idn {
    std::uint16_t raw = 0;
    constexpr bool product() const noexcept { return (raw & 0x8000) != 0; }
    constexpr unsigned set() const noexcept { return (raw >> 12) & 0x7u; }
    constexpr unsigned number() const noexcept { return raw & 0x0FFFu; }
    friend constexpr bool operator==(Idn, Idn) = default;
    friend constexpr auto operator<=>(Idn, Idn) = default;
};
constexpr Idn s_idn(unsigned number, unsigned set = 0) noexcept {
    return Idn{static_cast<std::uint16_t>(((set & 7u) << 12) | (number & 0x0FFFu))};
}
constexpr Idn p_idn(unsigned number, unsigned set = 0) noexcept {
    return Idn{static_cast<std::uint16_t>(0x8000u | ((set & 7u) << 12) | (number & 0x0FFFu))};
}
// "S-0-0024", "P-0-0100".
std::string idn_name(Idn idn);

// The attribute element (IEC 61800-7-204, SERCOS attribute): bits 0-15 conversion factor, bits 16-18 data
// length (code 1, 2, 3: 2, 4, 8 bytes; bit 18 set: a variable-length list of 1/2/4/8-byte elements), bit 19
// procedure command, bits 20-22 data type and display format, bits 24-27 decimal places, bits 28-30 write
// protected in CP2 (PREOP), CP3 (SAFEOP), CP4 (OP).
enum class SoeDataType : std::uint8_t {
    Binary = 0,
    Unsigned = 1,
    Signed = 2,
    Hex = 3,
    Text = 4,  // a list of 1-byte characters
    IdnList = 5,
    Float = 6,
    Parameter = 7,
};
struct SoeAttribute {
    std::uint16_t conversion = 1;
    std::uint8_t length_code = 1;  // 0: 1-byte, 1: 2-byte, 2: 4-byte, 3: 8-byte elements
    bool list = false;             // a variable-length list (current and maximum length, then the elements)
    bool command = false;          // a procedure command
    SoeDataType type = SoeDataType::Unsigned;
    std::uint8_t decimals = 0;  // 0..15
    bool wp_preop = false;      // write protected in CP2
    bool wp_safeop = false;     // CP3
    bool wp_op = false;         // CP4

    std::uint32_t pack() const noexcept;
    static SoeAttribute unpack(std::uint32_t w) noexcept;
    // Bytes of one element (or of the fixed value): 1, 2, 4 or 8.
    constexpr std::size_t element_size() const noexcept { return std::size_t{1} << (length_code & 3u); }
    friend bool operator==(const SoeAttribute&, const SoeAttribute&) = default;
};

// A list element (the value of a list IDN, a name, a unit): current length in bytes (2), maximum length in
// bytes (2), then the current length's bytes.
inline constexpr std::size_t kSoeListHeaderSize = 4;

// SoE error codes (ETG.1000.6 5.6, the SERCOS error codes of IEC 61800-7-204), sent after the header of a
// response with the error flag.
enum class SoeError : std::uint16_t {
    NoIdn = 0x1001,
    InvalidAccessElement1 = 0x1009,
    NoName = 0x2001,
    NameTooShort = 0x2002,
    NameTooLong = 0x2003,
    NameReadOnly = 0x2004,
    NameWriteProtected = 0x2005,
    AttributeTooShort = 0x3002,
    AttributeTooLong = 0x3003,
    AttributeReadOnly = 0x3004,
    AttributeWriteProtected = 0x3005,
    NoUnit = 0x4001,
    UnitTooShort = 0x4002,
    UnitTooLong = 0x4003,
    UnitReadOnly = 0x4004,
    UnitWriteProtected = 0x4005,
    NoMin = 0x5001,
    MinTooShort = 0x5002,
    MinTooLong = 0x5003,
    MinReadOnly = 0x5004,
    MinWriteProtected = 0x5005,
    NoMax = 0x6001,
    MaxTooShort = 0x6002,
    MaxTooLong = 0x6003,
    MaxReadOnly = 0x6004,
    MaxWriteProtected = 0x6005,
    DataTooShort = 0x7002,
    DataTooLong = 0x7003,
    DataReadOnly = 0x7004,
    DataWriteProtected = 0x7005,
    DataBelowMin = 0x7006,
    DataAboveMax = 0x7007,
    DataInvalid = 0x7008,
    DataPasswordProtected = 0x7009,
    DataCyclic = 0x700A,  // configured in the cyclic data (MDT)
    InvalidIndirect = 0x700B,
    DataProtectedBySettings = 0x700C,
    CommandActive = 0x7010,
    CommandNotInterruptible = 0x7011,
    CommandNotNow = 0x7012,  // not executable in this phase
    CommandInvalidParameters = 0x7013,
    NoDataState = 0x7014,
    NoDefault = 0x8001,
    DefaultTooLong = 0x8002,
    DefaultReadOnly = 0x8004,
    InvalidDriveNumber = 0x800A,
    GeneralError = 0x800B,
    NoElementAddressed = 0x800C,
};
std::string_view describe(SoeError e) noexcept;

// One SoE message as it is on the wire (after the mailbox header).
struct SoeMessage {
    SoeOpCode op = SoeOpCode::ReadRequest;
    bool incomplete = false;
    bool error = false;
    std::uint8_t drive = 0;              // 0..7
    std::uint8_t elements = 0;           // soe_element flags
    std::uint16_t idn_or_fragments = 0;  // the IDN, or the fragments left when incomplete
    ConstBytes data;                     // what follows the header (a view into the parsed buffer)

    Idn idn() const noexcept { return Idn{idn_or_fragments}; }
    std::uint16_t fragments_left() const noexcept { return idn_or_fragments; }
    // The error code of a response with the error flag: its last two bytes (nullopt when none).
    std::optional<std::uint16_t> error_code() const noexcept;
};

// Parses an SoE payload (the mailbox payload of type SoE). nullopt when it is shorter than the header;
// every opcode value (1..7, and 0) is returned as it is: the server decides what it serves.
std::optional<SoeMessage> parse_soe(ConstBytes payload) noexcept;

// Writes the header and data (cut to what out holds) and returns the payload length, 0 when out is too
// short for the header.
std::size_t write_soe(Bytes out, const SoeMessage& m) noexcept;
// An error response (ETG.1000.6 5.6.3): the request's opcode + 1 with the error flag, the drive, the
// elements and the IDN of the request, then the error code. Returns the payload length (6).
std::size_t write_soe_error(Bytes out, SoeOpCode response, std::uint8_t drive, std::uint8_t elements, Idn idn,
                            SoeError e) noexcept;

// The data one fragment carries in a mailbox of mailbox_length bytes (SM length): the mailbox header and
// the SoE header take 10.
constexpr std::size_t soe_data_capacity(std::size_t mailbox_length) noexcept {
    constexpr std::size_t kHeaders = 6 + kSoeHeaderSize;  // mailbox header + SoE header
    return mailbox_length > kHeaders ? mailbox_length - kHeaders : 0;
}

}  // namespace vecat::protocol
