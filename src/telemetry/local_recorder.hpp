// Records the sampler's queue in the same process, without DDS (the demo's scope picture, tests): a thread
// empties the queue into a Recording.
#pragma once

#include <atomic>
#include <thread>

#include "telemetry/recording.hpp"
#include "telemetry/sampler.hpp"

namespace vecat::telemetry {

class LocalRecorder {
  public:
    explicit LocalRecorder(TelemetryQueue& q) : q_(q) {
        thread_ = std::thread([this] {
            while (running_.load(std::memory_order_relaxed)) {
                drain();
                std::this_thread::sleep_for(std::chrono::milliseconds(1));
            }
            drain();
        });
    }
    ~LocalRecorder() { stop(); }
    // Stops the thread after the last record; the recording is complete then.
    Recording& stop() {
        running_ = false;
        if (thread_.joinable()) thread_.join();
        return rec_;
    }

  private:
    void drain() {
        Record r;
        while (q_.pop(r))
            rec_.add(r);
    }
    TelemetryQueue& q_;
    Recording rec_;
    std::atomic<bool> running_{true};
    std::thread thread_;
};

}  // namespace vecat::telemetry
