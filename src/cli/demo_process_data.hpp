// The process data of `vecat demo` as the master sees it: each drive's objects at the places its PDO mapping
// puts them (the fixed mapping the demo writes to its own drives, or whatever a device of a network file
// maps), and the I/O terminals whose outputs the demo writes and whose inputs it reads back.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "master/master.hpp"
#include "protocol/cia402.hpp"

namespace vecat::cli {

// Byte offsets of a drive's objects in its slave's outputs and inputs; -1: not mapped.
struct DriveLayout {
    std::size_t slave = 0;  // index in the master's slave list
    int controlword = -1, mode = -1, target = -1;
    int statusword = -1, mode_display = -1, position = -1, velocity = -1, following_error = -1,
        error_code = -1;
    // What a CSP move needs mapped: controlword, target position, statusword, position actual value.
    bool movable() const { return controlword >= 0 && target >= 0 && statusword >= 0 && position >= 0; }
};

// Finds the layout from the entries the master mapped (MappedEntry); objects not byte-aligned, or of another
// length than CiA 402 gives them, count as not mapped.
DriveLayout layout_from_entries(const master::SlaveInfo& s, std::size_t slave);

// One drive as the master sees it: its outputs and the inputs of the last cycle.
struct Axis {
    DriveLayout layout;
    std::uint16_t controlword = 0;
    std::int8_t mode = static_cast<std::int8_t>(protocol::cia402::Mode::CyclicPosition);
    std::int32_t target = 0;
    std::uint16_t statusword = 0;
    std::int8_t mode_display = 0;
    std::int32_t position = 0, velocity = 0, following_error = 0;
    std::uint16_t error_code = 0;
    // The state a statusword shows; a pattern CiA 402 does not give reads as a fault.
    protocol::cia402::State state() const {
        return protocol::cia402::decode_state(statusword).value_or(protocol::cia402::State::Fault);
    }
    // Into / out of the master's process image (what is not mapped is left alone / keeps its value).
    void write_outputs(Bytes out) const;
    void read_inputs(ConstBytes in);
};

// The drives of a network: the CoE slaves whose device type (0x1000) names the CiA 402 profile. Reads 0x1000
// by SDO, so the mailboxes must be configured (PREOP). notes: one line per drive found, and why a drive
// cannot be moved when it cannot.
std::vector<Axis> find_drives(master::Master& m, std::vector<std::string>& notes);

// The slaves with process data that are not drives: the demo writes a walking bit (1-bit entries) and a
// sawtooth (16-bit entries) to their outputs, and counts how often their inputs change.
class IoExercise {
  public:
    IoExercise() = default;
    IoExercise(master::Master& m, const std::vector<Axis>& drives);
    bool empty() const { return slaves_.empty(); }
    std::size_t size() const { return slaves_.size(); }
    // Before the cycle's exchange: the outputs of step `step`.
    void write_outputs(master::Master& m, unsigned step) const;
    // After the exchange.
    void read_inputs(master::Master& m);
    std::uint64_t input_changes() const;
    // One line per terminal: its outputs and inputs, and how often the inputs changed.
    std::vector<std::string> report(master::Master& m) const;

  private:
    struct Terminal {
        std::size_t slave;
        std::vector<std::uint8_t> last_inputs;
        std::uint64_t changes = 0;
        bool seen = false;
    };
    std::vector<Terminal> slaves_;
};

}  // namespace vecat::cli
