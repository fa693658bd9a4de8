// The fault model: which faults vecat can inject, with their parameters (src/faults/README.md).
#pragma once

#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "protocol/al_status.hpp"

namespace vecat::faults {

enum class FaultKind : std::uint8_t {
    Drop,              // frames lost on a cable: the master sees no reply
    Corrupt,           // frames with a wrong FCS: counted by the ESCs behind, dropped, no reply
    Delay,             // replies held back
    LinkDown,          // a port loses its link: the line is cut there
    PowerOff,          // a slave without power: the line is cut before it; back on, it restarts in INIT
    FirmwareHang,      // the slave's firmware stops: AL state, mailbox and inputs freeze, the ESC goes on
    AlError,           // the application forces an AL error with a status code
    SdoAbort,          // SDO requests answered with an abort code
    MailboxLostReply,  // a mailbox request is executed, its reply never appears
    EncoderFault,      // drive: 0x7305
    OverCurrent,       // drive: 0x2310
    FollowingError,    // drive: 0x8611
    DcDrift,           // a DC clock's oscillator drift changes
    Unplug,            // hot connect: a group of devices unplugged; plugged back (INIT) when the fault ends
    External,          // handled outside the injector (TWINsync...): see FaultHandler
};

struct FaultKindInfo {
    std::string_view name;
    FaultKind kind;
    std::string_view parameters;  // the keys it takes besides the common ones
    std::string_view help;
};

// Every built-in fault, and the external ones vecat knows by name (a handler must be registered).
std::span<const FaultKindInfo> fault_kinds();
const FaultKindInfo* find_kind(std::string_view name);

struct FaultSpec {
    std::string name;  // kind name as written ("drop", "twinsync_cable_break"...)
    FaultKind kind = FaultKind::Drop;
    std::string id;  // what stop/clear refer to; given or made up when started

    // Common keys.
    std::size_t slave = 0;          // position on the line (0 = next to the master)
    double probability = 1.0;       // of each frame/request being affected
    std::uint64_t count = 0;        // affected frames/requests before the fault ends (0: no limit)
    std::uint64_t duration_ns = 0;  // ends by itself after this long (0: until stopped)
    // Line faults.
    std::size_t cable = 0;   // drop/corrupt: cable k leads into slave k (0: from the master)
    bool returning = false;  // direction: out (towards the end of the line) or back (towards the master)
    unsigned port = 1;       // link_down
    std::uint64_t delay_ns = 0;
    // Error codes: AL status code, SDO abort code, drive error code.
    std::uint32_t code = 0;
    protocol::AlState state = protocol::AlState::SafeOp;  // al_error: state the slave falls back to
    std::uint16_t index = 0;                              // sdo_abort: only this object (0: any)
    int subindex = -1;                                    // -1: any
    // dc_drift: absolute ppm, or a step added to the current drift.
    double ppm = 0.0;
    bool ppm_is_step = false;
    // unplug: the hot connect group (network file hot_connect:), else the group headed by `slave`.
    std::string group;
    // unplug with to=SLAVE:PORT: plugged back into that port of that slave (positions on the line as it is
    // when the fault starts) instead of where it was.
    bool elsewhere = false;
    std::size_t to_slave = 0;
    unsigned to_port = 0;
    // Every key as given, for external handlers.
    std::map<std::string, std::string> params;
};

using KeyValues = std::vector<std::pair<std::string, std::string>>;

// Builds a fault from its kind name and key/value parameters; throws std::invalid_argument with a message
// naming the bad key or value. Unknown kind names are accepted as external faults.
FaultSpec make_fault(std::string_view name, const KeyValues& kv);
// "kind key=value key=value..." (the control channel's syntax).
FaultSpec parse_fault(std::string_view line);
// One line describing a fault and its parameters.
std::string describe(const FaultSpec& f);

// Durations: "1.5" (seconds), "250ms", "20us", "3s".
std::uint64_t parse_duration_ns(std::string_view v);

}  // namespace vecat::faults
