// What stands between a transport and the segment when faults are injected (src/faults): it runs each
// frame through the segment with the faults of the line, and may hold replies back to send them later.
#pragma once

#include <cstddef>
#include <cstdint>

#include "common/bytes.hpp"

namespace vecat::net {

class FrameFilter {
  public:
    virtual ~FrameFilter() = default;
    // Replaces Segment::process_frame: true when the (processed) frame goes back now.
    virtual bool process_frame(Bytes frame, std::size_t& len, std::uint64_t now_ns) = 0;
    // The same for a frame that came in at one of the master's two ports (cable redundancy; 0: primary,
    // 1: secondary); to_port: the port its reply goes out of. By default only the primary port has slaves.
    virtual bool process_frame_at(Bytes frame, std::size_t& len, std::uint64_t now_ns, unsigned from_port,
                                  unsigned& to_port) {
        to_port = 0;
        return from_port == 0 && process_frame(frame, len, now_ns);
    }
    // Called when the transport is idle (timelines advance without frames).
    virtual void tick(std::uint64_t now_ns) = 0;
    // A held-back reply due at now_ns, copied into out; its length, 0 when none is due.
    virtual std::size_t take_due(std::uint64_t now_ns, Bytes out) = 0;
    // Host time of the next held-back reply (max when none).
    virtual std::uint64_t next_due_ns() const = 0;
    // Host time by which tick() has something to do (a timeline event, the end of a fault, a request
    // from another thread), max when nothing: an idle transport need not wake up for it before then.
    virtual std::uint64_t next_event_ns() const { return ~std::uint64_t{0}; }
};

}  // namespace vecat::net
