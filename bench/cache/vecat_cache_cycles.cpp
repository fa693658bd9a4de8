// vecat-cache-cycles: the cyclic exchange of a line of N vecat drives in OP, made to be measured under
// callgrind's cache model (see bench/README.md, "Large networks"). The start-up runs uninstrumented; only the
// measured cycles are (callgrind's client requests: run it with --instr-atstart=no). Outside valgrind it is
// an ordinary program that prints the firmware runs and the time per cycle.
//
//   valgrind --tool=callgrind --instr-atstart=no --cache-sim=yes --D1=32768,8,64 --LL=524288,8,64
//       build/bench/cache/vecat-cache-cycles --slaves 512 --cycles 10   (one command line)
//   callgrind_annotate --sort=DLmr callgrind.out.<pid>
//
// The totals' DLmr + DLmw are the lines a cycle misses in a 512 KB L2 cache (this machine's), times cycles.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <exception>
#include <memory>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "bench/drive_line.hpp"
#include "bench/summary.hpp"
#include "esc/firmware_threads.hpp"

#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#else
#define CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_STOP_INSTRUMENTATION
#endif

using namespace vecat;

int main(int argc, char** argv) {
    CLI::App app{"vecat-cache-cycles: cyclic exchanges of a line of drives, to be measured under callgrind"};
    std::size_t slaves = 512;
    unsigned cycles = 10;
    bool inline_firmware = false;
    unsigned threads = 1;
    unsigned frame_gap_us = 0;
    unsigned evict_mb = 0;
    unsigned period_us = 0;
    app.add_option("--slaves", slaves, "Virtual drives on the line")->check(CLI::Range(1, 4096));
    app.add_option("--cycles", cycles, "Measured cycles (after 5 unmeasured ones)")
        ->check(CLI::Range(1, 100000));
    app.add_flag(
        "--inline-firmware", inline_firmware,
        "Run the firmware within each frame (default: after the cycle's replies, as vecat run does)");
    app.add_option("--threads", threads, "Threads that run the firmware (as vecat run --threads)")
        ->check(CLI::Range(1, 64));
    app.add_option("--frame-gap-us", frame_gap_us,
                   "Time between the frames of a cycle, as they reach a line over a wire (default 0: all "
                   "at the cycle's time); with a gap, a frame that reads inputs finds drives whose local "
                   "cycle passed since their run, as in the soak of vecat-roundtrip")
        ->check(CLI::Range(0, 60));
    app.add_option("--evict-mb", evict_mb,
                   "Between cycles, write this many MB elsewhere (not timed), as the master, the kernel and "
                   "other programs do between the cycles of a soak: each cycle then starts with the caches "
                   "cold")
        ->check(CLI::Range(0, 1024));
    app.add_option(
           "--period-us", period_us,
           "Start a cycle every this many us, sleeping in between, as a master's cycles come (default "
           "0: one after the other); the report then also says how the cycles' times spread, and how "
           "many windows of 50 cycles were slower than 1.25 times the median on average")
        ->check(CLI::Range(0, 1'000'000));
    CLI11_PARSE(app, argc, argv);

    std::unique_ptr<bench::DriveLine> line;
    try {
        line = std::make_unique<bench::DriveLine>(slaves);
    } catch (const std::exception& e) {
        fmt::print(stderr, "{}\n", e.what());
        return 1;
    }
    esc::Segment& seg = *line->seg;
    seg.set_deferred_firmware(!inline_firmware);
    esc::FirmwareThreads workers(threads);
    if (threads > 1) seg.set_firmware_threads(&workers);
    // (The frames of a cycle must fit into it: time does not go back at the next cycle's start.)
    const std::size_t frames = line->m->process_data_frames();
    if (frames * frame_gap_us >= 1'000) {
        fmt::print(stderr, "{} frames {} us apart do not fit into a cycle of 1 ms\n", frames, frame_gap_us);
        return 2;
    }
    line->link->set_time_step(std::uint64_t{frame_gap_us} * 1'000);
    using Clock = std::chrono::steady_clock;
    const auto cycle = [&] {
        line->advance(1'000'000);  // 1 ms a cycle: four servo periods of every drive
        line->m->exchange_process_data();
        seg.run_deferred_firmware();
    };
    for (int c = 0; c < 5; ++c)
        cycle();
    std::vector<std::uint8_t> elsewhere(std::size_t{evict_mb} << 20);
    const std::uint64_t runs_before = seg.counters().firmware_runs;
    Clock::duration timed{};
    std::vector<std::uint32_t> each;  // --period-us: every cycle's time, ns
    each.reserve(period_us ? cycles : 0);
    auto next = Clock::now();
    CALLGRIND_START_INSTRUMENTATION;
    for (unsigned c = 0; c < cycles; ++c) {
        if (!elsewhere.empty()) {
            CALLGRIND_STOP_INSTRUMENTATION;
            for (std::size_t i = 0; i < elsewhere.size(); i += 64)
                elsewhere[i] = static_cast<std::uint8_t>(elsewhere[i] + c);
            CALLGRIND_START_INSTRUMENTATION;
        }
        if (period_us) {
            next += std::chrono::microseconds(period_us);
            std::this_thread::sleep_until(next);
        }
        const auto t0 = Clock::now();
        cycle();
        const auto took = Clock::now() - t0;
        timed += took;
        if (period_us)
            each.push_back(static_cast<std::uint32_t>(
                std::min<std::int64_t>(std::chrono::nanoseconds(took).count(), 0xFFFFFFFF)));
    }
    CALLGRIND_STOP_INSTRUMENTATION;
    fmt::print(
        "{} drives, {} cycles, {} thread(s), frames {} us apart: {:.2f} firmware runs a cycle, "
        "{:.1f} us a cycle\n",
        slaves, cycles, threads, frame_gap_us,
        static_cast<double>(seg.counters().firmware_runs - runs_before) / cycles,
        std::chrono::duration<double, std::micro>(timed).count() / cycles);
    if (!each.empty()) {
        // The cycles do the same work every time. Stretches of slower ones (windows of 50 cycles whose mean
        // is more than 1.25 times the median cycle) are the machine's doing: a neighbour on the host taking
        // the shared cache or the memory bus, a slower clock (bench/README.md, "Runs of misses").
        std::vector<std::uint32_t> sorted = each;
        const bench::Summary spread = bench::summarize(sorted);
        const double median = spread.p50 / 1e3;
        constexpr std::size_t kWindow = 50;
        std::size_t windows = 0, slow = 0;
        double slowest = 0;
        for (std::size_t i = 0; i + kWindow <= each.size(); i += kWindow, ++windows) {
            double sum = 0;
            for (std::size_t k = i; k < i + kWindow; ++k)
                sum += each[k] / 1e3;
            const double mean = sum / kWindow;
            slow += mean > 1.25 * median;
            slowest = std::max(slowest, mean);
        }
        fmt::print(
            "  a cycle every {} us: median {:.1f} us, p99 {:.1f}, p99.9 {:.1f}, max {:.1f}; {} of {} "
            "windows of {} cycles took more than 1.25 times the median on average, the slowest "
            "{:.1f} us\n",
            period_us, median, spread.p99 / 1e3, spread.p999 / 1e3, spread.max / 1e3, slow, windows, kWindow,
            slowest);
    }
    return 0;
}
