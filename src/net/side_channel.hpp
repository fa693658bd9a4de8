// Descriptors besides the EtherCAT socket that the serve loop waits on (the TAP interfaces of the EoE
// devices, src/eoe/eoe_bridge.hpp): when one of them is readable, the serve loop calls service() on its
// own thread, between frames, so that what it delivers into the slaves needs no lock.
#pragma once

#include <cstdint>
#include <span>

namespace vecat::net {

class SideChannel {
  public:
    virtual ~SideChannel() = default;
    // The descriptors to wait on for reading (stable while the serve loop runs).
    virtual std::span<const int> fds() const = 0;
    // Reads what is ready without blocking and hands it on; called when a descriptor is readable (and on
    // each pass of a busy-polling loop). now_ns: the monotonic time.
    virtual void service(std::uint64_t now_ns) = 0;
};

}  // namespace vecat::net
