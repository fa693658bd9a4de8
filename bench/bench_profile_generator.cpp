// Profile generator: time to plan one profile and to evaluate one cycle.
#include "cia402/profile_generator.hpp"

#include <benchmark/benchmark.h>

namespace {

using vecat::cia402::Kinematics;
using vecat::cia402::ProfileGenerator;
using vecat::cia402::ProfileLimits;

const ProfileLimits kJerk{2000, 5000, 10000, 50000};
const ProfileLimits kTrapezoid{2000, 5000, 10000, 0};

// Plan from rest: range(0) = 0 long move (V reached: no search), 1 short move (V not reached: regula falsi
// on the cruise level), 2 trapezoid.
void BM_PlanFromRest(benchmark::State& state) {
    const bool shortmove = state.range(0) == 1;
    const ProfileLimits& lim = state.range(0) == 2 ? kTrapezoid : kJerk;
    ProfileGenerator g;
    double target = shortmove ? 500 : 5000;
    for (auto _ : state) {
        g.reset({0, 0, 0});
        benchmark::DoNotOptimize(g.move_to(target, lim));
        benchmark::DoNotOptimize(g.remaining_time());
        target += 1e-3;  // not the same input twice
    }
}
BENCHMARK(BM_PlanFromRest)->Arg(0)->Arg(1)->Arg(2);

// Replan from a moving state: range(0) = 0 new target ahead (direct), 1 new target overshot (stop and
// return), 2 new target ahead but too close for V (search of the cruise level from the moving state).
void BM_PlanFromMoving(benchmark::State& state) {
    const Kinematics moving{1000, 1500, 2500};
    const double targets[] = {6000, 900, 1700};
    double target = targets[state.range(0)];
    ProfileGenerator g;
    for (auto _ : state) {
        g.reset(moving);
        benchmark::DoNotOptimize(g.move_to(target, kJerk));
        benchmark::DoNotOptimize(g.remaining_time());
        target += 1e-6;
    }
}
BENCHMARK(BM_PlanFromMoving)->Arg(0)->Arg(1)->Arg(2);

// One cycle of 1 ms on a long move (replanned when it ends).
void BM_Step(benchmark::State& state) {
    ProfileGenerator g;
    g.reset({0, 0, 0});
    g.move_to(1e6, kJerk);
    double target = 0;
    for (auto _ : state) {
        benchmark::DoNotOptimize(g.step(1e-3));
        if (g.done()) g.move_to(target, kJerk), target = 1e6 - target;
    }
}
BENCHMARK(BM_Step);

// One cycle with a position compensation in progress.
void BM_StepCompensating(benchmark::State& state) {
    ProfileGenerator g;
    auto restart = [&g] {
        g.reset({0, 0, 0});
        g.move_to(1e9, kJerk);
        g.step(1);
        g.compensate(1e5, 1e8);
    };
    restart();
    for (auto _ : state) {
        benchmark::DoNotOptimize(g.step(1e-3));
        if (!g.compensating()) restart();
    }
}
BENCHMARK(BM_StepCompensating);

}  // namespace
