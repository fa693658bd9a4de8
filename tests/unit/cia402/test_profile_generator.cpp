// The jerk-limited profile generator alone (no drive, no EtherCAT): the seven-phase profile, new targets
// in motion, override and its four types, position compensation and its stop (TX1250 2.1-2.5).
// Long (about 1,000 lines): one generator fixture for every profile case; the drive-level tests of the same
// behaviours are in tests/conformance/test_tx1250_nc_ptp.cpp.
#include "cia402/profile_generator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

namespace vecat::cia402 {
namespace {

constexpr double kRel = 1e-9;

ProfileLimits limits(double v, double up, double down, double jerk) {
    return {v, up, down, jerk};
}

// Checks the limits between consecutive samples of one generator; remembers the first violation.
class Watch {
  public:
    // scale: the magnitude of the distances, for the rounding allowed in positions.
    Watch(const ProfileLimits& lim, double dt, double scale = 1)
        : lim_(lim), dt_(dt), vbound_(lim.velocity), scale_(scale) {}

    // A new command at state k with velocity limit v: |v| may stay above it only while braking down.
    void command(const Kinematics& k, double v) {
        const double speeding = k.a * k.v > 0 ? std::abs(k.a) : 0.0;
        const double creep = lim_.jerk > 0 ? speeding * speeding / (2 * lim_.jerk) : 0.0;
        vbound_ = std::max(v, std::abs(k.v) + creep);
    }
    void restart() { have_prev_ = false; }
    void sample(const Kinematics& k) {
        ++samples_;
        if (!std::isfinite(k.p) || !std::isfinite(k.v) || !std::isfinite(k.a)) fail(k, "not finite");
        if (std::abs(k.v) > vbound_ * (1 + kRel) + 1e-12) fail(k, "velocity above the limit");
        const double amax = k.a * k.v > 0   ? lim_.acceleration
                            : k.a * k.v < 0 ? lim_.deceleration
                                            : std::max(lim_.acceleration, lim_.deceleration);
        if (std::abs(k.a) > amax * (1 + kRel) + 1e-12) fail(k, "acceleration above the limit");
        if (have_prev_) {
            // The position follows the velocity: trapezoidal rule error J dt^3/12 (jerk-limited) or at
            // most (A+ + A-) dt^2/4 around an acceleration jump; no jumps beyond rounding.
            const double step = k.p - prev_.p, rule = (k.v + prev_.v) / 2 * dt_;
            const double allowed = (lim_.jerk > 0 ? lim_.jerk * dt_ * dt_ * dt_ / 12 * (1 + 1e-6)
                                                  : (lim_.acceleration + lim_.deceleration) * dt_ * dt_ / 4) +
                                   1e-9 * (std::abs(k.p) + scale_);
            if (std::abs(step - rule) > allowed) fail(k, "position jump");
        }
        if (have_prev_ && lim_.jerk > 0) {
            const double jerk = std::abs(k.a - prev_.a) / dt_;
            if (jerk > lim_.jerk * (1 + 1e-7) + 1e-6 * amax / dt_) fail(k, "jerk above the limit");
        }
        prev_ = k;
        have_prev_ = true;
    }
    int failures() const { return failures_; }
    const std::string& first() const { return first_; }
    long samples() const { return samples_; }

