// Signal sources for the inputs of the built-in I/O terminals (network files: inputs:, docs/network-file.md):
// what an input channel reads at a time. The time counts from the terminal's first process data exchange, so
// that a test sees the same signal whenever its master reaches SAFEOP.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace vecat::io {

enum class SignalKind : std::uint8_t {
    Constant,  // value
    Square,    // low for the first half of each period, then high
    Sine,      // offset + amplitude * sin(2 pi t / period)
    Ramp,      // from -> to over each period, then again
    Table,     // (time, value) rows: each value holds from its time to the next row's; the last holds on,
               // or, with a period, the table starts again after it
    Wire,      // the output channel `channel` of the output terminal `device`, or an output PDO entry of it
};

struct Signal {
    SignalKind kind = SignalKind::Constant;
    double value = 0;
    double low = 0, high = 1;
    double amplitude = 1, offset = 0;
    double from = 0, to = 1;
    std::uint64_t period_ns = 1'000'000'000;              // square, sine, ramp; table: 0 = no repetition
    std::uint64_t phase_ns = 0;                           // added to the time
    std::vector<std::pair<std::uint64_t, double>> table;  // rising times
    std::string device;    // wire: the output terminal (its name in the network file)
    unsigned channel = 0;  // ... and its channel
    // A wire that names an output PDO entry of a device of an ESI file or SII dump (DEVICE:0xINDEX:SUB)
    // instead of a channel.
    bool wire_entry = false;
    std::uint16_t wire_index = 0;
    std::uint8_t wire_subindex = 0;
};

// The signal's value t_ns after its start (not for Wire: the terminal reads the wire).
double value_at(const Signal& s, std::uint64_t t_ns) noexcept;

// A table from CSV text: one "time_ms,value" row per line (blank lines and lines starting with # skipped),
// times rising. Throws std::invalid_argument("LINE: what is wrong").
std::vector<std::pair<std::uint64_t, double>> parse_table(const std::string& csv);

}  // namespace vecat::io
