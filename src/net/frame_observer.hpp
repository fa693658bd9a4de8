// Something that watches the frames between a master and the slaves without changing them: the report on
// the master (src/report) is one. The serve loop (src/serve) and the in-process link call it on their
// thread; an observer must not block.
#pragma once

#include <cstdint>

#include "common/bytes.hpp"

namespace vecat::net {

class FrameObserver {
  public:
    virtual ~FrameObserver() = default;
    // A frame from the master, before any slave has processed it. now_ns: the time the slaves see it at.
    virtual void on_request(ConstBytes frame, std::uint64_t now_ns) = 0;
    // The reply to it, as it goes back to the master (after the slaves' firmware has run, or not: the
    // firmware may run after the reply is sent, see esc::Segment::set_deferred_firmware).
    virtual void on_reply(ConstBytes frame, std::uint64_t now_ns) = 0;
};

}  // namespace vecat::net