  private:
    void fail(const Kinematics& k, const char* what) {
        if (failures_++ == 0) {
            std::ostringstream os;
            os.precision(17);
            os << what << " at sample " << samples_ << ": p=" << k.p << " v=" << k.v << " a=" << k.a
               << " (prev a=" << prev_.a << ") V=" << vbound_ << " A+=" << lim_.acceleration
               << " A-=" << lim_.deceleration << " J=" << lim_.jerk << " dt=" << dt_;
            first_ = os.str();
        }
    }
    ProfileLimits lim_;
    double dt_;
    double vbound_;
    double scale_;
    Kinematics prev_;
    bool have_prev_ = false;
    int failures_ = 0;
    long samples_ = 0;
    std::string first_;
};

// Steps until done; returns the number of steps (or -1 beyond max_steps).
long run_to_end(ProfileGenerator& g, double dt, long max_steps, Watch* w = nullptr) {
    for (long n = 1; n <= max_steps; ++n) {
        const Kinematics& k = g.step(dt);
        if (w) w->sample(k);
        if (g.done()) return n;
    }
    return -1;
}

ProfileGenerator at_rest(double p = 0) {
    ProfileGenerator g;
    g.reset({p, 0, 0});
    return g;
}

// ---- Closed form ----------------------------------------------------------------------------------------

struct Case {
    const char* name;
    double distance;
    ProfileLimits lim;
    double duration;  // by hand from the formulas
};

TEST(ProfileClosedForm, DurationsByHand) {
    const double tj = 5000.0 / 50000;  // A/J
    const Case cases[] = {
        // V and A reached: t = 2 (V/A + A/J) + (d - V (V/A + A/J)) / V.
        {"V and A reached", 2000, limits(2000, 5000, 5000, 50000), 2 * (0.4 + tj) + (2000 - 1000) / 2000.0},
        // A not reached (J < A^2/V): ramps of 2 sqrt(V/J) = 0.894427191 s.
        {"A not reached", 3000, limits(2000, 5000, 5000, 10000),
         4 * std::sqrt(0.2) + (3000 - 2000 * 2 * std::sqrt(0.2)) / 2000},
        // V not reached, A reached: T = A/J + sqrt((A/J)^2 + 4 d / A).
        {"V not reached", 800, limits(2000, 5000, 5000, 50000), tj + std::sqrt(tj * tj + 4 * 800 / 5000.0)},
        // Neither reached: T = 4 (d / 2J)^(1/3).
        {"V and A not reached", 50, limits(2000, 5000, 5000, 50000), 4 * std::cbrt(50 / 100000.0)},
        // Asymmetric: A+ ramp 0.4 + 0.1 s, A- ramp at the critical jerk 0.2 + 0.2 s, cruise 100/2000 s.
        {"asymmetric", 1000, limits(2000, 5000, 10000, 50000), 0.5 + 0.4 + 100 / 2000.0},
        // Asymmetric, V not reached: the symmetric min(A+, A-) of the manual.
        {"asymmetric, V not reached", 800, limits(2000, 5000, 10000, 50000),
         tj + std::sqrt(tj * tj + 4 * 800 / 5000.0)},
        // Trapezoid: 2000/5000 + 2000/10000 + (1000 - 400 - 200)/2000.
        {"trapezoid", 1000, limits(2000, 5000, 10000, 0), 0.4 + 0.2 + 0.2},
        // Trapezoid, V not reached: 2 sqrt(d / min(A+, A-)).
        {"trapezoid, V not reached", 100, limits(2000, 5000, 10000, 0), 2 * std::sqrt(100 / 5000.0)},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        EXPECT_NEAR(ProfileGenerator::rest_to_rest_duration(c.distance, c.lim), c.duration, 1e-12);
        EXPECT_NEAR(ProfileGenerator::rest_to_rest_duration(-c.distance, c.lim), c.duration, 1e-12);
        for (double dt : {125e-6, 1e-3, 4e-3}) {
            ProfileGenerator g = at_rest(10);
            ASSERT_TRUE(g.move_to(10 + c.distance, c.lim));
            EXPECT_NEAR(g.remaining_time(), c.duration, 1e-9);
            Watch w(c.lim, dt);
            const long n = run_to_end(g, dt, 100000, &w);
            ASSERT_GT(n, 0);
            // Done on the first sample at or after the closed-form end.
            const double steps = static_cast<double>(n);
            EXPECT_GE(steps * dt, c.duration - 1e-9);
            EXPECT_LT((steps - 1) * dt, c.duration + 1e-9);
            EXPECT_EQ(g.state().p, 10 + c.distance);
            EXPECT_EQ(w.failures(), 0) << w.first();
        }
    }
    EXPECT_EQ(ProfileGenerator::rest_to_rest_duration(0, limits(1, 1, 1, 1)), 0);
    EXPECT_EQ(ProfileGenerator::rest_to_rest_duration(1, limits(0, 1, 1, 1)), 0);
}

// Samples one profile exactly at given times (step evaluates the table in closed form).
std::vector<Kinematics> sample_at(ProfileGenerator g, const std::vector<double>& times) {
    std::vector<Kinematics> out;
    double t = 0;
    for (double ti : times) {
        g.step(ti - t);
        t = ti;
        out.push_back(g.state());
    }
    return out;
}

TEST(ProfileClosedForm, SevenPhaseBoundaries) {
    // Manual, dynamics 1.1 with a longer distance: A = 5000, J = 50000, V = 2000, 0 -> 2000.
    const double A = 5000, J = 50000, V = 2000, d = 2000;
    const double tj = A / J, ta = V / A - A / J, tacc = ta + 2 * tj, tc = (d - V * tacc) / V;
    ProfileGenerator g = at_rest();
    ASSERT_TRUE(g.move_to(d, limits(V, A, A, J)));
    // (the end is sampled just after the sum of the phase times, which is rounded)
    const std::vector<double> t = {
        tj, tj + ta, tacc, tacc + tc, tacc + tc + tj, tacc + tc + tj + ta, 2 * tacc + tc + 1e-12};
    const auto k = sample_at(g, t);
    const double p1 = J * tj * tj * tj / 6, v1 = J * tj * tj / 2;
    const double p2 = p1 + v1 * ta + A * ta * ta / 2, v2 = v1 + A * ta;
    EXPECT_NEAR(p1, 50000 * 0.001 / 6, 1e-12);  // 8.333 mm
    EXPECT_NEAR(k[0].p, p1, 1e-9);
    EXPECT_NEAR(k[0].v, v1, 1e-9);
    EXPECT_NEAR(k[0].a, A, 1e-9);
    EXPECT_NEAR(k[1].p, p2, 1e-9);
    EXPECT_NEAR(k[1].v, v2, 1e-9);
    EXPECT_NEAR(k[1].a, A, 1e-9);
    EXPECT_NEAR(k[2].p, V * tacc / 2, 1e-9);  // point symmetric ramp: mean velocity V/2
    EXPECT_NEAR(k[2].v, V, 1e-9);
    EXPECT_NEAR(k[2].a, 0, 1e-9);
    EXPECT_NEAR(k[3].p, d - V * tacc / 2, 1e-9);
    EXPECT_NEAR(k[3].v, V, 1e-9);
    EXPECT_NEAR(k[4].p, d - (V * tacc / 2 - (V * tj - p1)), 1e-9);  // braking mirrors the ramp-up
    EXPECT_NEAR(k[4].v, V - v1, 1e-9);
    EXPECT_NEAR(k[4].a, -A, 1e-9);
    EXPECT_NEAR(k[5].p, d - p1, 1e-9);
    EXPECT_NEAR(k[5].v, v1, 1e-9);
    EXPECT_EQ(k[6].p, d);
    EXPECT_EQ(k[6].v, 0);
    EXPECT_EQ(k[6].a, 0);
}

TEST(ProfileClosedForm, ShortMovesAndTrapezoid) {
    {  // neither V nor A reached: four jerk phases of T/4, peak acceleration J T/4
        const double J = 50000, d = 50, T = 4 * std::cbrt(d / (2 * J));
        ProfileGenerator g = at_rest();
        ASSERT_TRUE(g.move_to(d, limits(2000, 5000, 5000, J)));
        const auto k = sample_at(g, {T / 4, T / 2, 3 * T / 4});
        EXPECT_NEAR(k[0].p, J * std::pow(T / 4, 3) / 6, 1e-9);
        EXPECT_NEAR(k[0].a, J * T / 4, 1e-9);
        EXPECT_NEAR(k[1].p, d / 2, 1e-9);
        EXPECT_NEAR(k[1].v, J * (T / 4) * (T / 4), 1e-9);
        EXPECT_NEAR(k[2].p, d - J * std::pow(T / 4, 3) / 6, 1e-9);
    }
    {  // V reached, A not: peak acceleration sqrt(V J) at half the ramp
        const double V = 2000, J = 10000, tr = 2 * std::sqrt(V / J);
        ProfileGenerator g = at_rest();
        ASSERT_TRUE(g.move_to(3000, limits(V, 5000, 5000, J)));
        const auto k = sample_at(g, {tr / 2, tr});
        EXPECT_NEAR(k[0].a, std::sqrt(V * J), 1e-9);
        EXPECT_NEAR(k[0].v, V / 2, 1e-9);
        EXPECT_NEAR(k[1].p, V * tr / 2, 1e-9);
    }
    {  // trapezoid, asymmetric: accelerate 0.4 s at 5000, cruise 0.2 s, brake 0.2 s at 10000
        ProfileGenerator g = at_rest();
        ASSERT_TRUE(g.move_to(1000, limits(2000, 5000, 10000, 0)));
        const auto k = sample_at(g, {0.2, 0.4, 0.6, 0.7, 0.8});
        EXPECT_NEAR(k[0].p, 5000 * 0.04 / 2, 1e-9);
        EXPECT_NEAR(k[0].a, 5000, 1e-9);
        EXPECT_NEAR(k[1].p, 400, 1e-9);
        EXPECT_NEAR(k[2].p, 800, 1e-9);
        EXPECT_NEAR(k[3].v, 1000, 1e-9);
        EXPECT_NEAR(k[3].a, -10000, 1e-9);
        EXPECT_EQ(k[4].p, 1000);
    }
    {  // asymmetric, V not reached: braking uses min(A+, A-) = 5000, never 10000
        ProfileGenerator g = at_rest();
        ASSERT_TRUE(g.move_to(800, limits(2000, 5000, 10000, 50000)));
        double amin = 0;
        for (int i = 0; i < 2000 && !g.done(); ++i)
            amin = std::min(amin, g.step(1e-3).a);
        EXPECT_NEAR(amin, -5000, 1e-6);
    }
}

TEST(ProfileClosedForm, VelocityProfileAndStop) {
    const ProfileLimits lim = limits(2000, 5000, 10000, 50000);
    ProfileGenerator g = at_rest();
    ASSERT_TRUE(g.run_at(1000, lim));
    // 0 -> 1000 with A+ = 5000, J = 50000: A reached (V J >= A^2), t = V/A + A/J = 0.3 s.
    EXPECT_NEAR(g.remaining_time(), 0.3, 1e-12);
    Watch w(lim, 1e-3);
    EXPECT_EQ(run_to_end(g, 1e-3, 1000, &w), 300);
    EXPECT_EQ(g.state().v, 1000);
    const double p = g.state().p;
    g.step(0.5);  // holds the velocity
    EXPECT_NEAR(g.state().p, p + 500, 1e-9);
    EXPECT_TRUE(g.done());
    // Reverse: brake 1000 -> 0 with A- (critical jerk: 0.2 + 0.0 s... A-^2/J = 2000 > 1000: A not reached,
    // 2 sqrt(1000/50000)), then 0 -> -1000 with A+ (0.3 s).
    ASSERT_TRUE(g.run_at(-1000, lim));
    w.restart();  // after the unwatched half second
    EXPECT_NEAR(g.remaining_time(), 2 * std::sqrt(1000 / 50000.0) + 0.3, 1e-12);
    w.command(g.state(), 1000);
    EXPECT_GT(run_to_end(g, 1e-3, 2000, &w), 0);
    EXPECT_EQ(g.state().v, -1000);
    EXPECT_EQ(w.failures(), 0) << w.first();
    // |velocity| is limited to V.
    ASSERT_TRUE(g.run_at(-1e9, lim));
    EXPECT_GT(run_to_end(g, 1e-3, 2000, &w), 0);
    EXPECT_EQ(g.state().v, -2000);

    // Stop from V with deceleration D and jerk J: distance V (V/D + D/J) / 2, at rest, target() = there.
    ProfileGenerator h = at_rest();
    ASSERT_TRUE(h.run_at(2000, lim));
    run_to_end(h, 1e-3, 10000);
    const double p0 = h.state().p;
    h.stop(4000, 40000);
    EXPECT_NEAR(h.target(), p0 + 2000 * (0.5 + 0.1) / 2, 1e-9);
    EXPECT_NEAR(h.remaining_time(), 0.6, 1e-12);
    Watch ws(limits(2000, 4000, 4000, 40000), 1e-3);
    EXPECT_EQ(run_to_end(h, 1e-3, 10000, &ws), 600);
    EXPECT_EQ(ws.failures(), 0) << ws.first();
    EXPECT_EQ(h.state().v, 0);
    EXPECT_EQ(h.state().a, 0);
    EXPECT_NEAR(h.state().p, p0 + 600, 1e-9);
    // Without jerk limit: V^2 / 2D.
    ProfileGenerator q = at_rest();
    ASSERT_TRUE(q.run_at(-2000, limits(2000, 5000, 5000, 0)));
    q.step(1);
    q.stop(4000, 0);
    EXPECT_NEAR(q.target(), q.state().p - 2000.0 * 2000 / 8000, 1e-9);
}

// ---- Online changes -------------------------------------------------------------------------------------

TEST(ProfileOnline, OvershotTargetStopsAndReturns) {
    // Manual, "new end position with reversal": 0 -> 3000 at V = 2000, new end 2000 while fast.
    const ProfileLimits lim = limits(2000, 5000, 5000, 50000);
    ProfileGenerator g = at_rest();
    ASSERT_TRUE(g.move_to(3000, lim));
    Watch w(lim, 1e-3);
    while (g.state().p < 1900)
        w.sample(g.step(1e-3));
    ASSERT_NEAR(g.state().v, 2000, 1e-9);
    // Braking from 2000 takes 2000 (0.4 + 0.1) / 2 = 500 > 100: cannot stop before 2000.
    ASSERT_TRUE(g.move_to(2000, lim));
    w.command(g.state(), 2000);
    double pmax = 0;
    int reversals = 0;
    double vprev = g.state().v;
    for (int i = 0; i < 10000 && !g.done(); ++i) {
        const Kinematics& k = g.step(1e-3);
        w.sample(k);
        pmax = std::max(pmax, k.p);
        if (k.v < 0 && vprev >= 0) ++reversals;
        if (k.v > 0 && vprev < 0) ++reversals;
        vprev = k.v;
    }
    EXPECT_TRUE(g.done());
    EXPECT_EQ(g.state().p, 2000);
    EXPECT_EQ(g.state().v, 0);
    EXPECT_EQ(reversals, 1);
    EXPECT_NEAR(pmax, 1900 + 500, 5);  // stopped about where a full stop from V ends
    EXPECT_EQ(w.failures(), 0) << w.first();
}

TEST(ProfileOnline, NewEndPositionDuringBrakePhase) {
    // Manual, "new end position during the stop phase": 0 -> 3000, then 5000 while braking.
    const ProfileLimits lim = limits(2000, 5000, 5000, 50000);
    ProfileGenerator g = at_rest();
    ASSERT_TRUE(g.move_to(3000, lim));
    Watch w(lim, 1e-3);
    while (!g.in_brake_phase())
        w.sample(g.step(1e-3));
    for (int i = 0; i < 200; ++i)
        w.sample(g.step(1e-3));
    ASSERT_TRUE(g.move_to(5000, lim));
    w.command(g.state(), 2000);
    double vmin = g.state().v;
    for (int i = 0; i < 10000 && !g.done(); ++i) {
        w.sample(g.step(1e-3));
        if (!g.done()) vmin = std::min(vmin, g.state().v);
    }
    EXPECT_EQ(g.state().p, 5000);
    EXPECT_GT(vmin, 0);  // no reversal
    EXPECT_EQ(w.failures(), 0) << w.first();
}

TEST(ProfileOnline, LowerVelocityDeceleratesFirst) {
    const ProfileLimits lim = limits(2000, 5000, 5000, 50000);
    ProfileGenerator g = at_rest();
    ASSERT_TRUE(g.move_to(10000, lim));
    for (int i = 0; i < 1000; ++i)
        g.step(1e-3);
    ASSERT_NEAR(g.state().v, 2000, 1e-9);
    ASSERT_TRUE(g.move_to(10000, limits(1000, 5000, 5000, 50000)));
    EXPECT_NEAR(g.cruise_velocity(), 1000, 1e-12);
    Watch w(lim, 1e-3);
    w.command(g.state(), 1000);
    double vprev = g.state().v;
    bool monotone = true;
    for (int i = 0; i < 500; ++i) {  // 2000 -> 1000: 0.2 + 0.1 s
        const Kinematics& k = g.step(1e-3);
        w.sample(k);
        monotone = monotone && k.v <= vprev + 1e-12;
        vprev = k.v;
    }
    EXPECT_TRUE(monotone);
    EXPECT_NEAR(g.state().v, 1000, 1e-9);
    EXPECT_GT(run_to_end(g, 1e-3, 100000, &w), 0);
    EXPECT_EQ(g.state().p, 10000);
    EXPECT_EQ(w.failures(), 0) << w.first();
}

TEST(ProfileOnline, RepeatingTheSameMoveKeepsTheProfile) {
    // The drive may replan every cycle with an unchanged set-point: the curve must not change.
    for (const ProfileLimits& lim :
         {limits(2000, 5000, 10000, 50000), limits(2000, 5000, 5000, 10000), limits(2000, 5000, 10000, 0)}) {
        for (double d : {3000.0, 800.0, 20.0}) {
            ProfileGenerator a = at_rest(), b = at_rest();
            ASSERT_TRUE(a.move_to(d, lim));
            ASSERT_TRUE(b.move_to(d, lim));
            double worst = 0;
            long steps = 0;
            while (!a.done() && steps < 100000) {
                a.step(1e-3);
                b.step(1e-3);
                ASSERT_TRUE(b.move_to(d, lim));
                worst = std::max(worst, std::abs(a.state().p - b.state().p));
                ++steps;
            }
            EXPECT_LT(worst, 1e-9 * d) << d;
            EXPECT_EQ(b.step(1e-3).p, d);
            EXPECT_TRUE(b.done());
            double reversed = 0;  // never a return move near the end
            ProfileGenerator c = at_rest();
            ASSERT_TRUE(c.move_to(d, lim));
            while (!c.done()) {
                reversed = std::min(reversed, c.step(1e-3).v);
                ASSERT_TRUE(c.move_to(d, lim));
            }
            // Rounding only: ~1300 replans leave the state ~1e-9 V off the curve, a stop from it may dip.
            EXPECT_GT(reversed, -1e-8 * lim.velocity);
        }
    }
}

// ---- Override -------------------------------------------------------------------------------------------

TEST(ProfileOverride, HundredSeventyFiveHundred) {
    // Manual: override 100 % -> 75 % -> 100 %, V = 2000, 0 -> 5000.
    const ProfileLimits lim = limits(2000, 5000, 5000, 50000);
    ProfileGenerator g = at_rest();
    ASSERT_TRUE(g.move_to(5000, lim));
    Watch w(lim, 1e-3);
    for (int i = 0; i < 600; ++i)
        w.sample(g.step(1e-3));
    ASSERT_NEAR(g.state().v, 2000, 1e-9);
    g.set_override(0.75);
    EXPECT_EQ(g.override_fraction(), 0.75);
    EXPECT_NEAR(g.cruise_velocity(), 1500, 1e-12);
    double vmin = 1e9;
    for (int i = 0; i < 400; ++i)
        vmin = std::min(vmin, (w.sample(g.step(1e-3)), g.state().v));
    EXPECT_NEAR(g.state().v, 1500, 1e-9);  // the new level is held
    EXPECT_NEAR(vmin, 1500, 1e-9);         // and not undershot
    g.set_override(1.0);
    double vmax = 0;
    for (int i = 0; i < 400; ++i)
        vmax = std::max(vmax, (w.sample(g.step(1e-3)), g.state().v));
    EXPECT_NEAR(vmax, 2000, 1e-9);
    EXPECT_GT(run_to_end(g, 1e-3, 100000, &w), 0);
    EXPECT_EQ(g.state().p, 5000);
    EXPECT_EQ(w.failures(), 0) << w.first();
}

TEST(ProfileOverride, TwentyToHundred) {
    const ProfileLimits lim = limits(2000, 5000, 5000, 50000);
    ProfileGenerator g = at_rest();
    g.set_override(0.2);
    ASSERT_TRUE(g.move_to(5000, lim));
    EXPECT_NEAR(g.cruise_velocity(), 400, 1e-12);
    Watch w(lim, 1e-3);
    double vmax = 0;
    for (int i = 0; i < 1000; ++i)
        vmax = std::max(vmax, (w.sample(g.step(1e-3)), g.state().v));
    EXPECT_NEAR(vmax, 400, 1e-9);
    EXPECT_NEAR(g.state().v, 400, 1e-9);
    g.set_override(1.0);
    vmax = 0;
    while (!g.done())
        vmax = std::max(vmax, (w.sample(g.step(1e-3)), g.state().v));
    EXPECT_NEAR(vmax, 2000, 1e-9);  // 4600 mm left: room for the full level
    EXPECT_EQ(g.state().p, 5000);
    EXPECT_EQ(w.failures(), 0) << w.first();
}

// TX1250 2.2, the four override types: odd ones scale the level calculated at the start (here reduced:
// 0 -> 500 cannot reach V = 2000 with A = 5000), even ones V; types 1/2 keep the table when the new level
// is not achievable, 3/4 take the largest achievable one.
TEST(ProfileOverride, TypesScaleTheLevelOrTheVelocityAndKeepOrReduce) {
    const ProfileLimits lim = limits(2000, 5000, 5000, 0);
    const double level = std::sqrt(5000.0 * 500);  // the triangle's peak
    for (int type = 1; type <= 4; ++type) {
        ProfileGenerator g = at_rest();
        g.set_override_type(type);
        g.set_override(0.5);
        ASSERT_TRUE(g.move_to(500, lim));
        EXPECT_NEAR(g.cruise_velocity(), 0.5 * (type % 2 == 1 ? level : 2000), 1e-6 * level) << type;
        EXPECT_GT(run_to_end(g, 1e-3, 100000), 0);
        EXPECT_EQ(g.state().p, 500);
    }
    // 20 % of V up to 100 % 100 before the end of 0 -> 5000: 2000 is not achievable any more.
    for (int type = 1; type <= 4; ++type) {
        ProfileGenerator g = at_rest();
        g.set_override_type(type);
        g.set_override(0.2);
        ASSERT_TRUE(g.move_to(5000, lim));
        while (g.state().p < 4900)
            g.step(1e-3);
        g.set_override(1.0);
        if (type <= 2)
            EXPECT_NEAR(g.cruise_velocity(), 400, 1e-9) << type << ": the old table";
        else
            EXPECT_GT(g.cruise_velocity(), 600) << type << ": the largest achievable level";
        EXPECT_LT(g.cruise_velocity(), 2000) << type;
        EXPECT_GT(run_to_end(g, 1e-3, 100000), 0);
        EXPECT_EQ(g.state().p, 5000);
    }
    ProfileGenerator g;
    g.set_override_type(7);
    EXPECT_EQ(g.override_type(), 4);
}

TEST(ProfileOverride, ZeroStopsAndResumes) {
    const ProfileLimits lim = limits(2000, 5000, 5000, 50000);
    ProfileGenerator g = at_rest();
    ASSERT_TRUE(g.move_to(5000, lim));
    for (int i = 0; i < 800; ++i)
        g.step(1e-3);
    g.set_override(0);
    Watch w(lim, 1e-3);
    for (int i = 0; i < 2000; ++i)
        w.sample(g.step(1e-3));
    EXPECT_EQ(g.state().v, 0);
    EXPECT_EQ(g.state().a, 0);
    EXPECT_LT(g.state().p, 5000);
    EXPECT_FALSE(g.done());  // the move waits
    EXPECT_EQ(g.target(), 5000);
    g.set_override(1);
    EXPECT_GT(run_to_end(g, 1e-3, 100000, &w), 0);
    EXPECT_EQ(g.state().p, 5000);
    EXPECT_EQ(w.failures(), 0) << w.first();

    // Starting with override 0: nothing moves until the override rises.
    ProfileGenerator h = at_rest();
    h.set_override(0);
    ASSERT_TRUE(h.move_to(100, lim));
    for (int i = 0; i < 100; ++i)
        h.step(1e-3);
    EXPECT_EQ(h.state().p, 0);
    EXPECT_FALSE(h.done());
    h.set_override(0.5);
    EXPECT_GT(run_to_end(h, 1e-3, 100000), 0);
    EXPECT_EQ(h.state().p, 100);
}

TEST(ProfileOverride, IgnoredInBrakePhase) {
    const ProfileLimits lim = limits(2000, 5000, 5000, 50000);
    ProfileGenerator a = at_rest(), b = at_rest();
    ASSERT_TRUE(a.move_to(3000, lim));
    ASSERT_TRUE(b.move_to(3000, lim));
    while (!a.in_brake_phase()) {
        a.step(1e-3);
        b.step(1e-3);
    }
    a.set_override(0.5);
    EXPECT_EQ(a.override_fraction(), 0.5);  // stored for the next move
    a.step(1e-3);
    b.step(1e-3);
    a.set_override(0);  // a stop by override is ignored in the brake phase too
    int differences = 0;
    while (!b.done()) {
        differences += a.step(1e-3).p != b.step(1e-3).p;
    }
    EXPECT_EQ(differences, 0);
    EXPECT_TRUE(a.done());
    EXPECT_EQ(a.state().p, 3000);
}

// ---- Position compensation ------------------------------------------------------------------------------

struct CompRun {
    double compensation = 0;  // what compensate() promised
    double final_p = 0;
    double diff_at_length = 0;  // p - p(basic) once the basic move passed start + L
    double max_comp_velocity = 0;
    bool monotone = true;
    bool accepted = false;
};

// Basic move 0 -> 10000 at V = 2000 (A = 1000, J = 10000: ramps of 2.1 s), compensation at t = 2.5 s.
CompRun compensate_run(double d, double l, const CompensationLimits& c) {
    const ProfileLimits lim = limits(2000, 1000, 1000, 10000);
    ProfileGenerator g = at_rest(), basic = at_rest();
    g.move_to(10000, lim);
    basic.move_to(10000, lim);
    for (int i = 0; i < 2500; ++i) {
        g.step(1e-3);
        basic.step(1e-3);
    }
    CompRun r;
    const double start = g.state().p;
    r.accepted = g.compensate(d, l, c);
    r.compensation = g.compensation();
    double prev = 0;
    bool measured = false;
    while (!g.done()) {
        const double p = g.step(1e-3).p, pb = basic.step(1e-3).p;
        const double diff = p - pb;
        r.max_comp_velocity = std::max(r.max_comp_velocity, std::abs(g.state().v - basic.state().v));
        if (d > 0 ? diff < prev - 1e-9 : diff > prev + 1e-9) r.monotone = false;
        prev = diff;
        if (!measured && pb >= start + l) {
            r.diff_at_length = diff;
            measured = true;
        }
        if (measured) {
            EXPECT_NEAR(diff, r.diff_at_length, 1e-9);  // nothing after the compensation length
        }
    }
    r.final_p = g.state().p;
    return r;
}

TEST(ProfileCompensation, FullAsInTheManual) {
    // AK+ = 500, AK- = 1000, VK = 300, VP = 2000, L = 5000, D = 250 -> end position 10250.
    const CompRun r = compensate_run(250, 5000, {300, 500, 1000, 2000});
    ASSERT_TRUE(r.accepted);
    EXPECT_EQ(r.compensation, 250);
    EXPECT_EQ(r.final_p, 10250);
    EXPECT_NEAR(r.diff_at_length, 250, 1e-9);
    EXPECT_TRUE(r.monotone);
    // Peak of the trapezoid: 2 D / (T + sqrt(T^2 - 4 c D)), T = L/VP, c = 1/2AK+ + 1/2AK-.
    const double T = 2.5, c = 1 / 1000.0 + 1 / 2000.0;
    EXPECT_NEAR(r.max_comp_velocity, 2 * 250 / (T + std::sqrt(T * T - 4 * c * 250)), 0.5);
}

TEST(ProfileCompensation, NegativeAsInTheManual) {
    const CompRun r = compensate_run(-250, 5000, {300, 500, 1000, 2000});
    ASSERT_TRUE(r.accepted);
    EXPECT_EQ(r.compensation, -250);
    EXPECT_EQ(r.final_p, 9750);
    EXPECT_TRUE(r.monotone);
}

TEST(ProfileCompensation, PartialIsTheMaximumPossible) {
    // Manual: VK = 500, L = 2000, D = 500 -> not achievable. In T = L/VP = 1 s the largest distance is the
    // triangle of slopes 500 and 1000: peak 1 / (1/500 + 1/1000) = 333.3, area 166.67 (the manual's
    // figure reads 10165).
    const double peak = 1 / (1 / 500.0 + 1 / 1000.0), best = peak / 2;
    const CompRun r = compensate_run(500, 2000, {500, 500, 1000, 2000});
    ASSERT_TRUE(r.accepted);
    EXPECT_NEAR(r.compensation, best, 1e-9);
    EXPECT_NEAR(r.final_p, 10000 + best, 1e-9);
    EXPECT_NEAR(r.diff_at_length, best, 1e-9);
    EXPECT_NEAR(r.max_comp_velocity, peak, 1.0);
    // Limited by VK instead: trapezoid at VK = 100 over 2.5 s: 100 (2.5 - 100 c).
    const CompRun v = compensate_run(1000, 5000, {100, 500, 1000, 2000});
    EXPECT_NEAR(v.compensation, 100 * (2.5 - 100 * (1 / 1000.0 + 1 / 2000.0)), 1e-9);
    EXPECT_NEAR(v.final_p, 10000 + v.compensation, 1e-9);
    EXPECT_NEAR(v.max_comp_velocity, 100, 1e-6);
}

// TX1250 2.5, compensation stop: the rise or hold ends at once, the falling ramp follows, and D becomes
// what is compensated until it ends. The manual's full compensation (VK = 300, AK+ = 500, AK- = 1000,
// VP = 2000, L = 5000, D = 250) stopped 1 s after its start: the hold at the peak ended at tau = 1 s.
TEST(ProfileCompensation, StopKeepsTheDistanceCompensatedUntilTheFallEnds) {
    const ProfileLimits lim = limits(2000, 1000, 1000, 10000);
    ProfileGenerator g = at_rest();
    g.move_to(10000, lim);
    for (int i = 0; i < 2500; ++i)
        g.step(1e-3);
    ASSERT_NEAR(g.state().v, 2000, 1e-9);
    ASSERT_TRUE(g.compensate(250, 5000, {300, 500, 1000, 2000}));
    for (int i = 0; i < 1000; ++i)
        g.step(1e-3);
    ASSERT_TRUE(g.stop_compensation());
    const double T = 2.5, c = 1 / 1000.0 + 1 / 2000.0;
    const double peak = 2 * 250 / (T + std::sqrt(T * T - 4 * c * 250)), t1 = peak / 500, tau = 1.0;
    const double expected = peak * t1 / 2 + peak * (tau - t1) + peak * peak / (2 * 1000);
    EXPECT_NEAR(g.compensation(), expected, 1e-6);
    EXPECT_NEAR(g.target(), 10000 + expected, 1e-6);
    EXPECT_GT(run_to_end(g, 1e-3, 100000), 0);
    EXPECT_NEAR(g.state().p, 10000 + expected, 1e-6);
    EXPECT_FALSE(g.stop_compensation()) << "none left";
    // In the falling ramp it is too late.
    ProfileGenerator h = at_rest();
    h.move_to(10000, lim);
    for (int i = 0; i < 2500; ++i)
        h.step(1e-3);
    ASSERT_TRUE(h.compensate(250, 5000, {300, 500, 1000, 2000}));
    for (int i = 0; i < 2450; ++i)  // the fall takes peak / 1000 = 0.1 s before tau = 2.5 s
        h.step(1e-3);
    EXPECT_FALSE(h.stop_compensation());
    EXPECT_GT(run_to_end(h, 1e-3, 100000), 0);
    EXPECT_EQ(h.state().p, 10250);
}

TEST(ProfileCompensation, RefusalsAndDefaults) {
    const ProfileLimits lim = limits(2000, 1000, 1000, 10000);
    ProfileGenerator g = at_rest();
    EXPECT_FALSE(g.compensate(10, 100));  // no move
    ASSERT_TRUE(g.move_to(10000, lim));
    g.step(3);
    EXPECT_FALSE(g.compensate(0, 100));
    EXPECT_FALSE(g.compensate(10, 0));
    EXPECT_FALSE(g.compensate(10, 100, {0, 1, 1, 0}));
    // Default: the move's limits, VP = the cruise velocity; L longer than the rest is cut to the rest.
    ASSERT_TRUE(g.compensate(50, 1e9));
    EXPECT_FALSE(g.compensate(10, 100));  // already compensating
    EXPECT_EQ(g.target(), 10050);
    EXPECT_GT(run_to_end(g, 1e-3, 100000), 0);
    EXPECT_NEAR(g.state().p, 10050, 1e-9);
    // Not in a stop.
    ProfileGenerator h = at_rest();
    ASSERT_TRUE(h.move_to(10000, lim));
    h.step(3);
    h.stop(1000, 10000);
    EXPECT_FALSE(h.compensate(10, 100));
    // A stop during the compensation stops it with the basic move; the state stays continuous.
    ProfileGenerator s = at_rest();
    ASSERT_TRUE(s.move_to(10000, lim));
    s.step(3);
    ASSERT_TRUE(s.compensate(100, 2000, {300, 500, 1000, 0}));
    s.step(0.5);
    const double before = s.state().p;
    s.stop(1000, 10000);
    EXPECT_EQ(s.state().p, before);
    EXPECT_GT(run_to_end(s, 1e-3, 100000), 0);
    EXPECT_FALSE(s.compensating());
    EXPECT_EQ(s.state().v, 0);
    EXPECT_NEAR(s.state().p, s.target(), 1e-9);
}

TEST(ProfileCompensation, FollowsOverrideZero) {
    // Linear path control: with the basic move held by override 0 the compensation holds too, and it
    // completes once the basic move has travelled L after all.
    const ProfileLimits lim = limits(2000, 1000, 1000, 10000);
    ProfileGenerator g = at_rest();
    ASSERT_TRUE(g.move_to(10000, lim));
    g.step(2.5);
    ASSERT_TRUE(g.compensate(250, 5000, {300, 500, 1000, 2000}));
    g.step(0.8);
    g.set_override(0);
    EXPECT_GT(run_to_end(g, 1e-3, 3000), -2);  // held: not done
    EXPECT_EQ(g.state().v, 0);
    EXPECT_TRUE(g.compensating());
    const double held = g.state().p;
    g.step(1);
    EXPECT_EQ(g.state().p, held);
    g.set_override(1);
    EXPECT_GT(run_to_end(g, 1e-3, 100000), 0);
    EXPECT_EQ(g.state().p, 10250);
}

TEST(ProfileRandom, Compensations) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0, 1);
    int ran = 0;
    for (int n = 0; n < 300; ++n) {
        SCOPED_TRACE(::testing::Message() << "case " << n);
        const ProfileLimits lim = limits(1000 * (0.5 + u(rng)), 2000 * (0.5 + u(rng)), 2000 * (0.5 + u(rng)),
                                         u(rng) < 0.2 ? 0 : 20000 * (0.5 + u(rng)));
        const double dir = u(rng) < 0.5 ? -1 : 1;
        ProfileGenerator g = at_rest();
        ASSERT_TRUE(g.move_to(dir * 5000, lim));
        g.step(u(rng) * 4);
        const double d = (2 * u(rng) - 1) * 300, l = 100 + u(rng) * 6000;
        const CompensationLimits c{50 + 300 * u(rng), 100 + 1000 * u(rng), 100 + 1000 * u(rng), 0};
        if (!g.compensate(d, l, c)) continue;  // e.g. ended already
        ++ran;
        const double promised = g.compensation();
        EXPECT_LE(std::abs(promised), std::abs(d) * (1 + 1e-12));
        EXPECT_GE(promised * d, 0);
        EXPECT_NEAR(g.target(), dir * (5000 + promised), 1e-9);  // d counts along the path
        const double dt = u(rng) < 0.5 ? 1e-3 : 4e-3;
        Kinematics prev = g.state();
        bool finite = true, continuous = true;
        while (!g.done()) {
            const Kinematics& k = g.step(dt);
            finite = finite && std::isfinite(k.p) && std::isfinite(k.v) && std::isfinite(k.a);
            // Velocity bounded by V + VK (ratio of the basic velocity to VP is at most 1 here).
            continuous =
                continuous && std::abs(k.p - prev.p) <= (lim.velocity + c.velocity) * dt * (1 + 1e-9);
            prev = k;
        }
        EXPECT_TRUE(finite);
        EXPECT_TRUE(continuous);
        EXPECT_NEAR(g.state().p, dir * (5000 + promised), 1e-9);
        EXPECT_EQ(g.state().v, 0);
    }
    EXPECT_GT(ran, 200);
}

