// The control socket's `status` command (vecat fault status, the Python kit's Network.status()): what each
// slave shows now, one line per slave of key=value pairs, for a test to read while the line runs.
#pragma once

#include <string>

#include "esc/segment.hpp"

namespace vecat::faults {

// "ok N slaves", then per slave: slave= al= al_code= lost_links= rx_errors= watchdog_pd=, and for a device
// with the CiA 402 statusword also statusword= state= mode= position= velocity= error_code=.
std::string line_status(const esc::Segment& seg);

}  // namespace vecat::faults
