// A link a master sends EtherCAT frames over: a raw socket, or a segment in the same process.
#pragma once

#include <cstddef>
#include <cstdint>

#include "common/bytes.hpp"

namespace vecat::net {

class Link {
  public:
    virtual ~Link() = default;
    virtual bool send(ConstBytes frame) = 0;
    // Receives one frame into buf; returns its length, 0 on timeout, -1 on error.
    virtual long receive(Bytes buf, std::int64_t timeout_us) = 0;
};

}  // namespace vecat::net
