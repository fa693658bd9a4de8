// A link straight into a segment in the same process: the frame is processed when sent and its reply is
// queued for receive, as a wire with a receive ring holds the replies of frames sent back to back (a master
// may send a cycle's frames before it receives any). For tests without a network.
#pragma once

#include <array>
#include <chrono>
#include <cstring>

#include "esc/segment.hpp"
#include "net/frame_filter.hpp"
#include "net/frame_observer.hpp"
#include "net/link.hpp"

namespace vecat::net {

class InProcessLink final : public Link {
  public:
    explicit InProcessLink(esc::Segment& seg) : seg_(seg) {}
    bool send(ConstBytes frame) override {
        if (frame.size() > kFrameBytes) return false;
        if (manual_time_) manual_now_ += step_ns_;
        if (count_ == kQueued) return true;  // the receive ring is full: the reply is lost on the way back
        Slot& slot = queue_[(head_ + count_) % kQueued];
        std::memcpy(slot.bytes.data(), frame.data(), frame.size());
        slot.len = frame.size();
        const Bytes buf(slot.bytes.data(), slot.bytes.size());
        if (observer_) observer_->on_request(ConstBytes(buf.data(), slot.len), now_ns());
        const bool reply = filter_ ? filter_->process_frame(buf, slot.len, now_ns())
                                   : seg_.process_frame(buf, slot.len, now_ns());
        if (reply) ++count_;
        if (beside_ && !filter_ && !observer_ && ++frames_ % beside_ == 0) seg_.start_deferred_firmware();
        return true;
    }
    long receive(Bytes out, std::int64_t) override {
        // A held-back reply that is due left earlier than the frames just sent: it arrives first.
        if (filter_)
            if (const std::size_t late = filter_->take_due(now_ns(), out)) return static_cast<long>(late);
        if (count_ == 0) return 0;
        const Slot& slot = queue_[head_];
        head_ = (head_ + 1) % kQueued;
        --count_;
        const std::size_t n = std::min(slot.len, out.size());
        std::memcpy(out.data(), slot.bytes.data(), n);
        if (observer_) observer_->on_reply(ConstBytes(slot.bytes.data(), slot.len), now_ns());
        return static_cast<long>(n);
    }
    // Time seen by the segment; tests may drive it by hand.
    std::uint64_t now_ns() const {
        if (manual_time_) return manual_now_;
        return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                              std::chrono::steady_clock::now().time_since_epoch())
                                              .count());
    }
    // Fault injection between the link and the segment (nullptr: none).
    void set_filter(FrameFilter* f) { filter_ = f; }
    // Sees each frame before the segment and each reply as the master receives it (nullptr: none).
    void set_observer(FrameObserver* o) { observer_ = o; }
    // After every n-th frame (1: each, as the serve loop does; 0: never), the segment's deferred firmware
    // goes to its firmware threads (Segment::start_deferred_firmware, with set_deferred_firmware and
    // set_firmware_threads): the next frames sent are processed beside it. The caller runs the segment's
    // run_deferred_firmware() before it looks at the slaves.
    void set_firmware_beside(unsigned every_nth_frame) { beside_ = every_nth_frame; }
    void set_time(std::uint64_t ns) {
        manual_time_ = true;
        manual_now_ = ns;
    }
    // With the time set by hand: each frame sent first moves it on by this much, as frames sent back to back
    // reach a line one after the other (0, the default: every frame at the time set).
    void set_time_step(std::uint64_t ns) { step_ns_ = ns; }

  private:
    esc::Segment& seg_;
    FrameFilter* filter_ = nullptr;
    FrameObserver* observer_ = nullptr;
    static constexpr std::size_t kFrameBytes = 1600;
    static constexpr std::size_t kQueued = 32;  // replies not yet received (Master::kMaxFramesInFlight)
    struct Slot {
        std::array<std::uint8_t, kFrameBytes> bytes{};
        std::size_t len = 0;
    };
    std::array<Slot, kQueued> queue_{};
    std::size_t head_ = 0, count_ = 0;
    bool manual_time_ = false;
    unsigned beside_ = 0;
    unsigned frames_ = 0;
    std::uint64_t manual_now_ = 0;
    std::uint64_t step_ns_ = 0;
};

}  // namespace vecat::net
