#include "cia402/drive_io.hpp"

namespace vecat::cia402 {

bool supported(Mode m) noexcept {
    switch (m) {
        case Mode::ProfilePosition:
        case Mode::ProfileVelocity:
        case Mode::ProfileTorque:
        case Mode::Homing:
        case Mode::CyclicPosition:
        case Mode::CyclicVelocity:
        case Mode::CyclicTorque:
            return true;
        default:
            return false;
    }
}

bool fault::injectable(std::uint16_t code) noexcept {
    return code == OverCurrent || code == Encoder || code == FollowingError || code == ReferenceLimit;
}

}  // namespace vecat::cia402
