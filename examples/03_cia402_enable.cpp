// 03_cia402_enable: walk a drive's CiA 402 state machine with the controlword (6 Shutdown, 7 Switch on,
// 15 Enable operation) over process data, and decode the statusword the drive answers with.
#include <cstdio>

#include "testing/virtual_segment.hpp"

using namespace vecat;

namespace {
// The state bits of the statusword (CiA 402 Table 30: bits 0-3, 5, 6).
const char* state_name(std::uint16_t sw) {
    switch (sw & 0x6F) {
        case 0x00:
        case 0x20:
            return "Not ready to switch on";
        case 0x40:
        case 0x60:
            return "Switch on disabled";
        case 0x21:
            return "Ready to switch on";
        case 0x23:
            return "Switched on";
        case 0x27:
            return "Operation enabled";
        case 0x07:
            return "Quick stop active";
        case 0x0F:
        case 0x2F:
            return "Fault reaction active";
        case 0x08:
        case 0x28:
            return "Fault";
        default:
            return "?";
    }
}
}  // namespace

int main() {
    testing::VirtualSegment vs({.drives = 1});  // in OP, process data running
    vs.set_mode(0, 8);                          // cyclic synchronous position
    vs.cycles(3);
    std::printf("after start-up: statusword 0x%04X %s\n", vs.statusword(0), state_name(vs.statusword(0)));

    const std::uint16_t expected[] = {0x21, 0x23, 0x27};
    int step = 0;
    for (const std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}}) {
        vs.set_controlword(0, cw);
        vs.set_target_position(0, vs.position(0));  // CSP: hold where the axis stands when it enables
        vs.cycles(3);  // the statusword answers one cycle later (inputs are read before the firmware runs)
        const std::uint16_t sw = vs.statusword(0);
        std::printf("controlword %2u -> statusword 0x%04X %s\n", cw, sw, state_name(sw));
        if ((sw & 0x6F) != expected[step++]) return 1;
    }
    // Back down: controlword 0 (disable voltage) -> Switch on disabled.
    vs.set_controlword(0, 0);
    vs.cycles(3);
    std::printf("controlword  0 -> statusword 0x%04X %s\n", vs.statusword(0), state_name(vs.statusword(0)));
    return (vs.statusword(0) & 0x4F) == 0x40 ? 0 : 1;
}
