// The cyclic-thread side of the telemetry: after each frame the serve loop processed, the sampler reads
// the segment's slaves (the dictionary objects of each CiA 402 device, the ESC registers, the TWINsync link
// status) and pushes records into the bounded queue. It samples an axis when its slave exchanged process
// data, every `decimation`-th exchange; it detects events (AL state, CiA 402 state, mode, 0x603F faults,
// emergencies) on every frame. A CiA 402 device is one whose dictionary has the statusword 0x6041; its state
// is the statusword decoded (protocol::cia402::decode_state), as a master sees it. The TWINsync status comes
// from an application that is a twinsync::StatusSource (the drive). I/O terminals (io::InputTerminal,
// io::OutputTerminal) give an IoSample every `decimation`-th exchange of theirs. It neither allocates nor
// blocks: a full queue drops the record and counts it.
#pragma once

#include <cstdint>
#include <vector>

#include "esc/segment.hpp"
#include "telemetry/samples.hpp"
#include "telemetry/spsc_queue.hpp"

namespace vecat::coe {
class CoeApplication;
class Entry;
}  // namespace vecat::coe

namespace vecat::telemetry {

// 8192 records: about two seconds of two axes at 1 kHz if the publisher stalls.
using TelemetryQueue = SpscQueue<Record, 8192>;

struct SamplerOptions {
    unsigned decimation = 1;      // one axis sample every n process data exchanges (1: every one)
    unsigned status_every = 100;  // slave status every n axis samples (and at each AL state change)
};

struct SamplerStats {
    std::uint64_t frames = 0;      // on_frame calls
    std::uint64_t samples = 0;     // axis samples pushed
    std::uint64_t io_samples = 0;  // I/O samples pushed
    std::uint64_t events = 0;      // events pushed
};

class Sampler {
  public:
    // The segment's slaves are looked up here (call before the serve loop starts), and again only when the
    // segment says they changed (esc::Segment::slaves_epoch: a restart, a hot connect move).
    Sampler(esc::Segment& seg, TelemetryQueue& q, SamplerOptions opt = {});
    ~Sampler();
    Sampler(const Sampler&) = delete;
    Sampler& operator=(const Sampler&) = delete;

    // After each processed frame, on the cyclic thread (now_ns: the time the frame was processed at).
    void on_frame(std::uint64_t now_ns);
    // Samples every slave now, whether it exchanged process data or not (what on_frame does for a slave
    // whose sample is due). Used by the benchmark.
    void sample_all(std::uint64_t now_ns);

    // For net::ServeOptions::after_frame (context: the sampler).
    static void after_frame(void* sampler, std::uint64_t now_ns) {
        static_cast<Sampler*>(sampler)->on_frame(now_ns);
    }

    const SamplerStats& stats() const { return stats_; }
    TelemetryQueue& queue() { return q_; }

  private:
    struct Slot;
    void bind(Slot& s, std::size_t position);  // the slave at position and its objects
    void follow_slaves();
    void sample(Slot& s, std::uint64_t now_ns);  // after detect_events(s) of the same frame
    void sample_io(Slot& s, std::uint64_t now_ns);
    void status(Slot& s, std::uint64_t now_ns);
    void detect_events(Slot& s, std::uint64_t now_ns);
    void event(const Slot& s, std::uint64_t now_ns, EventKind k, std::uint32_t code, std::int64_t old_value,
               std::int64_t new_value);

    esc::Segment& seg_;
    TelemetryQueue& q_;
    SamplerOptions opt_;
    std::vector<Slot> slots_;
    SamplerStats stats_;
    std::uint64_t overflows_reported_ = 0;
    std::uint64_t slaves_epoch_ = 0;
};

}  // namespace vecat::telemetry
