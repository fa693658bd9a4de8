// The parameters the drive core tests start from (test_drive_core.cpp, test_settled_drive.cpp): a profile
// of one revolution per second, a position window, and the software position limits off.
#pragma once

#include "cia402/drive_io.hpp"

namespace vecat::cia402 {

inline void set_test_profile(DriveIo& io) {
    io.parameters.profile_velocity = 1u << 20;
    io.parameters.profile_acceleration = 10u << 20;
    io.parameters.profile_deceleration = 10u << 20;
    io.parameters.position_window = 100;
    // 0x607D as the vecat drive has it (0/0: off). Absent, the core clamps positions to 0, as the adapter
    // always did for a dictionary without the object (drive_io.hpp).
    io.parameters.software_limit_min = 0;
    io.parameters.software_limit_max = 0;
}

}  // namespace vecat::cia402
