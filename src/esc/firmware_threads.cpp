#include "esc/firmware_threads.hpp"

#include <pthread.h>
#include <sched.h>

#include <cstring>

#include <algorithm>
#include <chrono>
#include <string>

namespace vecat::esc {

namespace {

// The lower half of a lane's claim while a batch is being published: no item can be claimed.
constexpr std::uint32_t kNotReady = ~std::uint32_t{0};

void pause() noexcept {
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#elif defined(__aarch64__)
    asm volatile("yield");
#endif
}

std::uint64_t steady_ns() noexcept {
    return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                          std::chrono::steady_clock::now().time_since_epoch())
                                          .count());
}

}  // namespace

FirmwareThreads::FirmwareThreads(unsigned threads, std::uint64_t spin_ns)
    : lanes_(std::max(threads, 1u)), spin_ns_(spin_ns) {
    const unsigned n = threads > 1 ? threads - 1 : 0;
    workers_.reserve(n);
    for (unsigned i = 0; i < n; ++i) {
        workers_.emplace_back([this, i] { worker(i + 1); });
        // Named for perf and top: vecat-fw-1, vecat-fw-2...
        const std::string name = "vecat-fw-" + std::to_string(i + 1);
        pthread_setname_np(workers_.back().native_handle(), name.c_str());
    }
}

bool FirmwareThreads::set_fifo_priority(int priority, std::string* why) {
    for (auto& t : workers_) {
        sched_param p{};
        p.sched_priority = priority;
        if (const int e = pthread_setschedparam(t.native_handle(), SCHED_FIFO, &p); e != 0) {
            if (why) *why = std::string("firmware threads under SCHED_FIFO: ") + std::strerror(e);
            return false;
        }
    }
    return true;
}

FirmwareThreads::~FirmwareThreads() {
    stop_.store(true);
    wake_.fetch_add(1);
    wake_.notify_all();
    for (auto& t : workers_)
        t.join();
}

std::size_t FirmwareThreads::drain(std::uint32_t batch, unsigned lane) {
    Lane& l = lanes_[lane];
    std::size_t ran = 0;
    for (;;) {
        std::uint64_t c = l.claim.load();
        if (static_cast<std::uint32_t>(c >> 32) != batch) break;
        const auto next = static_cast<std::uint32_t>(c);
        // Read before the claim: a claim that succeeds proves that this batch was still the current one,
        // and the caller writes a new batch's work only after invalidating every lane (see run()).
        const std::size_t end = l.end.load();
        const std::size_t chunk = l.chunk.load();
        const Work work = work_.load();
        void* const context = context_.load();
        if (next >= end) break;
        const auto stop = static_cast<std::uint32_t>(std::min<std::size_t>(end, next + chunk));
        if (!l.claim.compare_exchange_weak(c, pack(batch, stop))) continue;
        for (std::uint32_t i = next; i < stop; ++i)
            work(context, i);
        ran += stop - next;
        done_.fetch_add(stop - next, std::memory_order_release);
    }
    return ran;
}

std::size_t FirmwareThreads::work_through(std::uint32_t batch, unsigned self) {
    std::size_t ran = 0;
    const auto n = static_cast<unsigned>(lanes_.size());
    for (unsigned k = 0; k < n; ++k)
        ran += drain(batch, (self + k) % n);
    return ran;
}

void FirmwareThreads::run(std::size_t count, Work work, void* context, std::span<const std::size_t> lanes) {
    if (count == 0) return;
    if (workers_.empty() || count == 1) {
        for (std::size_t i = 0; i < count; ++i)
            work(context, i);
        return;
    }
    const auto n = static_cast<unsigned>(lanes_.size());
    const bool named = lanes.size() == n + 1 && lanes.front() == 0 && lanes.back() == count &&
                       std::is_sorted(lanes.begin(), lanes.end());
    ++batch_;
    for (Lane& l : lanes_)
        l.claim.store(pack(batch_, kNotReady));  // late claimers of the last batch fail from here on
    done_.store(0, std::memory_order_relaxed);
    work_.store(work);
    context_.store(context);
    for (unsigned t = 0; t < n; ++t) {
        const std::size_t begin = named ? lanes[t] : count * t / n;
        const std::size_t end = named ? lanes[t + 1] : count * (t + 1) / n;
        lanes_[t].end.store(end);
        // Items are claimed a chunk at a time: each claim and each count of finished items moves a cache
        // line between the cores, which costs more than a small item (one slave's run). Eight chunks per
        // thread still share out items of unequal cost.
        lanes_[t].chunk.store(std::max<std::size_t>(1, (end - begin) / kChunksPerThread));
        lanes_[t].claim.store(pack(batch_, static_cast<std::uint32_t>(begin)));
    }
    if (sleepers_.load() > 0) {
        wake_.fetch_add(1);
        wake_.notify_all();
    }
    work_through(batch_, 0);
    while (done_.load(std::memory_order_acquire) < count)
        pause();
}

void FirmwareThreads::worker(unsigned self) {
    std::uint32_t last = 0;
    std::uint64_t idle_since = steady_ns();
    unsigned spins = 0;
    // (The last lane is published last: once it shows a new batch, every lane does.)
    const std::atomic<std::uint64_t>& published = lanes_.back().claim;
    while (!stop_.load(std::memory_order_relaxed)) {
        const std::uint64_t c = published.load();
        const auto batch = static_cast<std::uint32_t>(c >> 32);
        if (batch != last && static_cast<std::uint32_t>(c) != kNotReady) {
            last = batch;
            if (const std::size_t ran = work_through(batch, self))
                on_workers_.fetch_add(ran, std::memory_order_relaxed);
            idle_since = steady_ns();
            continue;
        }
        pause();
        if (++spins % 64 != 0 || steady_ns() - idle_since < spin_ns_) continue;
        // Idle for a while: sleep until the caller publishes a batch (it wakes sleepers only).
        const std::uint32_t w = wake_.load();
        sleepers_.fetch_add(1);
        if (published.load() == c && !stop_.load()) wake_.wait(w);
        sleepers_.fetch_sub(1);
        idle_since = steady_ns();
    }
}

}  // namespace vecat::esc
