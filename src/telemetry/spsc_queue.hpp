// A bounded single-producer single-consumer queue without locks or allocation after construction: the
// cyclic thread pushes, the publisher thread pops. A full queue refuses the record and counts it; the
// producer never waits.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <type_traits>

namespace vecat::telemetry {

template <class T, std::size_t Capacity>
class SpscQueue {
    static_assert(Capacity >= 2 && (Capacity & (Capacity - 1)) == 0, "capacity: a power of two");
    static_assert(std::is_trivially_copyable_v<T>);

  public:
    // Producer side. False (and counted) when full.
    bool push(const T& v) noexcept {
        const std::size_t head = head_.load(std::memory_order_relaxed);
        if (head - tail_cache_ >= Capacity) {
            tail_cache_ = tail_.load(std::memory_order_acquire);
            if (head - tail_cache_ >= Capacity) {
                overflows_.store(overflows_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
                return false;
            }
        }
        slots_[head & (Capacity - 1)] = v;
        head_.store(head + 1, std::memory_order_release);
        return true;
    }

    // Consumer side.
    bool pop(T& out) noexcept {
        const std::size_t tail = tail_.load(std::memory_order_relaxed);
        if (tail == head_cache_) {
            head_cache_ = head_.load(std::memory_order_acquire);
            if (tail == head_cache_) return false;
        }
        out = slots_[tail & (Capacity - 1)];
        tail_.store(tail + 1, std::memory_order_release);
        return true;
    }

    // Records refused because the queue was full (either side may read it).
    std::uint64_t overflows() const noexcept { return overflows_.load(std::memory_order_relaxed); }
    static constexpr std::size_t capacity() { return Capacity; }
    std::size_t size_approx() const noexcept {
        return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire);
    }

  private:
    // Producer and consumer indices on their own cache lines, each with a cached copy of the other's.
    alignas(64) std::atomic<std::size_t> head_{0};
    std::size_t tail_cache_ = 0;
    std::atomic<std::uint64_t> overflows_{0};
    alignas(64) std::atomic<std::size_t> tail_{0};
    std::size_t head_cache_ = 0;
    alignas(64) std::array<T, Capacity> slots_{};
};

}  // namespace vecat::telemetry
