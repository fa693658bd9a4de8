// TWINsync: encoding and checking one telegram, and one control cycle of an option card (build the
// telegram from the mapped parameters, send it, receive and check the partner's, copy its PDOs, monitor).
#include <benchmark/benchmark.h>

#include "cia402/drive.hpp"
#include "cia402/twinsync_port.hpp"
#include "device/device_description.hpp"
#include "twinsync/telegram.hpp"

namespace {

using namespace vecat;

void BM_TwinsyncTelegramEncodeDecode(benchmark::State& state) {
    twinsync::Telegram t;
    t.pdo_size = static_cast<std::uint8_t>(state.range(0));
    for (std::size_t i = 0; i < t.pdo_size; ++i)
        t.pdo[i] = static_cast<std::uint8_t>(i);
    std::array<std::uint8_t, twinsync::kMaxFrameBytes> buf{};
    twinsync::Telegram out;
    for (auto _ : state) {
        t.status++;
        const std::size_t n = twinsync::encode(t, Bytes(buf.data(), buf.size()));
        benchmark::DoNotOptimize(
            twinsync::decode(ConstBytes(buf.data(), n), twinsync::Layout::Standard, t.pdo_size, out));
    }
    state.SetLabel(std::to_string(6 + t.pdo_size) + "-byte frame");
}
BENCHMARK(BM_TwinsyncTelegramEncodeDecode)->Arg(10)->Arg(26);

// Both cards of a gantry (modes 29/30) for one control cycle: each transmits, then each receives.
void BM_TwinsyncPortCycle(benchmark::State& state) {
    const auto dev = device::default_drive();
    cia402::Drive a(dev), b(dev);
    cia402::connect_twinsync(a, b);
    cia402::apply_twinsync_preset(a, b, cia402::TwinsyncPreset::Gantry);
    auto& pa = a.twinsync_port();
    auto& pb = b.twinsync_port();
    twinsync::LocalState local;
    std::uint64_t t = 1'000'000;
    for (auto _ : state) {
        t += cia402::Drive::kServoPeriodNs;
        pa.transmit(t, local);
        pb.transmit(t, local);
        pa.receive(t + 1, local);
        pb.receive(t + 1, local);
    }
    if (pb.status().crc_errors != 0 || !pb.status().link_ok) state.SkipWithError("link not working");
    state.SetLabel("two cards, per control cycle");
}
BENCHMARK(BM_TwinsyncPortCycle);

}  // namespace
