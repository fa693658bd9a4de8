// A segment: N slaves on one line in one process. A frame passes through them in order, each slave
// seeing it as its predecessor left it, then returns to the master (open line: the last slave closes
// the loop on its port 1).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "common/bytes.hpp"
#include "esc/slave.hpp"

namespace vecat::esc {

struct SegmentCounters {
    std::uint64_t frames = 0;
    std::uint64_t replies = 0;
    std::uint64_t dropped = 0;  // malformed EtherCAT frames
    std::uint64_t ignored = 0;  // not EtherCAT
};

class Segment {
  public:
    Segment() = default;
    void add(std::unique_ptr<Slave> s);
    std::size_t size() const { return slaves_.size(); }
    Slave& slave(std::size_t i) { return *slaves_[i]; }
    const Slave& slave(std::size_t i) const { return *slaves_[i]; }

    // Processes a received frame in place. frame must have room for at least kMinEthFrame bytes; len is
    // updated (padding to 60 bytes). Returns true when a reply must be sent.
    bool process_frame(Bytes frame, std::size_t& len, std::uint64_t now_ns);
    // Runs the slaves' firmware and watchdogs without a frame.
    void tick(std::uint64_t now_ns);
    // Host time of the next SYNC pulse of any slave (DistributedClock::kNever if none): the serve loop runs
    // tick() then, so SYNC events happen on time without frames.
    std::uint64_t next_event_ns() const;

    const SegmentCounters& counters() const { return counters_; }

    // Line model: delay of a frame per hop (cable + PHY + forwarding) in ns.
    std::uint64_t hop_delay_ns = 500;

  private:
    void run(std::size_t k, std::uint64_t now_ns);
    std::vector<std::unique_ptr<Slave>> slaves_;
    // Per slave: host time of its last firmware run. A frame runs the firmware of the slaves it addressed,
    // and of the others only when kMaxRunGapNs has passed (a cycle of several frames does not run every
    // slave once per frame).
    std::vector<std::uint64_t> last_run_ns_;
    static constexpr std::uint64_t kMaxRunGapNs = 100'000;
    SegmentCounters counters_;
};

// Makes the application of one slave (the CoE stack and drive, or a bare process image).
using ApplicationFactory = std::function<std::unique_ptr<Application>(const device::DeviceDescription&)>;

// Builds a segment of n slaves of the given device, each with an application from the factory (by
// default a ProcessImageApplication without mailbox protocols).
std::unique_ptr<Segment> make_segment(const device::DeviceDescription& d, std::size_t n,
                                      const EscConfig& cfg = {}, const ApplicationFactory& factory = {});

}  // namespace vecat::esc