// ---- Numerics -------------------------------------------------------------------------------------------

TEST(ProfileNumerics, DegenerateInputs) {
    const ProfileLimits lim = limits(2000, 5000, 5000, 50000);
    ProfileGenerator g = at_rest(7);
    ASSERT_TRUE(g.move_to(7, lim));  // zero distance
    EXPECT_TRUE(g.done());
    EXPECT_EQ(g.step(1e-3).p, 7);
    // Tiny distances end exactly.
    for (double d : {1e-300, 1e-12, 1e-6}) {
        ProfileGenerator t = at_rest(1);
        ASSERT_TRUE(t.move_to(1 + d, lim));
        Watch w(lim, 1e-3);
        EXPECT_GT(run_to_end(t, 1e-3, 100, &w), 0);
        EXPECT_EQ(t.state().p, 1 + d);
        EXPECT_EQ(w.failures(), 0) << w.first();
    }
    // dt larger than the plan; dt = 0, negative, NaN, infinite change nothing.
    ProfileGenerator h = at_rest();
    ASSERT_TRUE(h.move_to(1000, lim));
    for (double dt : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()})
        EXPECT_EQ(h.step(dt).p, 0);
    EXPECT_EQ(h.step(1e6).p, 1000);
    EXPECT_TRUE(h.done());
    // Unusable limits are refused and the plan continues.
    ProfileGenerator r = at_rest();
    ASSERT_TRUE(r.move_to(1000, lim));
    const double nan = std::nan("");
    EXPECT_FALSE(r.move_to(5, limits(0, 1, 1, 1)));
    EXPECT_FALSE(r.move_to(5, limits(nan, 1, 1, 1)));
    EXPECT_FALSE(r.move_to(5, limits(1, -1, 1, 1)));
    EXPECT_FALSE(r.move_to(5, limits(1, 1, 1, nan)));
    EXPECT_FALSE(r.move_to(nan, lim));
    EXPECT_FALSE(r.run_at(nan, lim));
    r.set_override(nan);
    EXPECT_EQ(r.override_fraction(), 1);
    EXPECT_EQ(r.target(), 1000);
    EXPECT_GT(run_to_end(r, 1e-3, 10000), 0);
    EXPECT_EQ(r.state().p, 1000);
    // Infinite jerk = trapezoid.
    ProfileGenerator q = at_rest();
    ASSERT_TRUE(q.move_to(1000, limits(2000, 5000, 10000, std::numeric_limits<double>::infinity())));
    EXPECT_NEAR(q.remaining_time(), 0.8, 1e-12);
    // Unusable stop deceleration: at rest at once. reset() with garbage: finite.
    q.step(0.3);
    q.stop(nan, 0);
    EXPECT_EQ(q.state().v, 0);
    EXPECT_TRUE(q.done());
    q.reset({nan, std::numeric_limits<double>::infinity(), 1});
    EXPECT_TRUE(std::isfinite(q.state().p) && std::isfinite(q.state().v));
}

