// The errors of the TWINsync monitoring (MSD TWINsync specification CB08759-001 chapter 7) as MSD error
// numbers, and the bits of P2619 that report them.
#pragma once

#include <cstdint>

namespace vecat::twinsync {

// MSD error numbers of the TWINsync monitoring (chapter 7): number-location.
struct ErrorId {
    std::uint8_t number = 0;
    std::uint8_t location = 0;
    bool operator==(const ErrorId&) const = default;
};
namespace error {
inline constexpr ErrorId Communication{40, 0};       // faulty or missing telegrams > P2613, or sync lost
inline constexpr ErrorId SwitchingFrequency{40, 1};  // master and slave switching frequencies differ
inline constexpr ErrorId ModeConflict{40, 2};        // both master or both slave
inline constexpr ErrorId DriveComState{40, 4};       // different DriveCom states
inline constexpr ErrorId SpeedDifference{39, 0};     // gantry: speed (or position) tracking error
inline constexpr ErrorId TorqueDifference{39, 1};    // torque difference
inline constexpr ErrorId OtherAxis{39, 2};           // error detected on the other axis
}  // namespace error

// P2619 bits. vecat reads bit 0 "no error" as set while no error bit is.
namespace comm_status {
inline constexpr std::uint16_t NoError = 1u << 0;
inline constexpr std::uint16_t CommunicationLost = 1u << 1;
inline constexpr std::uint16_t SwitchingFrequency = 1u << 2;
inline constexpr std::uint16_t ModeConflict = 1u << 3;
inline constexpr std::uint16_t DriveComState = 1u << 5;
}  // namespace comm_status

}  // namespace vecat::twinsync
