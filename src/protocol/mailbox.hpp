// The mailbox layer (ETG.1000.4 5.6 / ETG.1000.6 5.6): header, mailbox types and the error reply.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "common/bytes.hpp"

namespace vecat::protocol {

inline constexpr std::size_t kMailboxHeaderSize = 6;
inline constexpr std::size_t kMaxMailboxSize = 1486;  // largest SM0/SM1 length a master uses

enum class MailboxType : std::uint8_t {
    Error = 0x00,
    AoE = 0x01,
    EoE = 0x02,
    CoE = 0x03,
    FoE = 0x04,
    SoE = 0x05,
    VoE = 0x0F,
};

// Mailbox error reply detail codes (ETG.1000.4 Table 30).
enum class MailboxError : std::uint16_t {
    Syntax = 0x0001,
    UnsupportedProtocol = 0x0002,
    InvalidChannel = 0x0003,
    ServiceNotSupported = 0x0004,
    InvalidHeader = 0x0005,
    SizeTooShort = 0x0006,
    NoMoreMemory = 0x0007,
    InvalidSize = 0x0008,
    ServiceInWork = 0x0009,
};

constexpr std::string_view describe(MailboxError e) noexcept {
    switch (e) {
        case MailboxError::Syntax:
            return "Syntax of 6 octet mailbox header is wrong";
        case MailboxError::UnsupportedProtocol:
            return "The mailbox protocol is not supported";
        case MailboxError::InvalidChannel:
            return "Channel field contains wrong value";
        case MailboxError::ServiceNotSupported:
            return "The service in the mailbox protocol is not supported";
        case MailboxError::InvalidHeader:
            return "The mailbox protocol header is wrong";
        case MailboxError::SizeTooShort:
            return "Length of received mailbox data is too short";
        case MailboxError::NoMoreMemory:
            return "Mailbox protocol can not be processed: limited resources";
        case MailboxError::InvalidSize:
            return "The length of data is inconsistent";
        case MailboxError::ServiceInWork:
            return "Mailbox service already in use";
    }
    return "Unknown mailbox error";
}

// The mailbox header (ETG.1000.4 5.6): length(2) address(2), channel (bits 0..5) and priority
// (bits 6..7), type (bits 0..3) and counter (bits 4..6).
struct MailboxHeader {
    static constexpr std::size_t kSize = kMailboxHeaderSize;
    std::uint16_t length = 0;  // bytes following the header
    std::uint16_t address = 0;
    std::uint8_t channel = 0;
    std::uint8_t priority = 0;
    std::uint8_t type = 0;     // MailboxType, kept raw so unknown types can be answered
    std::uint8_t counter = 0;  // 0 = no counter check, else 1..7

    void pack(std::span<std::uint8_t, kSize> out) const noexcept;
    static MailboxHeader unpack(std::span<const std::uint8_t, kSize> in) noexcept;
    friend bool operator==(const MailboxHeader&, const MailboxHeader&) = default;
};

// Checked forms of unpack/pack: nullopt / nothing written when the buffer is shorter than a header.
std::optional<MailboxHeader> parse_mailbox_header(ConstBytes b) noexcept;
void write_mailbox_header(Bytes b, const MailboxHeader& h) noexcept;

// The mailbox error reply (ETG.1000.4 5.6, Table 30): a payload of type MailboxType::Error with service
// 0x0001 and the detail code. Returns its length (0 when payload is too short).
inline constexpr std::uint16_t kMailboxErrorService = 0x0001;
inline constexpr std::size_t kMailboxErrorSize = 4;
std::size_t make_mailbox_error(Bytes payload, MailboxError e) noexcept;

}  // namespace vecat::protocol