TEST(ProfileNumerics, HugeValues) {
    // Positions of 1e12 units, V 1e12, A 1e13, J 1e15 (and a 1e-3 unit move far from the origin).
    const ProfileLimits lim = limits(1e12, 1e13, 2e13, 1e15);
    ProfileGenerator g = at_rest(-1e12);
    ASSERT_TRUE(g.move_to(1e12, lim));
    Watch w(lim, 1e-3);
    EXPECT_GT(run_to_end(g, 1e-3, 10000, &w), 0);
    EXPECT_EQ(g.state().p, 1e12);
    EXPECT_EQ(w.failures(), 0) << w.first();
    ASSERT_TRUE(g.move_to(1e12 + 1e-3, lim));
    EXPECT_GT(run_to_end(g, 1e-3, 10000), 0);
    EXPECT_EQ(g.state().p, 1e12 + 1e-3);
    // Extreme but accepted limits stay finite.
    const ProfileLimits wide = limits(1e30, 1e-30, 1e30, 1e30);
    ProfileGenerator h = at_rest();
    ASSERT_TRUE(h.move_to(1e30, wide));
    EXPECT_TRUE(std::isfinite(h.remaining_time()));
    h.step(1e-3);
    EXPECT_TRUE(std::isfinite(h.state().p) && std::isfinite(h.state().v) && std::isfinite(h.state().a));
    EXPECT_FALSE(h.move_to(1e31, wide));
}

