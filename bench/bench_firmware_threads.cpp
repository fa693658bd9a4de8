// The firmware threads' fork and join (esc::FirmwareThreads::run): one batch of N small items, each as much
// work as a few cache lines of one slave's state, on 1 or 2 threads. The time per batch beyond the items'
// own work is the hand-off: publishing the batch, claiming items, counting them done, waiting for the last.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <vector>

#include "esc/firmware_threads.hpp"

namespace {

using namespace vecat;

struct Items {
    // One 256-byte block per item, apart from the others' (as each slave's state is its own).
    std::vector<std::uint64_t> words;
    static constexpr std::size_t kWords = 32;
    static void work(void* self, std::size_t item) {
        auto& items = *static_cast<Items*>(self);
        std::uint64_t* w = items.words.data() + item * kWords;
        for (std::size_t i = 1; i < kWords; ++i)
            w[i] += w[i - 1] + 1;
    }
};

void BM_FirmwareThreadsBatch(benchmark::State& state) {
    const auto count = static_cast<std::size_t>(state.range(0));
    esc::FirmwareThreads threads(static_cast<unsigned>(state.range(1)));
    Items items;
    items.words.assign(count * Items::kWords, 0);
    for (auto _ : state) {
        threads.run(count, &Items::work, &items);
        benchmark::DoNotOptimize(items.words.data());
    }
    state.counters["items_on_workers"] = benchmark::Counter(static_cast<double>(threads.items_on_workers()) /
                                                            static_cast<double>(state.iterations()));
}
BENCHMARK(BM_FirmwareThreadsBatch)->ArgsProduct({{16, 128, 512}, {1, 2}})->UseRealTime();

}  // namespace
