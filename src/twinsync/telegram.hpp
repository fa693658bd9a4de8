// The TWINsync data telegram (specification CB08759-001 section 4.1.3), bit-exact:
//   standard mapping:  CRC16 | TWINsync status word | DriveCom control or status word | PDO bytes
//   extended mapping:  CRC16 | PDO bytes
// All words little-endian. The CRC covers every byte after it. The specification does not name the CRC
// polynomial; vecat uses CRC-16/CCITT-FALSE (polynomial 0x1021, initial value 0xFFFF, no reflection).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>

#include "common/bytes.hpp"
#include "twinsync/parameters.hpp"

namespace vecat::twinsync {

enum class Layout : std::uint8_t { Standard, Extended };

inline constexpr std::size_t kMaxFrameBytes = 32;  // 6..32 bytes on the wire
inline constexpr std::size_t kMaxPdoBytes = 30;
inline constexpr std::size_t header_bytes(Layout l) noexcept {
    return l == Layout::Standard ? 6 : 2;
}

// P2709[1] frame size selection 0..13: PDO bytes of each layout. A selection gives the same frame length
// in both layouts (the extended layout uses the four bytes of the two fixed words for PDOs), as the
// table of section 6.2.13 gives it; the table in 4.1 differs from it for selections 4, 5 and 10-13 and
// is inconsistent with the 6-32 byte frame, so vecat follows 6.2.13.
inline constexpr std::uint16_t kFrameSizeSelections = 14;
std::optional<std::size_t> pdo_bytes(Layout l, std::uint16_t frame_size_selection) noexcept;
std::optional<std::size_t> frame_bytes(Layout l, std::uint16_t frame_size_selection) noexcept;

std::uint16_t crc16(ConstBytes data) noexcept;

// The TWINsync status word (table 4.5), sent in every standard telegram and shown received in P2617.
struct TwinStatusWord {
    bool cyclic = false;                   // bit 0: process data mode (0 initialisation, 1 cyclic)
    std::uint8_t switching_frequency = 1;  // bits 1-3: 0 2 kHz, 1 4 kHz, 2 6 kHz, 3 8 kHz, 4 12, 5 16
    Role mode = Role::Off;                 // bits 4-5
    std::uint8_t drivecom_state = 0;       // bits 7-10: DriveCom state (see DriveComState)
    bool chopper = false;                  // bit 11
    bool pwm_counting_down = false;        // bit 12
    bool pwm_disable_event = false;        // bit 13
    bool system_error = false;             // bit 14: drive in the error state
    bool techopt_error = false;            // bit 15: a communication error is pending

    std::uint16_t pack() const noexcept;
    static TwinStatusWord unpack(std::uint16_t w) noexcept;
    bool operator==(const TwinStatusWord&) const = default;
};

// DriveCom states of the MSD drive as its display numbers them (state 5 = "Control").
enum class DriveComState : std::uint8_t {
    Start = 0,
    NotReadyToSwitchOn = 1,
    SwitchOnDisabled = 2,
    ReadyToSwitchOn = 3,
    SwitchedOn = 4,
    OperationEnabled = 5,
    QuickStopActive = 6,
    FaultReactionActive = 7,
    Fault = 8,
};

// TWINsync control word P2611 (table 5.1): what the master drive tells the slave drive.
namespace control {
inline constexpr std::uint16_t EnableOperation = 1u << 5;
inline constexpr std::uint16_t SwitchOn = 1u << 6;
inline constexpr std::uint16_t CoastStop = 1u << 7;  // 1 = coast stop requested (no torque)
inline constexpr std::uint16_t QuickStop = 1u << 8;  // 1 = quick stop requested
inline constexpr std::uint16_t StartHoming = 1u << 9;
inline constexpr std::uint16_t FaultReset = 1u << 10;
inline constexpr std::uint16_t EnableVoltage = 1u << 11;
inline constexpr std::uint16_t ReSyncPosition = 1u << 12;
}  // namespace control

// TWINsync status word P2612 (table 5.2): what the slave drive reports.
namespace slave_status {
inline constexpr std::uint16_t OperationEnabled = 1u << 5;
inline constexpr std::uint16_t Fault = 1u << 6;
inline constexpr std::uint16_t HomePositionSet = 1u << 9;
inline constexpr std::uint16_t OpInProgress = 1u << 12;
inline constexpr unsigned DriveComShift = 13;  // bits 13-15: DriveCom state (3 bits; Fault shows as 0)
}  // namespace slave_status

// The master drive's CiA 402 controlword (0x6040) as the TWINsync control word, and back. The CiA 402
// "disable voltage" (bit 1 = 0) is the coast stop, its active-low quick stop (bit 2 = 0) the quick stop.
// Homing start is bit 4 in homing mode; vecat takes the re-synchronisation request from the
// manufacturer-specific controlword bit 11.
std::uint16_t control_word_from_cia402(std::uint16_t controlword, bool homing_mode) noexcept;
std::uint16_t cia402_from_control_word(std::uint16_t twin_control) noexcept;
inline constexpr std::uint16_t kCia402ResyncBit = 1u << 11;

// One telegram as the drive sees it.
struct Telegram {
    Layout layout = Layout::Standard;
    std::uint16_t status = 0;         // standard only: TWINsync status word
    std::uint16_t drivecom_word = 0;  // standard only: P2611 (from the master) or P2612 (from the slave)
    std::uint8_t pdo_size = 0;
    std::array<std::uint8_t, kMaxPdoBytes> pdo{};
};

enum class DecodeError : std::uint8_t { None, Length, Crc };

// Writes the telegram with its CRC; returns the frame length, 0 if out is too small.
std::size_t encode(const Telegram& t, Bytes out) noexcept;
// Checks length (frame_bytes of the layout with t.pdo_size) and CRC.
DecodeError decode(ConstBytes frame, Layout layout, std::size_t pdo_size, Telegram& out) noexcept;

}  // namespace vecat::twinsync
