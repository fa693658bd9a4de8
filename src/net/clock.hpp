// The host clocks the transport and the serve loop stamp frames with.
#pragma once

#include <cstdint>

namespace vecat::net {

std::uint64_t monotonic_ns();  // CLOCK_MONOTONIC: frame times given to the segment
std::uint64_t realtime_ns();   // CLOCK_REALTIME: capture time stamps (pcapng)

}  // namespace vecat::net