// ---- Seeded random --------------------------------------------------------------------------------------

double log_uniform(std::mt19937& rng, double lo, double hi) {
    return std::exp(std::uniform_real_distribution<double>(std::log(lo), std::log(hi))(rng));
}

// A random state inside the limits that can brake without reversing.
Kinematics random_state(std::mt19937& rng, const ProfileLimits& lim, double p) {
    std::uniform_real_distribution<double> u(0, 1);
    const double v = (2 * u(rng) - 1) * lim.velocity;
    if (lim.jerk == 0) return {p, v, 0};
    const bool speeding = u(rng) < 0.5;
    const double room = speeding ? lim.velocity - std::abs(v) : std::abs(v);
    const double amax =
        std::min(speeding ? lim.acceleration : lim.deceleration, std::sqrt(2 * lim.jerk * room));
    const double s = v >= 0 ? 1.0 : -1.0;
    return {p, v, (speeding ? s : -s) * u(rng) * amax};
}

TEST(ProfileRandom, MovesWithOnlineChanges) {
    const double dts[] = {125e-6, 1e-3, 4e-3};
    long cases = 0, samples = 0;
    for (unsigned seed : {1u, 2u, 3u}) {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<double> u(0, 1);
        for (int n = 0; n < 1000; ++n, ++cases) {
            SCOPED_TRACE(::testing::Message() << "seed " << seed << " case " << n);
            ProfileLimits lim;
            lim.velocity = log_uniform(rng, 0.1, 1e4);
            lim.acceleration = lim.velocity * log_uniform(rng, 1, 50);
            lim.deceleration = lim.velocity * log_uniform(rng, 1, 50);
            lim.jerk =
                u(rng) < 0.15 ? 0 : std::max(lim.acceleration, lim.deceleration) * log_uniform(rng, 2, 200);
            const double dt = dts[rng() % 3];
            const double scale = lim.velocity * log_uniform(rng, 0.001, 1.5);  // distances of moves
            ProfileGenerator g;
            g.reset(random_state(rng, lim, (2 * u(rng) - 1) * 1e4));
            double target = g.state().p + (2 * u(rng) - 1) * scale;
            ASSERT_TRUE(g.move_to(target, lim));
            Watch w(lim, dt, scale + 1e4);
            w.command(g.state(), lim.velocity);
            ProfileLimits cur = lim;
            // Events at random steps within the first second.
            const int events = static_cast<int>(rng() % 5);
            long next = static_cast<long>(u(rng) * 0.5 / dt);
            int done_events = 0;
            long step = 0;
            long budget = 0;
            auto bound = [&] {
                // Stop (generous) then a rest-to-rest move with the symmetric smaller limit.
                const Kinematics& k = g.state();
                const double a_min = std::min(cur.acceleration, cur.deceleration);
                const double t_stop = std::abs(k.v) / cur.deceleration +
                                      (cur.jerk > 0 ? 2 * (std::abs(k.a) + cur.deceleration) / cur.jerk : 0);
                const double reach = std::abs(k.v) * t_stop + std::abs(k.a) * t_stop * t_stop;
                const double f = g.override_fraction() > 0 ? g.override_fraction() : 1;
                const ProfileLimits sym{cur.velocity * f, a_min, a_min, cur.jerk};
                const double t =
                    t_stop + ProfileGenerator::rest_to_rest_duration(std::abs(target - k.p) + reach, sym);
                return static_cast<long>(t * 1.001 / dt) + 3;
            };
            budget = bound();
            long since = 0;
            bool ended = false;
            while (since <= budget || done_events < events) {
                if (done_events < events && step == next) {
                    const double kind = u(rng);
                    if (kind < 0.4) {
                        target = g.state().p + (2 * u(rng) - 1) * scale;
                        ASSERT_TRUE(g.move_to(target, cur));
                    } else if (kind < 0.7) {
                        cur.velocity = lim.velocity * log_uniform(rng, 0.1, 1);
                        ASSERT_TRUE(g.move_to(target, cur));
                    } else {
                        g.set_override(u(rng) < 0.2 ? 0.0 : 0.05 + 0.95 * u(rng));
                    }
                    if (done_events + 1 >= events && g.override_fraction() == 0) g.set_override(1);
                    const double f = g.override_fraction();
                    w.command(g.state(), cur.velocity * (f > 0 ? f : 1));
                    ++done_events;
                    next = step + 1 + static_cast<long>(u(rng) * 0.3 / dt);
                    budget = bound();
                    since = 0;
                }
                w.sample(g.step(dt));
                ++step;
                ++since;
                if (g.done() && done_events >= events) {
                    ended = true;
                    break;
                }
            }
            samples += w.samples();
            ASSERT_TRUE(ended) << "no end within " << budget << " steps";
            EXPECT_EQ(g.state().p, target);
            EXPECT_EQ(g.state().v, 0);
            EXPECT_EQ(g.state().a, 0);
            ASSERT_EQ(w.failures(), 0) << w.first();
        }
    }
    EXPECT_EQ(cases, 3000);
    RecordProperty("samples", std::to_string(samples));
}

