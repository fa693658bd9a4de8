#include "protocol/soe.hpp"

#include <algorithm>
#include <cstdio>

namespace vecat::protocol {

namespace {
// Byte 0 of the header.
inline constexpr std::uint8_t kOpMask = 0x07;
inline constexpr std::uint8_t kIncomplete = 0x08;
inline constexpr std::uint8_t kError = 0x10;
inline constexpr unsigned kDriveShift = 5;
// Offsets in the header.
inline constexpr std::size_t kFlags = 0;
inline constexpr std::size_t kElements = 1;
inline constexpr std::size_t kIdn = 2;

// Attribute bits.
inline constexpr unsigned kLengthShift = 16;
inline constexpr std::uint32_t kListBit = 1u << 18;
inline constexpr std::uint32_t kCommandBit = 1u << 19;
inline constexpr unsigned kTypeShift = 20;
inline constexpr unsigned kDecimalsShift = 24;
inline constexpr std::uint32_t kWpPreop = 1u << 28;
inline constexpr std::uint32_t kWpSafeop = 1u << 29;
inline constexpr std::uint32_t kWpOp = 1u << 30;
}  // namespace

std::string idn_name(Idn idn) {
    char b[16];
    std::snprintf(b, sizeof b, "%c-%u-%04u", idn.product() ? 'P' : 'S', idn.set(), idn.number());
    return b;
}

std::uint32_t SoeAttribute::pack() const noexcept {
    std::uint32_t w = conversion;
    w |= static_cast<std::uint32_t>(length_code & 3u) << kLengthShift;
    if (list) w |= kListBit;
    if (command) w |= kCommandBit;
    w |= static_cast<std::uint32_t>(static_cast<std::uint8_t>(type) & 7u) << kTypeShift;
    w |= static_cast<std::uint32_t>(decimals & 0x0Fu) << kDecimalsShift;
    if (wp_preop) w |= kWpPreop;
    if (wp_safeop) w |= kWpSafeop;
    if (wp_op) w |= kWpOp;
    return w;
}

SoeAttribute SoeAttribute::unpack(std::uint32_t w) noexcept {
    SoeAttribute a;
    a.conversion = static_cast<std::uint16_t>(w);
    a.length_code = static_cast<std::uint8_t>((w >> kLengthShift) & 3u);
    a.list = (w & kListBit) != 0;
    a.command = (w & kCommandBit) != 0;
    a.type = static_cast<SoeDataType>((w >> kTypeShift) & 7u);
    a.decimals = static_cast<std::uint8_t>((w >> kDecimalsShift) & 0x0Fu);
    a.wp_preop = (w & kWpPreop) != 0;
    a.wp_safeop = (w & kWpSafeop) != 0;
    a.wp_op = (w & kWpOp) != 0;
    return a;
}

std::string_view describe(SoeError e) noexcept {
    switch (e) {
        case SoeError::NoIdn:
            return "No IDN";
        case SoeError::InvalidAccessElement1:
            return "Invalid access to element 1";
        case SoeError::NoName:
            return "No name";
        case SoeError::NameTooShort:
            return "Name transmission too short";
        case SoeError::NameTooLong:
            return "Name transmission too long";
        case SoeError::NameReadOnly:
            return "Name cannot be changed (read only)";
        case SoeError::NameWriteProtected:
            return "Name is write protected at this time";
        case SoeError::AttributeTooShort:
            return "Attribute transmission too short";
        case SoeError::AttributeTooLong:
            return "Attribute transmission too long";
        case SoeError::AttributeReadOnly:
            return "Attribute cannot be changed (read only)";
        case SoeError::AttributeWriteProtected:
            return "Attribute is write protected at this time";
        case SoeError::NoUnit:
            return "No unit";
        case SoeError::UnitTooShort:
            return "Unit transmission too short";
        case SoeError::UnitTooLong:
            return "Unit transmission too long";
        case SoeError::UnitReadOnly:
            return "Unit cannot be changed (read only)";
        case SoeError::UnitWriteProtected:
            return "Unit is write protected at this time";
        case SoeError::NoMin:
            return "No minimum input value";
        case SoeError::MinTooShort:
            return "Minimum input value transmission too short";
        case SoeError::MinTooLong:
            return "Minimum input value transmission too long";
        case SoeError::MinReadOnly:
            return "Minimum input value cannot be changed (read only)";
        case SoeError::MinWriteProtected:
            return "Minimum input value is write protected at this time";
        case SoeError::NoMax:
            return "No maximum input value";
        case SoeError::MaxTooShort:
            return "Maximum input value transmission too short";
        case SoeError::MaxTooLong:
            return "Maximum input value transmission too long";
        case SoeError::MaxReadOnly:
            return "Maximum input value cannot be changed (read only)";
        case SoeError::MaxWriteProtected:
            return "Maximum input value is write protected at this time";
        case SoeError::DataTooShort:
            return "Operation data transmission too short";
        case SoeError::DataTooLong:
            return "Operation data transmission too long";
        case SoeError::DataReadOnly:
            return "Operation data cannot be changed (read only)";
        case SoeError::DataWriteProtected:
            return "Operation data is write protected at this time (state)";
        case SoeError::DataBelowMin:
            return "Operation data is smaller than the minimum input value";
        case SoeError::DataAboveMax:
            return "Operation data is greater than the maximum input value";
        case SoeError::DataInvalid:
            return "Invalid operation data: configured IDN will not be supported";
        case SoeError::DataPasswordProtected:
            return "Operation data write protected by a password";
        case SoeError::DataCyclic:
            return "Operation data is write protected, it is configured cyclically";
        case SoeError::InvalidIndirect:
            return "Invalid indirect addressing";
        case SoeError::DataProtectedBySettings:
            return "Operation data is write protected due to other settings";
        case SoeError::CommandActive:
            return "Procedure command already active";
        case SoeError::CommandNotInterruptible:
            return "Procedure command not interruptible";
        case SoeError::CommandNotNow:
            return "Procedure command at this time not executable (state)";
        case SoeError::CommandInvalidParameters:
            return "Procedure command not executable (invalid or false parameters)";
        case SoeError::NoDataState:
            return "No data state";
        case SoeError::NoDefault:
            return "No default value";
        case SoeError::DefaultTooLong:
            return "Default value transmission too long";
        case SoeError::DefaultReadOnly:
            return "Default value cannot be changed (read only)";
        case SoeError::InvalidDriveNumber:
            return "Invalid drive number";
        case SoeError::GeneralError:
            return "General error";
        case SoeError::NoElementAddressed:
            return "No element addressed";
    }
    return "Unknown SoE error";
}

std::optional<std::uint16_t> SoeMessage::error_code() const noexcept {
    if (!error || data.size() < 2) return std::nullopt;
    return ld_le16(data.data() + data.size() - 2);
}

std::optional<SoeMessage> parse_soe(ConstBytes payload) noexcept {
    if (payload.size() < kSoeHeaderSize) return std::nullopt;
    SoeMessage m;
    const std::uint8_t b = payload[kFlags];
    m.op = static_cast<SoeOpCode>(b & kOpMask);
    m.incomplete = (b & kIncomplete) != 0;
    m.error = (b & kError) != 0;
    m.drive = static_cast<std::uint8_t>(b >> kDriveShift);
    m.elements = payload[kElements];
    m.idn_or_fragments = ld_le16(payload.data() + kIdn);
    m.data = payload.subspan(kSoeHeaderSize);
    return m;
}

std::size_t write_soe(Bytes out, const SoeMessage& m) noexcept {
    if (out.size() < kSoeHeaderSize) return 0;
    std::uint8_t b = static_cast<std::uint8_t>(static_cast<std::uint8_t>(m.op) & kOpMask);
    if (m.incomplete) b |= kIncomplete;
    if (m.error) b |= kError;
    b = static_cast<std::uint8_t>(b | ((m.drive & 7u) << kDriveShift));
    out[kFlags] = b;
    out[kElements] = m.elements;
    st_le16(out.data() + kIdn, m.idn_or_fragments);
    const std::size_t n = std::min(m.data.size(), out.size() - kSoeHeaderSize);
    std::copy_n(m.data.begin(), n, out.begin() + kSoeHeaderSize);
    return kSoeHeaderSize + n;
}

std::size_t write_soe_error(Bytes out, SoeOpCode response, std::uint8_t drive, std::uint8_t elements, Idn idn,
                            SoeError e) noexcept {
    std::uint8_t code[2];
    st_le16(code, static_cast<std::uint16_t>(e));
    SoeMessage m;
    m.op = response;
    m.error = true;
    m.drive = drive;
    m.elements = elements;
    m.idn_or_fragments = idn.raw;
    m.data = ConstBytes(code, 2);
    if (out.size() < kSoeHeaderSize + 2) return 0;
    return write_soe(out, m);
}

}  // namespace vecat::protocol
