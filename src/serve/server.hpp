// The serve loop, the slave side of the transport: receives frames on a raw socket (src/net), runs them
// through the segment (src/esc) and sends the replies back in place. Nothing on this path allocates or locks.
#pragma once

#include <atomic>
#include <cstdint>

#include "esc/firmware_threads.hpp"
#include "esc/segment.hpp"
#include "net/clock.hpp"
#include "net/frame_filter.hpp"
#include "net/frame_observer.hpp"
#include "net/pcapng_writer.hpp"
#include "net/raw_socket.hpp"
#include "net/side_channel.hpp"

namespace vecat::net {

// What the serve loop did so far, readable from another thread while it runs (relaxed counters: figures for
// a benchmark, not a synchronisation).
struct ServeCounters {
    // Loop passes that wait: blocking, one wake-up each (a frame, SYNC pulse, tick or empty wait); busy-
    // polling, one per poll of the socket. A frame that was already waiting when the last one was answered
    // takes a pass that does not wait, and does not count.
    std::atomic<std::uint64_t> wakeups{0};
    std::atomic<std::uint64_t> frames{0};  // frames from the master side processed
    std::atomic<std::uint64_t> ticks{0};   // firmware runs without a frame (deadlines, catch-up ticks)
    // Frames that arrived (kernel receive time) while a tick ran, and how long they waited for its end, ns:
    // the latency that ticks add to the reply path.
    std::atomic<std::uint64_t> frames_behind_tick{0};
    std::atomic<std::uint64_t> behind_tick_ns{0};
    // The time between firmware runs without a frame that the loop works with now (see
    // ServeOptions::catch_up_budget_us), ns.
    std::atomic<std::uint64_t> catch_up_ns{0};
};

struct ServeOptions {
    bool busy_poll = false;  // spin on the socket instead of sleeping in poll()
    // The slaves' local cycle (Segment::set_local_cycle_ns): the drives' servo period
    // (cia402::Drive::kServoPeriodNs). A slave whose firmware last ran this long ago or longer catches up
    // before a frame reaches it; it is also the shortest time between two runs of the firmware without a
    // frame.
    std::int64_t tick_us = 250;
    // Firmware when it is needed: the loop wakes up for frames, for the slaves' deadlines
    // (Segment::next_firmware_ns) and the faults' timeline, and otherwise only so often that the firmware
    // work a frame finds waiting (the slaves' cycles since their last run, done before the frame is
    // processed) stays near this budget, or near the frame's own time on a real 100 Mbit/s line if that
    // is longer (its reply is then no later than hardware's): between tick_us and kMaxCatchUpUs apart,
    // from what that work cost so far. A few drives at 1 kHz wake the loop once per frame; a large
    // network's catch-up goes into its frames of process data, as long as each fits the frame's time.
    std::int64_t catch_up_budget_us = 20;
    static constexpr std::int64_t kMaxCatchUpUs = 10'000;
    PcapngWriter* pcap = nullptr;   // capture of every frame in and out
    FrameFilter* filter = nullptr;  // fault injection (src/faults): frames go through it to the segment
    // Sees every frame from the master as it came, and every reply as it goes back (the report on the
    // master, src/report). Not given: nothing is copied or parsed for it.
    FrameObserver* observer = nullptr;
    // Called on the serving thread after each processed frame, once its reply is sent (telemetry); it must
    // neither block nor allocate. now_ns: the time the frame was processed at.
    void (*after_frame)(void* context, std::uint64_t now_ns) = nullptr;
    void* after_frame_context = nullptr;
    // While this flag is true a busy-polling loop sleeps in poll() like the blocking mode (the round-trip
    // benchmark parks one server while it measures another on the same two cores).
    const std::atomic<bool>* park = nullptr;
    // Chained segments: the interface port 1 of the last slave is cabled to (towards the next vecat
    // process). While it has a link, processed frames go out of it instead of back to the master, and the
    // frames coming back on it are forwarded to the master side; without a link the line closes here.
    RawSocket* downstream = nullptr;
    // Cable redundancy: the interface of the master's second port, cabled to the segment's redundancy
    // port (Segment::set_redundancy). Frames come in on either interface and their replies go out of the
    // one the segment says (Segment::reply_port); its carrier is the link of that port. Not together with
    // downstream.
    RawSocket* secondary = nullptr;
    ServeCounters* counters = nullptr;  // live counters, if given
    // Threads for the slaves' firmware (vecat run --threads N): the loop's thread and the workers run the
    // firmware batches of the segment (Segment::set_firmware_threads) while the loop runs. nullptr: this
    // thread alone.
    esc::FirmwareThreads* firmware_threads = nullptr;
    // Descriptors to wait on beside the socket (the EoE devices' TAP interfaces, src/eoe/eoe_bridge.hpp):
    // the loop wakes up when one is readable and calls its service() between frames. With busy polling,
    // downstream or secondary it is serviced on every pass instead (without waking the loop).
    SideChannel* side = nullptr;
};

struct ServeStats {
    std::uint64_t received = 0;
    std::uint64_t sent = 0;
    std::uint64_t send_errors = 0;
    std::uint64_t sent_downstream = 0;     // chained segments: frames passed on to the next segment
    std::uint64_t returned = 0;            // ... and frames back from it, forwarded to the master side
    std::uint64_t received_secondary = 0;  // cable redundancy: frames from the master's second port
    std::uint64_t sent_secondary = 0;      // ... and replies out of it
};

// Runs until stop becomes true.
ServeStats serve(esc::Segment& seg, RawSocket& sock, const ServeOptions& opt, const std::atomic<bool>& stop);

}  // namespace vecat::net
