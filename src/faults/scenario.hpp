// A fault scenario: a timeline of faults started and stopped at given times or cycles, read from a YAML
// file (format and example: src/faults/README.md, examples/faults/).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "faults/fault.hpp"

namespace vecat::faults {

struct TimelineEvent {
    bool by_cycle = false;  // at_cycle: N (frames received before it), else at: time since the first frame
    std::uint64_t at = 0;   // ns or frames
    bool start = true;      // start the fault, or stop the faults named by target
    FaultSpec fault;        // start
    std::string target;     // stop: an id, a kind name or "all"
    int line = 0;           // in the file, for messages
};

struct Scenario {
    std::uint64_t seed = 0;  // of the random draws (probability); 0: keep the injector's
    std::vector<TimelineEvent> events;
};

// Throw std::invalid_argument with the line of the offending event.
Scenario parse_scenario(const std::string& yaml_text);
Scenario load_scenario(const std::string& path);

}  // namespace vecat::faults
