// FoE wire format (ETG.1000.6 5.8, File access over EtherCAT): the 6-byte FoE header after the mailbox
// header, its opcodes, the error codes with their texts, and the six messages (read and write request, data,
// ack, error, busy). Shared by the slave's FoE server (src/foe) and the project's master (src/master).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "common/bytes.hpp"

namespace vecat::protocol {

// FoE opcodes (ETG.1000.6 Table 92).
enum class FoeOpCode : std::uint8_t {
    Read = 0x01,   // read request: password, file name
    Write = 0x02,  // write request: password, file name
    Data = 0x03,   // packet number, data
    Ack = 0x04,    // packet number
    Error = 0x05,  // error code, error text
    Busy = 0x06,   // done, entire, busy text
};

// The FoE header: opcode (1), reserved (1), then 4 bytes whose meaning depends on the opcode (password,
// packet number, error code, or done and entire of a busy message). What follows is the file name, the
// data, or the error or busy text.
inline constexpr std::size_t kFoeHeaderSize = 6;
// Largest file name vecat's FoE server accepts (and the master sends): real devices keep a short name
// buffer (SOES: FOE_FN_MAX); 255 keeps it bounded and covers any real firmware file name.
inline constexpr std::size_t kFoeMaxFileName = 255;

// FoE error codes (ETG.1000.6 Table 93).
enum class FoeError : std::uint32_t {
    NotDefined = 0x8000,
    NotFound = 0x8001,
    AccessDenied = 0x8002,
    DiskFull = 0x8003,
    Illegal = 0x8004,
    PacketNumberWrong = 0x8005,
    AlreadyExists = 0x8006,
    NoUser = 0x8007,
    BootstrapOnly = 0x8008,
    NotInBootstrap = 0x8009,
    NoRights = 0x800A,
    ProgramError = 0x800B,
};

// The text of an error code (ETG.1000.6 Table 93), sent as the error text of an FoE error message.
constexpr std::string_view describe(FoeError e) noexcept {
    switch (e) {
        case FoeError::NotDefined:
            return "Not defined";
        case FoeError::NotFound:
            return "Not found";
        case FoeError::AccessDenied:
            return "Access denied";
        case FoeError::DiskFull:
            return "Disk full";
        case FoeError::Illegal:
            return "Illegal";
        case FoeError::PacketNumberWrong:
            return "Packet number wrong";
        case FoeError::AlreadyExists:
            return "Already exists";
        case FoeError::NoUser:
            return "No user";
        case FoeError::BootstrapOnly:
            return "Bootstrap only";
        case FoeError::NotInBootstrap:
            return "Not in bootstrap";
        case FoeError::NoRights:
            return "No rights";
        case FoeError::ProgramError:
            return "Program error";
    }
    return "Unknown FoE error";
}

// One FoE message as it is on the wire (after the mailbox header).
struct FoeMessage {
    FoeOpCode op = FoeOpCode::Read;
    // Read/Write: the password; Data/Ack: the packet number; Error: the error code. Busy: done (low 16
    // bits) and entire (high 16 bits), see busy_done()/busy_entire().
    std::uint32_t value = 0;
    ConstBytes tail;  // file name, data, error text or busy text (a view into the parsed buffer)

    std::uint16_t busy_done() const noexcept { return static_cast<std::uint16_t>(value); }
    std::uint16_t busy_entire() const noexcept { return static_cast<std::uint16_t>(value >> 16); }
    std::string_view text() const noexcept {
        return {reinterpret_cast<const char*>(tail.data()), tail.size()};
    }
};

// Parses an FoE payload (the mailbox payload of type FoE). nullopt when it is shorter than the FoE header
// or the opcode is none of the six; never reads past payload.
std::optional<FoeMessage> parse_foe(ConstBytes payload) noexcept;
// True when b is an opcode of Table 92.
bool is_foe_opcode(std::uint8_t b) noexcept;

// Writers: each returns the payload length written into out, or 0 when out is too short for the header.
// A tail longer than out holds is cut (the caller sizes data packets from the mailbox length).
std::size_t write_foe(Bytes out, FoeOpCode op, std::uint32_t value, ConstBytes tail = {}) noexcept;
std::size_t write_foe_request(Bytes out, FoeOpCode op, std::uint32_t password,
                              std::string_view name) noexcept;
std::size_t write_foe_data(Bytes out, std::uint32_t packet, ConstBytes data) noexcept;
std::size_t write_foe_ack(Bytes out, std::uint32_t packet) noexcept;
// The error message with the code's text (ETG.1000.6 5.8.6) or the given text.
std::size_t write_foe_error(Bytes out, FoeError e, std::string_view text = {}) noexcept;
std::size_t write_foe_busy(Bytes out, std::uint16_t done, std::uint16_t entire,
                           std::string_view text = {}) noexcept;

// The data a DATA packet can carry in a mailbox of mailbox_length bytes (SM length): the mailbox header and
// the FoE header take 12. A packet shorter than this ends the file (ETG.1000.6 5.8.4).
constexpr std::size_t foe_data_capacity(std::size_t mailbox_length) noexcept {
    constexpr std::size_t kHeaders = 6 + kFoeHeaderSize;  // mailbox header + FoE header
    return mailbox_length > kHeaders ? mailbox_length - kHeaders : 0;
}

}  // namespace vecat::protocol
