// Cost of the drive's servo period (state machine, mode, profile, mechanics with 4 substeps, feedback) on
// the thread that processes frames.
#include <benchmark/benchmark.h>

#include "cia402/drive.hpp"
#include "protocol/cia402.hpp"
#include "protocol/cia402_objects.hpp"

namespace {

using vecat::cia402::Drive;
namespace obj = vecat::protocol::obj;
namespace cmd = vecat::protocol::cia402::cmd;

void BM_DriveServoPeriod(benchmark::State& state) {
    Drive d(vecat::device::default_drive());
    auto& od = d.dictionary();
    od.find(obj::modes_of_operation)->set(static_cast<std::int8_t>(state.range(0)));
    od.find(obj::target_velocity)->set(std::int32_t{200'000});
    std::uint64_t now = 1'000'000'000;
    d.tick(now);
    for (std::uint16_t cw : {cmd::Shutdown, cmd::SwitchOn, cmd::EnableOperation}) {
        od.find(obj::controlword)->set(cw);
        now += 1'000'000;
        d.tick(now);
    }
    std::int32_t target = 0;
    for (auto _ : state) {
        target += 100;
        od.find(obj::target_position)->set(target);
        now += Drive::kServoPeriodNs;
        d.tick(now);
    }
    benchmark::DoNotOptimize(d.position_actual());
    state.SetLabel(state.range(0) == 8 ? "CSP" : "PV");
}
BENCHMARK(BM_DriveServoPeriod)->Arg(8)->Arg(3);

// A servo period of a drive whose power stage is off (switch on disabled, the motor at rest): what every
// drive of a line costs while the master brings it up (INIT, PREOP, SAFEOP).
void BM_DriveServoPeriodDisabled(benchmark::State& state) {
    Drive d(vecat::device::default_drive());
    std::uint64_t now = 1'000'000'000;
    d.tick(now);
    for (auto _ : state) {
        now += Drive::kServoPeriodNs;
        d.tick(now);
    }
    benchmark::DoNotOptimize(d.position_actual());
}
BENCHMARK(BM_DriveServoPeriodDisabled);

}  // namespace
