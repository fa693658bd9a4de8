// 03_cia402_enable: walk a drive's CiA 402 state machine with the controlword (6 Shutdown, 7 Switch on,
// 15 Enable operation) over process data, and decode the statusword the drive answers with.
#include <cstdio>

#include "protocol/cia402.hpp"
#include "testing/virtual_segment.hpp"

using namespace vecat;

namespace cia = protocol::cia402;

namespace {
// The state the statusword shows (CiA 402 Table 30: bits 0-3, 5, 6).
const char* state_name(std::uint16_t sw) {
    const auto s = cia::decode_state(sw);
    return s ? cia::to_string(*s) : "?";
}
}  // namespace

int main() {
    testing::VirtualSegment vs({.drives = 1});  // in OP, process data running
    vs.set_mode(0, static_cast<std::int8_t>(cia::Mode::CyclicPosition));
    vs.cycles(3);
    std::printf("after start-up: statusword 0x%04X %s\n", vs.statusword(0), state_name(vs.statusword(0)));

    using cia::State;
    const State expected[] = {State::ReadyToSwitchOn, State::SwitchedOn, State::OperationEnabled};
    int step = 0;
    for (const std::uint16_t cw : {cia::cmd::Shutdown, cia::cmd::SwitchOn, cia::cmd::EnableOperation}) {
        vs.set_controlword(0, cw);
        vs.set_target_position(0, vs.position(0));  // CSP: hold where the axis stands when it enables
        vs.cycles(3);  // the statusword answers one cycle later (inputs are read before the firmware runs)
        const std::uint16_t sw = vs.statusword(0);
        std::printf("controlword %2u -> statusword 0x%04X %s\n", cw, sw, state_name(sw));
        if (cia::decode_state(sw) != expected[step++]) return 1;
    }
    // Back down: controlword 0 (disable voltage) -> Switch on disabled.
    vs.set_controlword(0, cia::cmd::DisableVoltage);
    vs.cycles(3);
    std::printf("controlword  0 -> statusword 0x%04X %s\n", vs.statusword(0), state_name(vs.statusword(0)));
    return cia::decode_state(vs.statusword(0)) == State::SwitchOnDisabled ? 0 : 1;
}
