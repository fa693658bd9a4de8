// A link straight into a segment in the same process: the frame is processed when sent and the reply
// is returned by the next receive. For tests without a network.
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
        if (frame.size() > buf_.size()) return false;
        std::memcpy(buf_.data(), frame.data(), frame.size());
        len_ = frame.size();
        if (observer_) observer_->on_request(ConstBytes(buf_.data(), len_), now_ns());
        pending_ = filter_ ? filter_->process_frame(Bytes(buf_.data(), buf_.size()), len_, now_ns())
                           : seg_.process_frame(Bytes(buf_.data(), buf_.size()), len_, now_ns());
        return true;
    }
    long receive(Bytes out, std::int64_t) override {
        // A held-back reply that is due left earlier than the frame just sent: it arrives first.
        if (filter_)
            if (const std::size_t late = filter_->take_due(now_ns(), out)) return static_cast<long>(late);
        if (!pending_) return 0;
        pending_ = false;
        const std::size_t n = std::min(len_, out.size());
        std::memcpy(out.data(), buf_.data(), n);
        if (observer_) observer_->on_reply(ConstBytes(buf_.data(), len_), now_ns());
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
    void set_time(std::uint64_t ns) {
        manual_time_ = true;
        manual_now_ = ns;
    }

  private:
    esc::Segment& seg_;
    FrameFilter* filter_ = nullptr;
    FrameObserver* observer_ = nullptr;
    std::array<std::uint8_t, 1600> buf_{};
    std::size_t len_ = 0;
    bool pending_ = false;
    bool manual_time_ = false;
    std::uint64_t manual_now_ = 0;
};

}  // namespace vecat::net
