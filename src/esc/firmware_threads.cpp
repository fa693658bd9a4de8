#include "esc/firmware_threads.hpp"

#include <pthread.h>
#include <sched.h>

#include <cstring>

#include <algorithm>
#include <chrono>
#include <string>

namespace vecat::esc {

namespace {

// The lower half of claim_ while a batch is being published: no item can be claimed.
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

FirmwareThreads::FirmwareThreads(unsigned threads, std::uint64_t spin_ns) : spin_ns_(spin_ns) {
    const unsigned n = threads > 1 ? threads - 1 : 0;
    workers_.reserve(n);
    for (unsigned i = 0; i < n; ++i) {
        workers_.emplace_back([this] { worker(); });
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
    join();
    stop_.store(true);
    wake_.fetch_add(1);
    wake_.notify_all();
    for (auto& t : workers_)
        t.join();
}

std::size_t FirmwareThreads::work_through(std::uint32_t batch) {
    std::size_t ran = 0;
    for (;;) {
        std::uint64_t c = claim_.load();
        if (static_cast<std::uint32_t>(c >> 32) != batch) break;
        const auto next = static_cast<std::uint32_t>(c);
        // Read before the claim: a claim that succeeds proves that this batch was still the current one,
        // and the caller writes a new batch's work only after invalidating claim_ (see run()).
        const std::size_t count = count_.load();
        const std::size_t chunk = chunk_.load();
        const Work work = work_.load();
        void* const context = context_.load();
        if (next >= count) break;
        const auto end = static_cast<std::uint32_t>(std::min<std::size_t>(count, next + chunk));
        if (!claim_.compare_exchange_weak(c, pack(batch, end))) continue;
        for (std::uint32_t i = next; i < end; ++i)
            work(context, i);
        ran += end - next;
        done_.fetch_add(end - next, std::memory_order_release);
    }
    return ran;
}

void FirmwareThreads::run(std::size_t count, Work work, void* context) {
    start(count, work, context);
    join();
}

void FirmwareThreads::start(std::size_t count, Work work, void* context) {
    if (started_) join();
    if (count == 0) return;
    if (workers_.empty() || count == 1) {
        for (std::size_t i = 0; i < count; ++i)
            work(context, i);
        return;
    }
    ++batch_;
    batch_count_ = count;
    started_ = true;
    claim_.store(pack(batch_, kNotReady));  // late claimers of the last batch fail from here on
    done_.store(0, std::memory_order_relaxed);
    count_.store(count);
    // Items are claimed a chunk at a time: each claim and each count of finished items moves a cache line
    // between the cores, which costs more than a small item (one slave's run). Eight chunks per thread
    // still share out items of unequal cost.
    chunk_.store(std::max<std::size_t>(1, count / (threads() * kChunksPerThread)));
    work_.store(work);
    context_.store(context);
    claim_.store(pack(batch_, 0));
    if (sleepers_.load() > 0) {
        wake_.fetch_add(1);
        wake_.notify_all();
    }
}

void FirmwareThreads::join() {
    if (!started_) return;
    started_ = false;
    const std::size_t count = batch_count_;
    work_through(batch_);
    if (done_.load(std::memory_order_acquire) >= count) return;
    // Items a worker claimed and still runs. (Sleeping here instead, after a while, was tried: the soaks
    // missed no fewer cycles and answered later; bench/README.md.)
    const std::uint64_t since = steady_ns();
    while (done_.load(std::memory_order_acquire) < count)
        pause();
    const std::uint64_t waited = steady_ns() - since;
    // (Only this thread writes them; others may read them while it runs: relaxed, no locked instruction.)
    if (waited >= kLongWaitNs)
        long_waits_.store(long_waits_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    if (waited > longest_wait_ns_.load(std::memory_order_relaxed))
        longest_wait_ns_.store(waited, std::memory_order_relaxed);
}

void FirmwareThreads::worker() {
    std::uint32_t last = 0;
    std::uint64_t idle_since = steady_ns();
    unsigned spins = 0;
    while (!stop_.load(std::memory_order_relaxed)) {
        const std::uint64_t c = claim_.load();
        const auto batch = static_cast<std::uint32_t>(c >> 32);
        if (batch != last && static_cast<std::uint32_t>(c) != kNotReady) {
            last = batch;
            if (const std::size_t ran = work_through(batch))
                on_workers_.fetch_add(ran, std::memory_order_relaxed);
            idle_since = steady_ns();
            continue;
        }
        pause();
        if (++spins % 64 != 0 || steady_ns() - idle_since < spin_ns_) continue;
        // Idle for a while: sleep until the caller publishes a batch (it wakes sleepers only).
        const std::uint32_t w = wake_.load();
        sleepers_.fetch_add(1);
        if (claim_.load() == c && !stop_.load()) wake_.wait(w);
        sleepers_.fetch_sub(1);
        idle_since = steady_ns();
    }
}

}  // namespace vecat::esc