TEST(ProfileRandom, VelocityProfiles) {
    std::mt19937 rng(42);
    std::uniform_real_distribution<double> u(0, 1);
    for (int n = 0; n < 1000; ++n) {
        SCOPED_TRACE(::testing::Message() << "case " << n);
        ProfileLimits lim;
        lim.velocity = log_uniform(rng, 0.1, 1e4);
        lim.acceleration = lim.velocity * log_uniform(rng, 1, 50);
        lim.deceleration = lim.velocity * log_uniform(rng, 1, 50);
        lim.jerk =
            u(rng) < 0.15 ? 0 : std::max(lim.acceleration, lim.deceleration) * log_uniform(rng, 2, 200);
        const double dt = u(rng) < 0.5 ? 1e-3 : 125e-6;
        ProfileGenerator g;
        g.reset(random_state(rng, lim, 0));
        const double goal = (2 * u(rng) - 1) * lim.velocity;
        ASSERT_TRUE(g.run_at(goal, lim));
        Watch w(lim, dt);
        const long steps = run_to_end(g, dt, 1000000, &w);
        ASSERT_GT(steps, 0);
        EXPECT_EQ(g.state().v, goal);
        EXPECT_EQ(g.state().a, 0);
        ASSERT_EQ(w.failures(), 0) << w.first();
        // Then a stop with other dynamics.
        const double dec = lim.deceleration * log_uniform(rng, 0.5, 2);
        g.stop(dec, lim.jerk);
        Watch ws(limits(lim.velocity, dec, dec, lim.jerk), dt);
        ASSERT_GT(run_to_end(g, dt, 1000000, &ws), 0);
        EXPECT_EQ(g.state().v, 0);
        EXPECT_EQ(g.state().p, g.target());
        ASSERT_EQ(ws.failures(), 0) << ws.first();
    }
}

}  // namespace
}  // namespace vecat::cia402
