// Cost of the telemetry on the cyclic thread per cycle: the sampler reads every drive of the line
// (dictionary objects, ESC registers, events) and pushes the records into the lock-free queue, which a
// consumer thread empties as the publisher does. The DDS write happens on the publisher thread and is not
// part of this cost.
#include <benchmark/benchmark.h>

#include <chrono>

#include "cia402/drive.hpp"
#include "telemetry/sampler.hpp"

namespace {

using namespace vecat;

// One cycle's sample of n drives (the work on_frame does when every slave exchanged process data). Timed
// in batches of 256 cycles (per_cycle: the time of one); the queue is emptied between batches, untimed, so
// that every push succeeds as with a publisher that keeps up (a consumer thread cannot keep up with millions
// of cycles per second, and a full queue would make pushes look cheaper than they are).
void BM_TelemetrySamplePerCycle(benchmark::State& state) {
    constexpr int kBatch = 256;
    const auto n = static_cast<std::size_t>(state.range(0));
    auto seg = cia402::make_drive_segment(device::default_drive(), n);
    auto q = std::make_unique<telemetry::TelemetryQueue>();
    telemetry::Sampler s(*seg, *q);
    std::uint64_t now = 1'000'000'000;
    telemetry::Record r;
    for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        for (int i = 0; i < kBatch; ++i) {
            now += 1'000'000;
            s.sample_all(now);
        }
        const auto t1 = std::chrono::steady_clock::now();
        state.SetIterationTime(std::chrono::duration<double>(t1 - t0).count());
        while (q->pop(r))
            benchmark::DoNotOptimize(r);
    }
    // The figure: time per cycle (the benchmark's own time is per batch).
    state.counters["per_cycle"] =
        benchmark::Counter(static_cast<double>(state.iterations()) * kBatch,
                           benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
    state.counters["axes"] = static_cast<double>(n);
    state.counters["lost"] = static_cast<double>(q->overflows());
}
BENCHMARK(BM_TelemetrySamplePerCycle)->Arg(1)->Arg(2)->Arg(8)->UseManualTime();

// A frame without process data (mailbox, register access): only the event detection runs.
void BM_TelemetryFrameWithoutExchange(benchmark::State& state) {
    auto seg = cia402::make_drive_segment(device::default_drive(), 2);
    auto q = std::make_unique<telemetry::TelemetryQueue>();
    telemetry::Sampler s(*seg, *q);
    std::uint64_t now = 1'000'000'000;
    for (auto _ : state) {
        now += 1'000'000;
        s.on_frame(now);
    }
}
BENCHMARK(BM_TelemetryFrameWithoutExchange);

// The queue alone: one push and one pop of a record on the same thread.
void BM_TelemetryQueuePushPop(benchmark::State& state) {
    auto q = std::make_unique<telemetry::TelemetryQueue>();
    telemetry::Record r = telemetry::AxisSample{};
    for (auto _ : state) {
        q->push(r);
        q->pop(r);
        benchmark::DoNotOptimize(r);
    }
}
BENCHMARK(BM_TelemetryQueuePushPop);

}  // namespace
