// What a capture tells about the line it was taken on, so that the replay can build that line without a
// network file: the number of slaves (working counters of broadcast reads), their station addresses (the
// master's auto-increment writes of 0x0010), their ESC information registers (0x0000-0x0009) and DL status
// (0x0110) as first read, and the SII EEPROM words the master read through the SII interface (0x0502-0x050F,
// ESC datasheet section II 3.x / ETG.1000.4 6.4.5).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "replay/capture.hpp"
#include "replay/recover_mailbox.hpp"

namespace vecat::replay {

inline constexpr std::size_t kEscInfoBytes = 10;  // 0x0000-0x0009: type .. features
// At most this many slaves are rebuilt (a broadcast working counter can claim up to 65,535).
inline constexpr std::size_t kMaxRecoveredSlaves = 1024;

// A state change the device refused in the capture: the master wrote AL control for `to` while the device
// was in `from`, and the device answered with the error indication (ETG.1000.6 6.4.1.4). The reason is the
// device's own (its application's checks); the code is the AL status code the master read, or 0x0001
// (unspecified) when it read none.
struct RefusedTransition {
    std::uint8_t from = 0, to = 0;
    std::uint16_t code = 0x0001;
    auto operator<=>(const RefusedTransition&) const = default;
};

struct RecoveredSlave {
    std::optional<std::uint16_t> station;  // configured station address
    std::array<std::optional<std::uint8_t>, kEscInfoBytes> esc_info{};
    // How many of those came from a broadcast read rather than a datagram to this slave alone (see
    // recover_line).
    std::size_t esc_info_from_broadcast = 0;
    std::optional<std::uint16_t> dl_status;
    // DL control (0x0100-0x0103) bytes as first read before the capture wrote them: what the ESC held when
    // the capture began (its reset value, or what an earlier master left; esc::EscConfig::dl_control).
    std::array<std::optional<std::uint8_t>, 4> dl_control{};
    std::optional<bool> sii_read_8_bytes;         // 0x0502 bit 6, as the ESC reported it
    std::optional<bool> sii_two_address_bytes;    // 0x0502 bit 7: an EEPROM larger than 16 Kbit
    std::optional<std::uint8_t> sii_status_bits;  // 0x0502 bits 1-5 as read (esc::EscConfig::sii_status_bits)
    // Whether the ESC has the DC system time unit (esc::EscConfig::dc_system_time_unit): a datagram to this
    // slave alone within 0x0910-0x09FF counted (true) or not counted (false; only when none counted); else
    // from the working counter of broadcast writes there (see recover_line).
    std::optional<bool> dc_system_time_unit;
    // FMMU and SyncManager counts (0x0004, 0x0005) when the master did not read them: worked out from the
    // working counters of its broadcast writes to the 16 FMMU and SyncManager blocks (see recover_line).
    std::optional<std::uint8_t> fmmus_from_writes, sms_from_writes;
    // SII words (index: word address); known[i]: 1 word i was read, 2 it was recovered from a register the
    // ESC loads from it (0x0140, 0x0150, 0x0152, 0x0982, 0x0012), 3 taken from an earlier slave of the same
    // identity, 0 unknown.
    std::vector<std::uint16_t> sii;
    std::vector<std::uint8_t> known;
    // The CoE dictionary as far as the mailbox traffic shows it (recover_mailbox.hpp).
    RecoveredDictionary coe;
    std::vector<RefusedTransition> refused;
    // How long the device's firmware took to read AL control (esc::Slave::set_al_control_latency): just more
    // than the longest gap after which a second write was refused, less than the shortest after which one
    // was accepted; nullopt when no write was refused.
    std::optional<std::uint64_t> al_control_latency_ns;
    std::size_t sii_words_known() const;
};

struct RecoveredLine {
    // From the working counters of broadcast reads of registers and broadcast writes of DL control.
    std::size_t slave_count = 0;
    std::vector<RecoveredSlave> slaves;
};

// Walks every exchange in order. A broadcast write to FMMU block k is counted by the slaves that have more
// than k FMMUs (ESC datasheet section I: writes to absent registers are not counted), so the working counters
// of the writes to blocks 0..15 give how many slaves have each count; which slave has which is not in them:
// the larger counts go to the first slaves (a coupler, with the larger ESC, comes before its terminals). The
// same holds for broadcast writes into the DC system time unit, for slaves that no datagram of their own
// tells about. ESC information and DL control bytes that no datagram to the slave alone read come from a
// broadcast read or the first read before any write (RecoveredSlave). Needs the capture's slave count first
// for replies without their request (auto-increment addresses in a reply have been counted up by every slave
// the frame passed).
RecoveredLine recover_line(const Capture& c, const Pairing& p);

// The request datagram's ADP for a datagram whose capture holds only the reply.
std::uint16_t request_adp(std::uint8_t command, std::uint16_t reply_adp, std::size_t slave_count) noexcept;

}  // namespace vecat::replay
