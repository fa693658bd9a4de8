// 05_twinsync_gantry: two drives coupled by a TWINsync cable with the gantry preset. The master commands
// drive 1 only (CSP); drive 2 follows its partner over TWINsync, not over EtherCAT. The tracking error is
// the difference of the two actual positions the master reads.
#include <cmath>
#include <cstdio>

#include "cia402/profile_generator.hpp"
#include "testing/virtual_segment.hpp"

using namespace vecat;

int main() {
    testing::VirtualSegment vs({.drives = 2, .twinsync = cia402::TwinsyncPreset::Gantry});
    vs.set_mode(1, 8);
    vs.cycles(50);  // the TWINsync link comes up and synchronises
    const auto* link = vs.drive(1).twinsync_status();
    if (!link || !link->synchronised) return 1;
    std::printf("TWINsync link up, drive 2 synchronised\n");

    if (!vs.enable(0)) return 1;  // drive 2 is enabled by drive 1's control word through TWINsync
    std::printf("drive 1 enabled by EtherCAT, drive 2 follows: %s\n",
                vs.drive(1).cia402_state() == cia402::State::OperationEnabled ? "enabled" : "NOT enabled");
    if (vs.drive(1).cia402_state() != cia402::State::OperationEnabled) return 1;

    constexpr double kRev = 1 << 20;
    const double start = vs.position(0);
    cia402::ProfileGenerator gen;
    gen.reset({start, 0, 0});
    gen.move_to(start + kRev, {2.0 * kRev, 20.0 * kRev, 20.0 * kRev, 400.0 * kRev});
    double worst = 0;
    int cycles = 0;
    while (!gen.done()) {
        vs.set_target_position(0, static_cast<std::int32_t>(std::lround(gen.step(1e-3).p)));
        if (!vs.cycle()) return 1;
        const double e = std::abs(static_cast<double>(vs.position(0)) - vs.position(1));
        worst = std::max(worst, e);
        if (++cycles % 100 == 0)
            std::printf("t=%4d ms drive 1 %10d drive 2 %10d tracking error %5.0f\n", cycles, vs.position(0),
                        vs.position(1), e);
    }
    vs.cycles(100);
    std::printf(
        "one revolution in %d ms: largest tracking error %.0f increments (%.3f %% of a revolution), "
        "final %d\n",
        cycles, worst, worst / kRev * 100.0, vs.position(0) - vs.position(1));
    return worst < 2000 && std::abs(vs.position(0) - vs.position(1)) <= 5 ? 0 : 1;
}
