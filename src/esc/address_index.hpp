// Which ESCs of a line a configured-address or logical datagram can concern, found without asking each ESC
// (ETG.1000.4 5.4: configured station address or alias for FPRD/FPWR/FPRW, the FMMUs' logical ranges for
// LRD/LWR/LRW). A frame of process data for a line of 1,000 slaves concerns the hundred or so whose FMMUs
// it covers; the segment hands it to those only (Segment::process_datagrams).
//
// The index gives candidates, a superset of the slaves concerned: the segment still asks each candidate's
// Esc::Addressing, so an index that is too wide costs time, never a wrong answer.
#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "esc/esc.hpp"

namespace vecat::esc {

class AddressIndex {
  public:
    // Made again from the addressing of every slave (by position). No allocation once it has held a line of
    // this many slaves.
    void rebuild(std::span<const Esc::Addressing> table);

    // Appends the slaves whose station address, or enabled alias, is adp (each once).
    void fixed(std::uint16_t adp, std::vector<std::uint32_t>& out) const;
    // Appends the slaves whose FMMUs' logical ranges (Esc::Addressing: those that read, those that write)
    // overlap [first_bit, last_bit], in the order of the ranges' first bits; a slave whose two ranges lie
    // apart and both overlap comes twice.
    void logical(std::uint64_t first_bit, std::uint64_t last_bit, std::vector<std::uint32_t>& out) const;

  private:
    std::vector<std::pair<std::uint16_t, std::uint32_t>> by_address_;  // (station or alias, slave), sorted
    struct Span {
        std::uint64_t first_bit, last_bit;
        std::uint64_t max_last_bit;  // the largest last_bit of this span and every span before it
        std::uint32_t slave;
    };
    std::vector<Span> by_first_bit_;  // the slaves' logical ranges, sorted by their first bits
};

}  // namespace vecat::esc
