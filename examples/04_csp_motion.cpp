// 04_csp_motion: a jerk-limited move in cyclic synchronous position mode. The master generates the set
// points every 1 ms cycle with cia402::ProfileGenerator, as a controller's NC does, and watches the
// following error the drive reports.
#include <cmath>
#include <cstdio>

#include "cia402/profile_generator.hpp"
#include "testing/virtual_segment.hpp"

using namespace vecat;

int main() {
    testing::VirtualSegment vs({.drives = 1});
    if (!vs.enable(0)) return 1;

    // One revolution is 2^20 increments; move half a revolution at up to 1 rev/s, 10 rev/s², 200 rev/s³.
    constexpr double kRev = 1 << 20;
    const double start = vs.position(0);
    cia402::ProfileGenerator gen;
    gen.reset({start, 0, 0});
    const cia402::ProfileLimits lim{1.0 * kRev, 10.0 * kRev, 10.0 * kRev, 200.0 * kRev};
    if (!gen.move_to(start + 0.5 * kRev, lim)) return 1;

    double worst = 0;
    int cycles = 0;
    while (!gen.done()) {
        const cia402::Kinematics k = gen.step(1e-3);
        vs.set_target_position(0, static_cast<std::int32_t>(std::lround(k.p)));
        if (!vs.cycle()) return 1;
        worst = std::max(worst, std::abs(k.p - vs.position(0)));
        if (++cycles % 100 == 0)
            std::printf("t=%4d ms demand %10.0f actual %10d velocity %8d\n", cycles, k.p, vs.position(0),
                        vs.velocity(0));
    }
    vs.cycles(50);  // settle
    const double error = std::abs(start + 0.5 * kRev - vs.position(0));
    std::printf("move of %.0f increments in %d ms; largest demand-actual %.0f, final error %.0f\n",
                0.5 * kRev, cycles, worst, error);
    return error < 100 ? 0 : 1;
}
