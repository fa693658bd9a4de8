// Homing mode (CiA 402 / IEC 61800-7-201, 0x6098 methods 1-14, 17-30, 33, 34, 35, 37): a state machine
// that, cycle by cycle, turns the switch and index signals into velocity commands and finally reports the
// home position it found.
#pragma once

#include <cstdint>

namespace vecat::cia402 {

class Homing {
  public:
    // TODO(issue 5): see the homing helper's brief.
};

}  // namespace vecat::cia402
