// The motor model (mechanics.hpp) against closed forms and its own invariants, one section per loop mode
// and effect (about 870 lines: each section is small, and they share the helpers at the top).
#include <gtest/gtest.h>
#include "cia402/mechanics.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <vector>

namespace vecat::cia402 {
namespace {

constexpr double pi = std::numbers::pi;

// The default motor without friction and with an ideal (instant) current loop: pure J dw/dt = T.
MotorParameters frictionless() {
    MotorParameters m;
    m.viscous_friction = 0;
    m.coulomb_friction = 0;
    return m;
}
ControlGains ideal_current() {
    ControlGains g;
    g.current_bandwidth = 0;
    return g;
}
constexpr double kJ = 3.6e-5;  // rotor + load of the default motor

// Steps n cycles of dt.
void run(Mechanics& m, double dt, int n) {
    for (int k = 0; k < n; ++k)
        m.step(dt);
}

bool same_bits(double a, double b) {
    return std::memcmp(&a, &b, sizeof a) == 0;
}

// ---------------------------------------------------------------------------------------------------
// Mechanics: torque mode against closed forms

TEST(MechanicsTorque, ConstantTorqueOnPureInertia) {
    Mechanics m(frictionless(), ideal_current());
    const double T = 0.1;
    m.command(LoopMode::Torque, 0, 0, T);
    run(m, 1e-3, 500);  // t = 0.5 s
    const double t = 0.5;
    EXPECT_NEAR(m.velocity(), T / kJ * t, 1e-9 * T / kJ * t);                // 1388.9 rad/s
    EXPECT_NEAR(m.position(), T / (2 * kJ) * t * t, 1e-9 * T / kJ * t * t);  // 347.2 rad
    EXPECT_NEAR(m.torque(), T, 1e-15);
    EXPECT_NEAR(m.current(), T / 0.6, 1e-14);
    EXPECT_FALSE(m.torque_limited());
}

// With the first-order current loop (tau = 1/2000 s): i = T/Kt (1 - e^{-t/tau}),
// w = T/J (t - tau (1 - e^{-t/tau})), p = T/J (t^2/2 - tau t + tau^2 (1 - e^{-t/tau})).
// The substep integration is exact for this, whatever the cycle.
TEST(MechanicsTorque, CurrentLagMatchesClosedFormForEveryCycle) {
    const double T = 0.2, tau = 1.0 / 2000.0;
    for (double dt : {125e-6, 1e-3, 4e-3, 100e-6}) {
        Mechanics m(frictionless());
        m.command(LoopMode::Torque, 0, 0, T);
        for (int k = 1; k * dt <= 0.1 + 1e-12; ++k) {
            m.step(dt);
            const double t = k * dt;
            const double e = std::exp(-t / tau);
            const double w = T / kJ * (t - tau * (1 - e));
            const double p = T / kJ * (t * t / 2 - tau * t + tau * tau * (1 - e));
            ASSERT_NEAR(m.current(), T / 0.6 * (1 - e), 1e-12) << "dt " << dt << " t " << t;
            ASSERT_NEAR(m.velocity(), w, 1e-9 * (1 + std::abs(w))) << "dt " << dt << " t " << t;
            ASSERT_NEAR(m.position(), p, 1e-9 * (1 + std::abs(p))) << "dt " << dt << " t " << t;
        }
    }
}

TEST(MechanicsTorque, LimitedByTorqueLimitsAndPeakCurrent) {
    Mechanics m;
    m.command(LoopMode::Torque, 0, 0, 100.0);  // far beyond 9 A * 0.6 Nm/A = 5.4 Nm
    run(m, 1e-3, 20);
    EXPECT_TRUE(m.torque_limited());
    EXPECT_LE(m.current(), 9.0);
    EXPECT_NEAR(m.torque(), 5.4, 1e-9);  // 20 ms = 40 current time constants
    m.set_torque_limits(2.0, 1.0);
    m.command(LoopMode::Torque, 0, 0, -5.0);
    run(m, 1e-3, 20);
    EXPECT_TRUE(m.torque_limited());
    EXPECT_NEAR(m.torque(), -1.0, 1e-9);
    m.command(LoopMode::Torque, 0, 0, 0.5);
    m.step(1e-3);
    EXPECT_FALSE(m.torque_limited());
}

// ---------------------------------------------------------------------------------------------------
// Mechanics: friction

// Viscous only: w = T/B (1 - e^{-t B/J}); at t = J/B = 0.72 s, 63.2 %.
TEST(MechanicsFriction, ViscousTimeConstant) {
    MotorParameters mp = frictionless();
    mp.viscous_friction = 5e-5;
    Mechanics m(mp, ideal_current());
    const double T = 0.01, wf = T / 5e-5;  // 200 rad/s
    m.command(LoopMode::Torque, 0, 0, T);
    run(m, 1e-3, 720);
    EXPECT_NEAR(m.velocity() / wf, 1 - std::exp(-1.0), 1e-9);
    EXPECT_NEAR(m.velocity(), 126.424, 1e-3);
    // p = T/B (t - tau (1 - e^{-t/tau})), tau = 0.72 s
    EXPECT_NEAR(m.position(), wf * (0.72 - 0.72 * (1 - std::exp(-1.0))), 1e-8 * wf);
    run(m, 1e-3, 4 * 720);
    EXPECT_NEAR(m.velocity() / wf, 1 - std::exp(-5.0), 1e-9);
}

// Viscous friction with the current lag: w = T/B (1 - (c e^{-at} - a e^{-ct}) / (c - a)), a = B/J.
TEST(MechanicsFriction, ViscousWithCurrentLag) {
    MotorParameters mp = frictionless();
    mp.viscous_friction = 5e-4;  // a = 13.9 1/s
    Mechanics m(mp);
    const double T = 0.05, a = 5e-4 / kJ, c = 2000;
    m.command(LoopMode::Torque, 0, 0, T);
    for (int k = 1; k <= 200; ++k) {
        m.step(1e-3);
        const double t = k * 1e-3;
        const double w = T / 5e-4 * (1 - (c * std::exp(-a * t) - a * std::exp(-c * t)) / (c - a));
        ASSERT_NEAR(m.velocity(), w, 1e-9 * (1 + w)) << "t " << t;
    }
}

// The same with the current bandwidth equal to the mechanical pole (c = a): w = T/B (1 - e^{-at} (1 + at)).
TEST(MechanicsFriction, CurrentPoleOnTheMechanicalPole) {
    MotorParameters mp = frictionless();
    mp.viscous_friction = 0.036;  // a = 1000 1/s
    ControlGains g;
    g.current_bandwidth = 1000;
    Mechanics m(mp, g);
    const double T = 0.5, a = 1000;
    m.command(LoopMode::Torque, 0, 0, T);
    for (int k = 1; k <= 40; ++k) {
        m.step(250e-6);
        const double t = k * 250e-6;
        const double w = T / 0.036 * (1 - std::exp(-a * t) * (1 + a * t));
        const double p = T / 0.036 * (t - 2 / a + std::exp(-a * t) * (t + 2 / a));
        ASSERT_NEAR(m.velocity(), w, 1e-9 * (1 + w)) << "t " << t;
        ASSERT_NEAR(m.position(), p, 1e-9 * (1 + p)) << "t " << t;
    }
}

TEST(MechanicsFriction, TorqueBelowCoulombFrictionDoesNotCreep) {
    Mechanics m;  // Tc = 0.01 Nm, current lag, viscous friction
    m.command(LoopMode::Torque, 0, 0, 0.0099);
    for (int k = 0; k < 1000; ++k) {
        m.step(1e-3);
        ASSERT_EQ(m.position(), 0.0);
        ASSERT_EQ(m.velocity(), 0.0);
    }
    // A load torque counts: 0.014 - 0.005 = 0.009 < Tc; and the other direction.
    for (double load : {0.005, -0.005}) {
        Mechanics l;
        l.set_load_torque(load);
        l.command(LoopMode::Torque, 0, 0, 2.8 * load);
        run(l, 1e-3, 500);
        EXPECT_EQ(l.position(), 0.0);
        EXPECT_EQ(l.velocity(), 0.0);
        EXPECT_EQ(l.encoder(), 0);
    }
    // The same torques without the load break away (T - Tc = 0.004 Nm): the stiction is not a lock.
    Mechanics f;
    f.command(LoopMode::Torque, 0, 0, 0.014);
    run(f, 1e-3, 100);
    EXPECT_GT(f.velocity(), 0.0);
}

// Above Tc the axis accelerates at (T - Tc)/J, in both directions.
TEST(MechanicsFriction, TorqueAboveCoulombFrictionAccelerates) {
    MotorParameters mp = frictionless();
    mp.coulomb_friction = 0.01;
    for (double T : {0.03, -0.03}) {
        Mechanics m(mp, ideal_current());
        m.command(LoopMode::Torque, 0, 0, T);
        run(m, 1e-3, 200);
        const double acc = (T - std::copysign(0.01, T)) / kJ;  // +-555.6 rad/s^2
        EXPECT_NEAR(m.velocity(), acc * 0.2, 1e-9 * std::abs(acc));
        EXPECT_NEAR(m.position(), acc * 0.02, 1e-9 * std::abs(acc));
    }
}

// With the current lag the break-away happens inside a substep, when T (1 - e^{-c tb}) = Tc:
// tb = ln 2 / c for T = 2 Tc. Then J w = (T - Tc)(t - tb) - T/c (e^{-c tb} - e^{-c t}).
TEST(MechanicsFriction, BreakAwayInsideASubstep) {
    MotorParameters mp = frictionless();
    mp.coulomb_friction = 0.01;
    Mechanics m(mp);
    const double T = 0.02, Tc = 0.01, c = 2000, tb = std::log(2.0) / c;  // 0.347 ms: 5.5 substeps
    m.command(LoopMode::Torque, 0, 0, T);
    for (int k = 1; k <= 400; ++k) {
        m.step(125e-6);
        const double t = k * 125e-6;
        if (t <= tb) {
            ASSERT_EQ(m.velocity(), 0.0);
            continue;
        }
        const double ecb = std::exp(-c * tb), ect = std::exp(-c * t);
        const double w = ((T - Tc) * (t - tb) - T / c * (ecb - ect)) / kJ;
        const double p =
            ((T - Tc) * (t - tb) * (t - tb) / 2 - T / c * (ecb * (t - tb) + (ect - ecb) / c)) / kJ;
        ASSERT_NEAR(m.velocity(), w, 1e-9 * (1 + w)) << "t " << t;
        ASSERT_NEAR(m.position(), p, 1e-9 * (1 + p)) << "t " << t;
    }
}

// A reversal under constant torque: from w0 the axis brakes at (T + Tc)/J, stops at the exact instant
// and accelerates backwards at (T - Tc)/J.
TEST(MechanicsFriction, ReversalUnderConstantTorque) {
    MotorParameters mp = frictionless();
    mp.coulomb_friction = 0.01;
    Mechanics m(mp, ideal_current());
    m.command(LoopMode::Torque, 0, 0, 0.1);
    run(m, 1e-3, 100);
    const double w0 = 0.09 / kJ * 0.1, p0 = 0.09 / kJ * 0.01 / 2;  // 250 rad/s, 12.5 rad
    ASSERT_NEAR(m.velocity(), w0, 1e-9 * w0);
    m.command(LoopMode::Torque, 0, 0, -0.1);
    const double brake = 0.11 / kJ, back = 0.09 / kJ;
    const double ts = w0 / brake;  // 81.8 ms, inside a substep
    const double ps = p0 + w0 * ts / 2;
    for (int k = 1; k <= 200; ++k) {
        m.step(1e-3);
        const double t = k * 1e-3;
        const double w = t < ts ? w0 - brake * t : -back * (t - ts);
        const double p = t < ts ? p0 + w0 * t - brake * t * t / 2 : ps - back * (t - ts) * (t - ts) / 2;
        ASSERT_NEAR(m.velocity(), w, 1e-9 * w0) << "t " << t;
        ASSERT_NEAR(m.position(), p, 1e-9 * p0) << "t " << t;
    }
}

// Amplifier off: no current at once; friction stops the axis. With w' = -a w - f (a = B/J, f = Tc/J) the
// axis stops at ts = ln(1 + a w0 / f) / a after (w0 - f ts) / a, and stays there exactly.
TEST(MechanicsFriction, CoastsToRestWhenOff) {
    Mechanics m;
    m.command(LoopMode::Velocity, 0, 200, 0);
    run(m, 1e-3, 200);
    m.command(LoopMode::Off, 0, 0, 0);
    EXPECT_EQ(m.current(), 0.0);
    EXPECT_EQ(m.torque(), 0.0);
    const double w0 = m.velocity(), p0 = m.position();
    ASSERT_NEAR(w0, 200, 0.5);
    const double a = 5e-5 / kJ, f = 0.01 / kJ;
    const double ts = std::log(1 + a * w0 / f) / a;  // ~0.5 s
    const double dist = (w0 - f * ts) / a;           // ~44 rad
    for (int k = 1; k <= 1500; ++k) {
        m.step(1e-3);
        const double t = k * 1e-3;
        EXPECT_EQ(m.current(), 0.0);
        if (t < ts) {
            const double w = (w0 + f / a) * std::exp(-a * t) - f / a;
            ASSERT_NEAR(m.velocity(), w, 1e-9 * w0) << "t " << t;
        } else {
            ASSERT_EQ(m.velocity(), 0.0) << "t " << t;
            ASSERT_NEAR(m.position() - p0, dist, 1e-9 * dist) << "t " << t;
        }
    }
    const double rest = m.position();
    run(m, 1e-3, 500);
    EXPECT_EQ(m.position(), rest);  // no chattering, no creep
}

// ---------------------------------------------------------------------------------------------------
// Mechanics: loops

// PI velocity loop with kp = J wv, Ti = 4/wv (wv = 400 rad/s): the set-point response is
// (wv s + wv/Ti) / (s^2 + wv s + wv/Ti), a double pole at 200 rad/s and a zero at 100 rad/s; its step
// response 1 - e^{-200t} + 200 t e^{-200t} peaks at t = 10 ms with 1 + e^{-2} (13.5 % overshoot). The
// sampled loops and the current lag add a little.
TEST(MechanicsVelocityLoop, StepResponseMatchesThePiDesign) {
    Mechanics m;
    m.command(LoopMode::Velocity, 0, 100, 0);
    double peak = 0, t_peak = 0;
    for (int k = 1; k <= 300; ++k) {
        m.step(1e-3);
        if (m.velocity() > peak) {
            peak = m.velocity();
            t_peak = k * 1e-3;
        }
    }
    EXPECT_GT(peak, 110.0);
    EXPECT_LT(peak, 120.0);  // < 25 % in any case
    EXPECT_GE(t_peak, 0.007);
    EXPECT_LE(t_peak, 0.011);
    // Settled: mean over 100 ms (the encoder difference quotient leaves a ripple of a few 0.1 rad/s).
    double sum = 0;
    for (int k = 0; k < 100; ++k) {
        m.step(1e-3);
        sum += m.velocity();
        ASSERT_NEAR(m.velocity(), 100, 0.5);
    }
    EXPECT_NEAR(sum / 100, 100, 0.01);
}

// The integrator removes the steady-state error under a load; the torque then carries the load, the
// Coulomb friction and the viscous friction: 0.5 + 0.01 + 5e-5 * 100 = 0.515 Nm.
TEST(MechanicsVelocityLoop, IntegratorCarriesTheLoad) {
    Mechanics m;
    m.set_load_torque(0.5);
    m.command(LoopMode::Velocity, 0, 100, 0);
    run(m, 1e-3, 300);
    double w = 0, t = 0;
    for (int k = 0; k < 100; ++k) {
        m.step(1e-3);
        w += m.velocity() / 100;
        t += m.torque() / 100;
    }
    EXPECT_NEAR(w, 100, 0.01);
    EXPECT_NEAR(t, 0.515, 0.002);
    // The same set-point backwards: the load now helps.
    m.command(LoopMode::Velocity, 0, -100, 0);
    run(m, 1e-3, 300);
    w = t = 0;
    for (int k = 0; k < 100; ++k) {
        m.step(1e-3);
        w += m.velocity() / 100;
        t += m.torque() / 100;
    }
    EXPECT_NEAR(w, -100, 0.01);
    EXPECT_NEAR(t, 0.5 - 0.01 - 5e-5 * 100, 0.002);
}

TEST(MechanicsVelocityLoop, TorqueNeverExceedsTheLimits) {
    Mechanics m;
    m.set_torque_limits(1.0, 0.5);
    m.command(LoopMode::Velocity, 0, 300, 0);
    int limited = 0;
    double peak = 0;
    for (int k = 1; k <= 200; ++k) {
        m.step(1e-3);
        ASSERT_LE(m.torque(), 1.0 + 1e-12);
        ASSERT_GE(m.torque(), -0.5 - 1e-12);
        peak = std::max(peak, m.velocity());
        // Accelerating at about (1 - 0.01) / J = 27500 rad/s^2: at the limit for ~11 ms; the torque
        // follows the clamped command through the current lag: 1 - e^{-2000 t}.
        if (k <= 9) {
            EXPECT_TRUE(m.torque_limited()) << k;
            EXPECT_NEAR(m.torque(), 1.0 - std::exp(-2.0 * k), 1e-9) << k;
        }
        limited += m.torque_limited();
    }
    EXPECT_GE(limited, 9);
    EXPECT_LE(limited, 14);
    EXPECT_FALSE(m.torque_limited());
    EXPECT_NEAR(m.velocity(), 300, 1);
    // Anti-windup: the saturated phase does not add to the overshoot of the linear response.
    EXPECT_LT(peak, 300 * 1.2);
    m.command(LoopMode::Velocity, 0, -300, 0);
    for (int k = 1; k <= 40; ++k) {
        m.step(1e-3);
        ASSERT_GE(m.torque(), -0.5 - 1e-12);
        if (k <= 30) {
            EXPECT_TRUE(m.torque_limited()) << k;  // 600 rad/s at ~13600 rad/s^2: 44 ms
        }
    }
}

// Position loop kp = 100 1/s behind a velocity loop of 400 rad/s: nearly first order with tau = 10 ms
// (2 % after ~40 ms), no significant overshoot; it comes to rest within an encoder increment or two.
TEST(MechanicsPositionLoop, StepSettles) {
    Mechanics m;
    const double inc = 2 * pi / (1 << 20);
    m.command(LoopMode::Position, 1.0, 0, 0);
    double peak = 0, settled = -1;
    for (int k = 1; k <= 300; ++k) {
        m.step(1e-3);
        peak = std::max(peak, m.position());
        if (settled < 0 && std::abs(m.position() - 1.0) < 0.02) settled = k * 1e-3;
        if (settled >= 0) {
            ASSERT_LT(std::abs(m.position() - 1.0), 0.02) << k;
        }
    }
    EXPECT_GT(settled, 0.035);
    EXPECT_LT(settled, 0.06);
    EXPECT_LT(peak, 1.01);
    EXPECT_NEAR(m.position(), 1.0, 2 * inc);
    EXPECT_NEAR(m.velocity(), 0.0, 0.2);
}

// A step far beyond the torque limit (20 rad): saturated acceleration, then it settles without a large
// overshoot (anti-windup).
TEST(MechanicsPositionLoop, LargeStepSaturatesAndSettles) {
    Mechanics m;
    m.command(LoopMode::Position, 20.0, 0, 0);
    m.step(1e-3);
    EXPECT_TRUE(m.torque_limited());
    EXPECT_NEAR(m.torque(), 5.4 * (1 - std::exp(-2.0)), 1e-9);  // rising to 9 A through the lag
    double peak = 0;
    for (int k = 0; k < 999; ++k) {
        m.step(1e-3);
        peak = std::max(peak, m.position());
    }
    EXPECT_LT(peak, 20.0 * 1.01);
    EXPECT_NEAR(m.position(), 20.0, 1e-4);
}

// Ramp p* = v t, held for each cycle, with velocity feed-forward v. The axis runs at v while the held
// set-point is a staircase, so the following error is a sawtooth of +-v dt/2; the loops sample it at the
// start of each substep, which shifts it by v h/2 (h = 62.5 us). Bound v (dt + h)/2 plus a few increments.
TEST(MechanicsPositionLoop, RampFollowingErrorWithVelocityFeedForward) {
    Mechanics m;
    const double v = 10, dt = 1e-3, h = 62.5e-6, inc = 2 * pi / (1 << 20);
    const double bound = v * (dt + h) / 2 + 4 * inc;
    double worst = 0, worst_late = 0;
    for (int k = 0; k < 1000; ++k) {
        const double p = v * k * dt;
        m.command(LoopMode::Position, p, v, 0);
        const double before = std::abs(p - m.position());
        m.step(dt);
        const double after = std::abs(p - m.position());
        worst = std::max({worst, before, after});
        if (k >= 300) worst_late = std::max({worst_late, before, after});
    }
    EXPECT_LT(worst_late, bound);
    EXPECT_GT(worst_late, v * dt / 2);  // the sawtooth is really there
    // Start from rest: lag of the PI loop to a velocity step v, at most v / (200 e) (see the velocity test).
    EXPECT_LT(worst, v / (200 * std::exp(1.0)) + bound);
    EXPECT_NEAR(m.velocity(), v, 0.5);
}

TEST(MechanicsPositionLoop, DefaultGainsAreTheTunedGains) {
    const ControlGains d;
    const ControlGains t = Mechanics::tuned_for(MotorParameters{});
    EXPECT_NEAR(t.velocity_kp, d.velocity_kp, 1e-12);
    EXPECT_NEAR(t.velocity_ti, d.velocity_ti, 1e-12);
    EXPECT_NEAR(t.position_kp, d.position_kp, 1e-9);
    EXPECT_EQ(t.current_bandwidth, d.current_bandwidth);
    MotorParameters heavy;
    heavy.load_inertia = 1.2e-4;  // J = 1.32e-4
    const ControlGains th = Mechanics::tuned_for(heavy, 300);
    EXPECT_NEAR(th.velocity_kp, 1.32e-4 * 300, 1e-12);
    EXPECT_NEAR(th.velocity_ti, 4.0 / 300, 1e-12);
    EXPECT_NEAR(th.position_kp, 75.0, 1e-12);
    // The tuned loops behave the same on the heavier axis: same overshoot of a velocity step.
    Mechanics m(heavy, th);
    m.command(LoopMode::Velocity, 0, 100, 0);
    double peak = 0;
    for (int k = 0; k < 300; ++k) {
        m.step(1e-3);
        peak = std::max(peak, m.velocity());
    }
    EXPECT_GT(peak, 110.0);
    EXPECT_LT(peak, 120.0);
}

// Amplifier off with a load above the friction (an unbraked vertical axis): it falls at (TL - Tc)/J.
TEST(MechanicsFriction, OffWithALoadAboveFrictionFalls) {
    MotorParameters mp = frictionless();
    mp.coulomb_friction = 0.01;
    Mechanics f(mp);
    f.set_load_torque(0.05);
    f.command(LoopMode::Off, 0, 0, 0);
    run(f, 1e-3, 100);
    EXPECT_NEAR(f.velocity(), -0.04 / kJ * 0.1, 1e-9 * 0.04 / kJ);
    EXPECT_NEAR(f.position(), -0.04 / kJ * 0.01 / 2, 1e-9 * 0.04 / kJ);
}

// Each mode uses only its own set-points.
TEST(MechanicsVelocityLoop, ModesBypassTheOuterLoops) {
    Mechanics v;
    v.command(LoopMode::Velocity, 1000.0, 0.0, 0.0);  // the position is not a set-point here
    run(v, 1e-3, 100);
    EXPECT_EQ(v.position(), 0.0);
    EXPECT_EQ(v.torque(), 0.0);
    Mechanics t(frictionless(), ideal_current());
    t.command(LoopMode::Torque, 1000.0, 500.0, 0.036);  // only the torque counts: 1000 rad/s^2
    run(t, 1e-3, 100);
    EXPECT_NEAR(t.velocity(), 100.0, 1e-9);
    // Leaving velocity mode clears the integrator: with a load of 0.5 Nm it holds ~0.515 Nm; after a
    // spell in torque mode (holding the speed with 0.515 Nm) the velocity loop restarts from P alone.
    Mechanics r(MotorParameters{}, ideal_current());
    r.set_load_torque(0.5);
    r.command(LoopMode::Velocity, 0, 100.0, 0);
    run(r, 1e-3, 300);
    ASSERT_NEAR(r.torque(), 0.515, 0.01);
    r.command(LoopMode::Torque, 0, 0, 0.515);
    run(r, 1e-3, 10);
    ASSERT_NEAR(r.velocity(), 100.0, 0.1);
    r.command(LoopMode::Velocity, 0, 100.0, 0);
    r.step(62.5e-6);
    EXPECT_LT(std::abs(r.torque()), 0.01);  // kp * (velocity error within 0.5 rad/s)
    run(r, 1e-3, 300);
    EXPECT_NEAR(r.torque(), 0.515, 0.01);  // rebuilt
}

TEST(MechanicsVelocityLoop, GainsApplyAtOnce) {
    Mechanics m(frictionless());
    ControlGains g = m.gains();
    g.current_bandwidth = 500;  // tau = 2 ms
    m.set_gains(g);
    EXPECT_EQ(m.gains().current_bandwidth, 500);
    m.command(LoopMode::Torque, 0, 0, 0.6);  // 1 A
    run(m, 1e-3, 2);
    EXPECT_NEAR(m.current(), 1 - std::exp(-1.0), 1e-12);
}

// ---------------------------------------------------------------------------------------------------
// Mechanics: encoder

TEST(MechanicsEncoder, QuantisesWithFloorMultiTurn) {
    MotorParameters mp;
    mp.encoder_bits = 17;
    Mechanics m(mp);
    const double inc = 2 * pi / 131072;
    // The middle of increment n reads n, negative increments included.
    for (std::int64_t n : {0LL, 1LL, 65535LL, 131071LL, 131072LL, 1000000LL, 10000000000LL, -1LL, -2LL,
                           -131072LL, -131073LL, -1000001LL}) {
        m.set_position((static_cast<double>(n) + 0.5) * inc);
        EXPECT_EQ(m.encoder(), n) << n;
    }
    m.set_position(pi);
    EXPECT_EQ(m.encoder(), 65536);  // half a turn (pi / 2pi is exactly 0.5 in binary)
    m.set_position(-1e-9);
    EXPECT_EQ(m.encoder(), -1);
    m.set_position(1e-9);
    EXPECT_EQ(m.encoder(), 0);
    m.set_position(-3 * 2 * pi - 0.25 * inc);
    EXPECT_EQ(m.encoder(), -3 * 131072 - 1);
    // The default 20-bit encoder.
    Mechanics d;
    d.set_position(2 * pi * 2.5 + 0.5 * 2 * pi / (1 << 20));
    EXPECT_EQ(d.encoder(), 5 * (1 << 19));
}

TEST(MechanicsEncoder, FaultFreezesTheValue) {
    Mechanics m;
    m.command(LoopMode::Torque, 0, 0, 0.1);
    run(m, 1e-3, 10);
    EXPECT_TRUE(m.encoder_ok());
    const std::int64_t frozen = m.encoder();
    m.inject_encoder_fault(true);
    EXPECT_FALSE(m.encoder_ok());
    run(m, 1e-3, 10);
    EXPECT_EQ(m.encoder(), frozen);
    EXPECT_GT(m.position(), static_cast<double>(frozen + 1000) * 2 * pi / (1 << 20));
    m.inject_encoder_fault(false);
    EXPECT_TRUE(m.encoder_ok());
    EXPECT_EQ(m.encoder(), static_cast<std::int64_t>(std::floor(m.position() / (2 * pi) * (1 << 20))));
}

// The loops see only the encoder: with it frozen the velocity loop believes the axis stands and drives it
// into the torque limit (what the drive must catch by disabling the loops on the fault).
TEST(MechanicsEncoder, LoopsLoseTheAxisOnAFault) {
    Mechanics m;
    m.command(LoopMode::Velocity, 0, 10, 0);
    run(m, 1e-3, 200);
    ASSERT_NEAR(m.velocity(), 10, 0.5);
    m.inject_encoder_fault(true);
    // Error 10 rad/s: P 0.144 Nm, the integrator adds 14.4 Nm/s, so it passes 5.4 Nm after ~0.36 s.
    run(m, 1e-3, 300);
    EXPECT_FALSE(m.torque_limited());
    run(m, 1e-3, 100);
    EXPECT_TRUE(m.torque_limited());
    EXPECT_GT(m.velocity(), 1000);
}

// ---------------------------------------------------------------------------------------------------
// Mechanics: over-current

TEST(MechanicsOvercurrent, Injection) {
    Mechanics m;
    EXPECT_FALSE(m.overcurrent());
    m.inject_overcurrent(true);
    EXPECT_TRUE(m.overcurrent());
    m.step(1e-3);
    EXPECT_TRUE(m.overcurrent());
    m.inject_overcurrent(false);
    EXPECT_FALSE(m.overcurrent());
    m.inject_overcurrent(true);
    m.reset();
    EXPECT_FALSE(m.overcurrent());
}

// I2t: d/dt i2t = (i^2 - Ir^2) / ((Ip^2 - Ir^2) tp), never below 0. The axis is held by an equal load
// torque. With the current lag i = I (1 - e^{-cs}) the integral starts when i passes Ir, at t3, and
// int_t3^t i^2 = I^2 (t - t3 - 2 (e^{-c t3} - e^{-ct}) / c + (e^{-2c t3} - e^{-2ct}) / (2c)).
double i2t_closed_form(double I, double t) {
    const double c = 2000, e3 = 1 - 3.0 / I, t3 = -std::log(e3) / c, et = std::exp(-c * t);
    const double sq = I * I * (t - t3 - 2 * (e3 - et) / c + (e3 * e3 - et * et) / (2 * c));
    return (sq - 9 * (t - t3)) / 72;
}

TEST(MechanicsOvercurrent, I2tTripsAfterPeakTimeAtPeakCurrent) {
    Mechanics m;
    m.set_load_torque(5.4);
    m.command(LoopMode::Torque, 0, 0, 5.4);  // 9 A
    for (int k = 1; k <= 500; ++k) {
        m.step(1e-3);
        // Trapezoid over each substep, clamped at 0 where the current passes Ir: within 1e-6.
        ASSERT_NEAR(m.i2t(), i2t_closed_form(9, k * 1e-3), 1e-6) << k;
    }
    EXPECT_EQ(m.velocity(), 0.0);
    EXPECT_FALSE(m.overcurrent());
    run(m, 1e-3, 500);  // t_trip = 1.00083 s
    EXPECT_FALSE(m.overcurrent());
    run(m, 1e-3, 1);
    EXPECT_TRUE(m.overcurrent());
    // Cooling without current: -Ir^2 / 72 = -0.125 per second.
    m.command(LoopMode::Off, 0, 0, 0);
    m.set_load_torque(0);
    const double before = m.i2t();
    run(m, 1e-3, 400);
    EXPECT_NEAR(m.i2t(), before - 0.05, 1e-9);
    EXPECT_FALSE(m.overcurrent());
}

TEST(MechanicsOvercurrent, I2tAtTwiceAndAtRatedCurrent) {
    Mechanics m;
    m.set_load_torque(3.6);
    m.command(LoopMode::Torque, 0, 0, 3.6);  // 6 A: trips at 2.66766 s
    ASSERT_LT(i2t_closed_form(6, 2.667), 1.0);
    ASSERT_GT(i2t_closed_form(6, 2.668), 1.0);
    run(m, 1e-3, 2667);
    EXPECT_FALSE(m.overcurrent());
    run(m, 1e-3, 1);
    EXPECT_TRUE(m.overcurrent());

    Mechanics r;
    r.set_load_torque(1.8);
    r.command(LoopMode::Torque, 0, 0, 1.8);  // the rated 3 A, approached from below
    run(r, 1e-3, 10000);
    EXPECT_EQ(r.i2t(), 0.0);
    EXPECT_FALSE(r.overcurrent());
}

// ---------------------------------------------------------------------------------------------------
// Mechanics: determinism

struct Snapshot {
    double p, w, i, t;
    std::int64_t enc;
};
Snapshot snap(const Mechanics& m) {
    return {m.position(), m.velocity(), m.current(), m.torque(), m.encoder()};
}
void expect_identical(const Snapshot& a, const Snapshot& b) {
    EXPECT_TRUE(same_bits(a.p, b.p)) << a.p << " " << b.p;
    EXPECT_TRUE(same_bits(a.w, b.w)) << a.w << " " << b.w;
    EXPECT_TRUE(same_bits(a.i, b.i)) << a.i << " " << b.i;
    EXPECT_TRUE(same_bits(a.t, b.t));
    EXPECT_EQ(a.enc, b.enc);
}

// A sequence of every mode, load and limit change.
void scenario(Mechanics& m, double dt, std::vector<Snapshot>* trace) {
    const int n = static_cast<int>(std::lround(0.4 / dt));
    for (int k = 0; k < n; ++k) {
        const double t = k * dt;
        if (t < 0.1)
            m.command(LoopMode::Position, 3.0 * t * t, 6.0 * t, 0.0);
        else if (t < 0.2)
            m.command(LoopMode::Velocity, 0, -20.0, 0.01);
        else if (t < 0.25)
            m.command(LoopMode::Torque, 0, 0, 0.3);
        else if (t < 0.3)
            m.command(LoopMode::Off, 0, 0, 0);
        else
            m.command(LoopMode::Position, 0.5, 0, 0);
        m.set_load_torque(t > 0.15 ? 0.02 : 0.0);
        m.set_torque_limits(t > 0.33 ? 0.2 : 3.0, 3.0);
        m.step(dt);
        if (trace) trace->push_back(snap(m));
    }
}

TEST(MechanicsDeterminism, TwoInstancesAreBitIdentical) {
    for (double dt : {125e-6, 1e-3, 100e-6}) {
        Mechanics a, b;
        std::vector<Snapshot> ta, tb;
        scenario(a, dt, &ta);
        scenario(b, dt, &tb);
        ASSERT_EQ(ta.size(), tb.size());
        for (std::size_t k = 0; k < ta.size(); ++k)
            expect_identical(ta[k], tb[k]);
        EXPECT_TRUE(same_bits(a.i2t(), b.i2t()));
    }
}

// What an instance did before (another cycle time, faults, a reset) does not leak into the next run.
TEST(MechanicsDeterminism, HistoryDoesNotLeak) {
    Mechanics a, b;
    b.command(LoopMode::Velocity, 0, 50, 0);
    run(b, 250e-6, 37);
    b.inject_encoder_fault(true);
    b.inject_overcurrent(true);
    b.step(3e-3);
    b.reset();
    std::vector<Snapshot> ta, tb;
    scenario(a, 1e-3, &ta);
    scenario(b, 1e-3, &tb);
    for (std::size_t k = 0; k < ta.size(); ++k)
        expect_identical(ta[k], tb[k]);
}

// The loops run at 62.5 us for all these cycles: with a constant command the state after the same time
// is the same bits, however the time was cut into cycles.
TEST(MechanicsDeterminism, SameSubstepSameResultForAnyCycle) {
    EXPECT_EQ(Mechanics::substeps(62.5e-6), 1u);
    EXPECT_EQ(Mechanics::substeps(125e-6), 2u);
    EXPECT_EQ(Mechanics::substeps(100e-6), 2u);
    EXPECT_EQ(Mechanics::substeps(1e-3), 16u);
    EXPECT_EQ(Mechanics::substeps(4e-3), 64u);
    EXPECT_EQ(Mechanics::substeps(0.0), 1u);
    std::vector<Snapshot> results;
    for (double dt : {125e-6, 250e-6, 1e-3, 4e-3}) {
        Mechanics m;
        m.set_load_torque(0.1);
        m.command(LoopMode::Position, 2.0, 0, 0);
        run(m, dt, static_cast<int>(std::lround(0.2 / dt)));
        results.push_back(snap(m));
    }
    for (std::size_t k = 1; k < results.size(); ++k)
        expect_identical(results[0], results[k]);
    EXPECT_NEAR(results[0].p, 2.0, 1e-3);
}

TEST(MechanicsDeterminism, SetPositionAndReset) {
    Mechanics m;
    m.set_position(-7.25);
    EXPECT_EQ(m.position(), -7.25);
    EXPECT_EQ(m.encoder(), static_cast<std::int64_t>(std::floor(-7.25 / (2 * pi) * (1 << 20))));
    // Holding there in position mode: no jump from a stale velocity estimate.
    m.command(LoopMode::Position, -7.25, 0, 0);
    run(m, 1e-3, 100);
    EXPECT_NEAR(m.position(), -7.25, 1e-4);
    m.reset();
    EXPECT_EQ(m.position(), 0.0);
    EXPECT_EQ(m.velocity(), 0.0);
    EXPECT_EQ(m.current(), 0.0);
    EXPECT_EQ(m.mode(), LoopMode::Off);
    run(m, 1e-3, 10);
    EXPECT_EQ(m.position(), 0.0);
}

// ---------------------------------------------------------------------------------------------------
// Mechanics: the power stage off with the motor at rest (a drive the master is bringing up). Its substeps
// are skipped (Mechanics::step): they must leave everything as computing them would.

TEST(MechanicsUnpowered, AMotorAtRestStaysBitForBit) {
    Mechanics m;
    m.set_position(1.25);
    m.set_load_torque(0.005);  // within the Coulomb friction of the default motor (0.01 Nm)
    run(m, 250e-6, 10);
    const double p = m.position(), w = m.velocity(), i = m.current(), h = m.i2t();
    const std::int64_t count = m.encoder();
    run(m, 250e-6, 4000);
    EXPECT_TRUE(same_bits(m.position(), p));
    EXPECT_TRUE(same_bits(m.velocity(), w));
    EXPECT_TRUE(same_bits(m.current(), i));
    EXPECT_TRUE(same_bits(m.i2t(), h));
    EXPECT_EQ(m.encoder(), count);
    EXPECT_EQ(w, 0.0);
}

TEST(MechanicsUnpowered, ALoadBeyondTheFrictionTurnsTheMotorAtRest) {
    Mechanics m;
    run(m, 250e-6, 10);  // at rest, unpowered: the substeps are skipped from here on
    ASSERT_EQ(m.velocity(), 0.0);
    m.set_load_torque(0.5);  // a hanging load, far beyond the friction
    run(m, 250e-6, 40);
    EXPECT_LT(m.velocity(), -1.0);  // the load drives it backwards
}

TEST(MechanicsUnpowered, AMotorSwitchedOffWhileTurningCoastsToRestAndStaysThere) {
    Mechanics m;
    m.command(LoopMode::Velocity, 0, 100, 0);
    run(m, 250e-6, 400);
    ASSERT_GT(m.velocity(), 50.0);
    m.command(LoopMode::Off, 0, 0, 0);
    run(m, 250e-6, 4000);  // friction stops it within a second
    EXPECT_EQ(m.velocity(), 0.0);
    EXPECT_EQ(m.current(), 0.0);
    const double p = m.position();
    run(m, 250e-6, 400);
    EXPECT_TRUE(same_bits(m.position(), p));
    // And a command powers it again.
    m.command(LoopMode::Velocity, 0, 50, 0);
    run(m, 250e-6, 400);
    EXPECT_NEAR(m.velocity(), 50.0, 1.0);
}

// ---------------------------------------------------------------------------------------------------
// Mechanics: a substep that leaves every member as it found it is a fixed point; step() skips the ones
// after it until an input changes. A twin that computes every substep (steps of one substep each, before
// each of which set_gains with its own gains makes it compute) must show the same bits at every step,
// through holds, a load within and then beyond the friction, a torque limit, every mode and an encoder
// fault.

void fixed_point_scenario(Mechanics& m, bool compute_all, std::vector<Snapshot>& trace) {
    const double dt = 250e-6;
    const auto steps = [&](int n) {
        for (int k = 0; k < n; ++k) {
            if (compute_all) {
                // One substep per step, each computed (Mechanics::substeps: a step of 250 us is four of them,
                // which give the same bits as four steps of 62.5 us).
                for (int s = 0; s < 4; ++s) {
                    m.set_gains(m.gains());
                    m.step(dt / 4);
                }
            } else {
                m.step(dt);
            }
            trace.push_back(snap(m));
        }
    };
    m.command(LoopMode::Position, 0.0, 0, 0);  // held where it is
    steps(400);
    m.command(LoopMode::Position, 0.5, 0, 0);  // a move; near the target the integrator still creeps
    steps(1000);
    // Held where its encoder stands (as a drive told to hold its actual position is): no error left.
    m.command(LoopMode::Position, static_cast<double>(m.encoder()) * std::ldexp(2 * pi, -20), 0, 0);
    steps(2000);
    m.set_load_torque(0.006);  // within the Coulomb friction (0.01 Nm): still held
    steps(400);
    m.set_load_torque(0.4);  // far beyond: the loop must carry it
    steps(800);
    m.set_torque_limits(0.05, 0.05);  // too weak to hold it
    steps(400);
    m.set_torque_limits(3.0, 3.0);
    m.command(LoopMode::Velocity, 0, 0, 0);
    steps(400);
    m.set_load_torque(0.0);
    m.command(LoopMode::Torque, 0, 0, 0.005);  // below the friction
    steps(400);
    m.command(LoopMode::Off, 0, 0, 0);
    steps(400);
    m.command(LoopMode::Position, m.position(), 0, 0);
    steps(400);
    m.inject_encoder_fault(true);
    m.set_load_torque(0.02);
    steps(200);
    m.inject_encoder_fault(false);
    steps(400);
}

TEST(MechanicsFixedPoint, SkippedSubstepsLeaveTheSameBitsAsComputedOnes) {
    Mechanics skipping, computing;
    std::vector<Snapshot> ts, tc;
    fixed_point_scenario(skipping, false, ts);
    fixed_point_scenario(computing, true, tc);
    ASSERT_EQ(ts.size(), tc.size());
    for (std::size_t k = 0; k < ts.size(); ++k) {
        SCOPED_TRACE(k);
        expect_identical(ts[k], tc[k]);
        if (::testing::Test::HasFailure()) break;
    }
    EXPECT_TRUE(same_bits(skipping.i2t(), computing.i2t()));
    // The scenario's holds without an error left: their substeps were skipped.
    EXPECT_LT(skipping.substeps_run() * 3, computing.substeps_run() * 2)
        << skipping.substeps_run() << " of " << computing.substeps_run();
}

// A held motor that a load beyond the friction then pulls: the skipping stops at once.
TEST(MechanicsFixedPoint, AChangedInputEndsTheSkipping) {
    Mechanics m;
    m.command(LoopMode::Position, 0.0, 0, 0);
    run(m, 250e-6, 100);
    const std::uint64_t held = m.substeps_run();
    run(m, 250e-6, 100);
    EXPECT_EQ(m.substeps_run(), held);  // a fixed point: nothing computed
    EXPECT_EQ(m.velocity(), 0.0);
    m.set_load_torque(0.5);
    run(m, 250e-6, 1);
    EXPECT_GT(m.substeps_run(), held);
    EXPECT_NE(m.velocity(), 0.0);
}

}  // namespace
}  // namespace vecat::cia402
