// A machine of 1,000 devices (bench/network-1000.yaml: 200 drives, 800 I/O terminals) served in-process:
// the CPU one 1 ms cycle costs the slave side, the process data frames of the project master plus the
// firmware of every slave for that millisecond (the drives' four servo periods). Under 1 ms of CPU per
// cycle on one core is what serving the machine at 1 ms takes.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>

#include "common/bytes.hpp"
#include "master/master.hpp"
#include "net/realtime.hpp"
#include "network/build.hpp"
#include "serve/in_process_link.hpp"

namespace {

using namespace vecat;

void BM_Network1000Cycle(benchmark::State& state) {
    // VECAT_BENCH_NETWORK: another file (a smaller one to profile).
    const char* other = std::getenv("VECAT_BENCH_NETWORK");
    const std::string file = other && *other ? other : VECAT_BENCH_DIR "/network-1000.yaml";
    auto built = network::build_network(network::read_network_file(file), file);
    net::InProcessLink link(*built.segment);
    std::uint64_t now = 1'000'000'000;
    link.set_time(now);
    master::Master m(link);
    if (!m.startup(protocol::AlState::Op)) throw std::runtime_error("start-up failed");
    std::uint64_t misses = 0;
    // Arg 0: every slave's firmware runs once a millisecond besides the frames (as a tick of the serve loop
    // would); arg 1: only at the slaves' deadlines, as the serve loop does while frames keep coming; arg 2:
    // as 1, with the drives enabled in cyclic synchronous position mode holding their position (what
    // vecat-roundtrip does).
    const bool every_ms = state.range(0) == 0;
    esc::Segment& seg = *built.segment;
    if (state.range(0) == 2) {
        // The drives' RxPDO starts with the controlword, the mode and the target position; their TxPDO
        // with the statusword and the actual position (the vecat drive's default mapping).
        for (const std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}})
            for (int c = 0; c < 10; ++c) {
                for (std::size_t i = 0; i < m.slaves().size(); ++i) {
                    auto out = m.outputs(i);
                    const auto in = m.inputs(i);
                    if (out.size() < 8 || in.size() < 8) continue;
                    st_le16(out.data(), cw);
                    out[2] = 8;
                    std::copy_n(in.data() + 4, 4, out.data() + 4);
                }
                now += 1'000'000;
                link.set_time(now);
                m.exchange_process_data();
            }
        int enabled = 0;
        for (std::size_t i = 0; i < m.slaves().size(); ++i)
            if (m.inputs(i).size() >= 8 && (ld_le16(m.inputs(i).data()) & 0x6F) == 0x27) ++enabled;
        state.counters["enabled"] = enabled;
    }
    // As the serve loop does before it serves (ServeOptions::huge_pages).
    net::back_heap_with_huge_pages();
    const std::uint64_t runs0 = seg.counters().firmware_runs;
    for (auto _ : state) {
        now += 1'000'000;
        link.set_time(now);
        if (every_ms || seg.next_firmware_ns() <= now) seg.tick(now);
        if (m.exchange_process_data().value_or(0) != m.expected_wkc()) ++misses;
    }
    state.counters["frames"] = static_cast<double>(m.process_data_frames());
    state.counters["misses"] = static_cast<double>(misses);
    // Firmware runs of one slave each, per cycle (of 1,000 slaves).
    state.counters["runs"] = benchmark::Counter(static_cast<double>(seg.counters().firmware_runs - runs0),
                                                benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_Network1000Cycle)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

}  // namespace
