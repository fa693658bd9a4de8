// How a difference between vecat's reply and the recorded one is judged. Some register values depend on
// the time or the physical world of the recording and no emulation can repeat them: DC times and latches,
// error counters of real cables, the inputs of real process data. Everything else is behaviour, which vecat
// must repeat.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace vecat::replay {

enum class Verdict : std::uint8_t {
    Same,
    TimeDependent,   // DC times, receive times, latches, SYNC start times (ESC datasheet section II 0x09xx)
    Counter,         // error and lost-link counters (0x0300-0x0313), watchdog counters (0x0442-0x0443)
    MailboxPadding,  // a mailbox read's bytes past the message its header announces (ETG.1000.4 5.6: the
                     // length gives the data; the rest of the SyncManager's area holds whatever the device's
                     // memory held before)
    Timing,          // vecat's reply is one the real device gave to the same read a little earlier or later:
                     // the device got there at another time (a state change, a mailbox reply, an EEPROM read)
    ProcessData,     // logical reads: the inputs of the recorded machine
    Differs,         // behaviour
};
std::string_view to_string(Verdict v) noexcept;

// The class of one register byte of a physical read.
Verdict register_class(std::uint16_t address) noexcept;

// A short name of the register or area at an address ("AL status", "SM1", "FMMU 2", "process RAM", ...).
std::string area_name(std::uint16_t address);

}  // namespace vecat::replay
