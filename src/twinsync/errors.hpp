// The errors of the TWINsync monitoring (MSD TWINsync specification CB08759-001 chapter 7) as MSD error
// numbers (the bits of P2619 that report them are parameters.hpp's comm_status).
#pragma once

#include <cstdint>

#include "twinsync/parameters.hpp"

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

}  // namespace vecat::twinsync
