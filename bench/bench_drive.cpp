// Cost of the drive's servo period (state machine, mode, profile, mechanics with 4 substeps, feedback) on
// the thread that processes frames.
#include <benchmark/benchmark.h>

#include "cia402/drive.hpp"

namespace {

using vecat::cia402::Drive;

void BM_DriveServoPeriod(benchmark::State& state) {
    Drive d(vecat::device::default_drive());
    auto& od = d.dictionary();
    od.find(0x6060, 0)->set(static_cast<std::int8_t>(state.range(0)));
    od.find(0x60FF, 0)->set(std::int32_t{200'000});
    std::uint64_t now = 1'000'000'000;
    d.tick(now);
    for (int cw : {0x06, 0x07, 0x0F}) {
        od.find(0x6040, 0)->set(static_cast<std::uint16_t>(cw));
        now += 1'000'000;
        d.tick(now);
    }
    std::int32_t target = 0;
    for (auto _ : state) {
        target += 100;
        od.find(0x607A, 0)->set(target);
        now += Drive::kServoPeriodNs;
        d.tick(now);
    }
    benchmark::DoNotOptimize(d.position_actual());
    state.SetLabel(state.range(0) == 8 ? "CSP" : "PV");
}
BENCHMARK(BM_DriveServoPeriod)->Arg(8)->Arg(3);

}  // namespace
