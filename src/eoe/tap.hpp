// A TAP interface (Linux /dev/net/tun, IFF_TAP | IFF_NO_PI): the Ethernet side of an EoE device in the
// network namespace vecat runs in. Frames written to it appear on the interface; frames the kernel sends
// out of the interface are read from it. Creating one needs CAP_NET_ADMIN (root, or a user namespace of
// one's own).
#pragma once

#include <string>

#include "common/bytes.hpp"

namespace vecat::eoe {

class Tap {
  public:
    // Creates (or attaches to) the interface `name` and brings it up; non-blocking. Throws
    // std::runtime_error with the reason when it cannot.
    explicit Tap(const std::string& name);
    ~Tap();
    Tap(const Tap&) = delete;
    Tap& operator=(const Tap&) = delete;

    int fd() const { return fd_; }
    const std::string& name() const { return name_; }
    // One frame out of the interface's queue: its length, 0 when none is waiting, -1 on error.
    long read(Bytes buf);
    // One frame into the interface; false when the kernel did not take it (queue full, interface down).
    bool write(ConstBytes frame);

  private:
    int fd_ = -1;
    std::string name_;
};

}  // namespace vecat::eoe
