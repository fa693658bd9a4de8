// The mailbox layer (ETG.1000.4 5.6 / ETG.1000.6 5.6): header, counter, error replies.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include "common/bytes.hpp"

namespace vecat::esc {

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

struct MailboxHeader {
    std::uint16_t length = 0;  // bytes following the header
    std::uint16_t address = 0;
    std::uint8_t channel = 0;
    std::uint8_t priority = 0;
    std::uint8_t type = 0;     // MailboxType, kept raw so unknown types can be answered
    std::uint8_t counter = 0;  // 0 = no counter check, else 1..7
};

std::optional<MailboxHeader> parse_mailbox_header(ConstBytes b) noexcept;
void write_mailbox_header(Bytes b, const MailboxHeader& h) noexcept;

// Where a protocol handler puts its answer. The payload excludes the 6-byte mailbox header.
class MailboxReplySink {
  public:
    virtual ~MailboxReplySink() = default;
    // Space for one reply payload of at most max_payload() bytes; commit() sends it.
    virtual Bytes reply_buffer() = 0;
    virtual void commit(MailboxType type, std::size_t payload_len) = 0;
    // True when a commit() now would be queued (not dropped).
    virtual bool can_commit() const = 0;
    // Replies committed but not yet read by the master.
    virtual std::size_t pending() const = 0;
    std::size_t max_payload() { return reply_buffer().size(); }
};

// A mailbox protocol served by the slave application (CoE, FoE, ...).
class MailboxProtocol {
  public:
    virtual ~MailboxProtocol() = default;
    virtual MailboxType type() const = 0;
    // Handles one request. Must answer through the sink (data, abort or mailbox error), never silently.
    virtual void handle(const MailboxHeader& h, ConstBytes payload, MailboxReplySink& out) = 0;
    // Called while the slave is running so a protocol can send unsolicited messages (emergencies).
    virtual void poll(MailboxReplySink&) {}
    // The mailbox was reset (state INIT): forget transfers in progress.
    virtual void reset() {}
};

// Builds a mailbox error reply payload (service 0x0001 + detail).
std::size_t make_mailbox_error(Bytes payload, MailboxError e) noexcept;

}  // namespace vecat::esc
