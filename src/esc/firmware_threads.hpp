// Threads for the slaves' firmware (vecat run --threads N). The segment hands a batch of independent work
// items (groups of slaves whose firmware shares no state, Segment::set_firmware_threads) to the thread that
// calls run() and to N - 1 workers, and run() returns when all are done: a fork and a join around each batch.
// A caller that has other work that touches none of the batch's state (the serve loop answering a frame for
// other slaves, Segment::start_deferred_firmware) splits run() into start() and join() around it.
//
// The hand-off is wait-free for the caller and takes no lock: a batch is published with one atomic store;
// the caller and the workers claim items, a chunk at a time, with compare-and-swap on one word holding the
// batch number and the next item (so a worker that looks late can never claim an item of a newer batch); the
// caller then works through items itself and waits only for items a worker has claimed and not finished. A
// worker that is slow to wake up costs the caller nothing: the caller takes the items it left. Results do not
// depend on which thread runs an item (the items share no state), only the time does.
//
// A worker spins (with a pause instruction) while batches keep coming, and sleeps in the kernel (std::atomic
// wait, a futex) after kSpinNs without one; the caller then wakes it with the next batch (a futex wake: a
// system call that never waits), and meanwhile works through the items itself. The frames of one cycle
// come close together and keep the worker awake; between cycles it sleeps, so that it does not take a core
// from the master under test (on a machine with few cores a spinning worker starves the other threads).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

namespace vecat::esc {

class FirmwareThreads {
  public:
    // threads: all threads that run firmware, the caller of run() included (1: no worker, run() works
    // alone). spin_ns: how long a worker spins without a batch before it sleeps.
    explicit FirmwareThreads(unsigned threads, std::uint64_t spin_ns = kSpinNs);
    ~FirmwareThreads();
    FirmwareThreads(const FirmwareThreads&) = delete;
    FirmwareThreads& operator=(const FirmwareThreads&) = delete;

    unsigned threads() const { return static_cast<unsigned>(workers_.size()) + 1; }
    // The workers under SCHED_FIFO with this priority, as the serve loop's thread (vecat run --fifo): a
    // worker that the scheduler preempts holds up the batch it claimed from. False (why) if refused.
    bool set_fifo_priority(int priority, std::string* why = nullptr);

    // Calls work(context, i) for every i in [0, count), each once, on this thread and the workers; returns
    // when all calls have returned. Only one thread may call it (the serve loop's).
    using Work = void (*)(void* context, std::size_t item);
    void run(std::size_t count, Work work, void* context);
    // The same in two steps, so that the caller can do other work while the workers run the batch: start()
    // hands the batch to the workers and returns at once; join() works through the items no worker has
    // claimed yet and returns when all are done. The caller must touch nothing the items touch in between,
    // and join() each batch before it starts or runs another. With one thread (or one item), start() runs
    // the batch itself.
    void start(std::size_t count, Work work, void* context);
    void join();
    // A batch is started and not joined yet.
    bool started() const { return started_; }
    // No batch is started, or the workers have run all of its items (join() then only takes note). (A batch
    // that start() ran itself is never started.)
    bool finished() const { return !started_ || done_.load(std::memory_order_acquire) >= batch_count_; }

    // A worker that has had no batch for this long sleeps until the next one (by default).
    static constexpr std::uint64_t kSpinNs = 100'000;
    // A batch is claimed in about this many chunks per thread (see run()).
    static constexpr std::size_t kChunksPerThread = 8;

    // Items run by the workers so far (the rest ran on the caller's thread): a figure for tests and the
    // benchmark.
    std::uint64_t items_on_workers() const { return on_workers_.load(std::memory_order_relaxed); }
    // Batches whose caller, its own share done, waited kLongWaitNs or more for items a worker had claimed
    // (a worker preempted in the middle of its chunk, or the machine stalled), and the caller's longest such
    // wait: figures for the soak and the tests.
    static constexpr std::uint64_t kLongWaitNs = 50'000;
    std::uint64_t long_waits() const { return long_waits_.load(std::memory_order_relaxed); }
    std::uint64_t longest_wait_ns() const { return longest_wait_ns_.load(std::memory_order_relaxed); }

  private:
    void worker();
    // Claims and runs items of batch `batch` until none is left; returns how many it ran.
    std::size_t work_through(std::uint32_t batch);
    static std::uint64_t pack(std::uint32_t batch, std::uint32_t next) {
        return (static_cast<std::uint64_t>(batch) << 32) | next;
    }

    // The batch being run: its number (upper half) and the next item to claim (lower half).
    alignas(64) std::atomic<std::uint64_t> claim_{0};
    // Items of the current batch finished so far.
    alignas(64) std::atomic<std::size_t> done_{0};
    // The current batch's work (written before claim_ publishes it; read by a claimer before it claims: a
    // successful claim proves the batch it read is still the current one).
    alignas(64) std::atomic<std::size_t> count_{0};
    std::atomic<std::size_t> chunk_{1};  // items per claim (see run())
    std::atomic<Work> work_{nullptr};
    std::atomic<void*> context_{nullptr};
    // Sleeping workers, and the word they sleep on (counted up to wake them).
    alignas(64) std::atomic<unsigned> sleepers_{0};
    std::atomic<std::uint32_t> wake_{0};
    std::atomic<bool> stop_{false};
    std::atomic<std::uint64_t> on_workers_{0};
    std::atomic<std::uint64_t> long_waits_{0}, longest_wait_ns_{0};  // the caller's (join())
    const std::uint64_t spin_ns_;
    std::uint32_t batch_ = 0;      // the caller's last batch number
    std::size_t batch_count_ = 0;  // its items
    bool started_ = false;         // it is not joined yet
    std::vector<std::thread> workers_;
};

}  // namespace vecat::esc
