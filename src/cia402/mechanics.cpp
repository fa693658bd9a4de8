#include "cia402/mechanics.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>

namespace vecat::cia402 {

namespace {

constexpr double two_pi = 2.0 * std::numbers::pi;

// For x >= 0 (g1: any x), given m = expm1(-x), with series where the closed forms cancel:
// g1(x) = (1 - exp(-x)) / x, g2(x) = (x - 1 + exp(-x)) / x^2, h2(x) = (1 - exp(-x) (1 + x)) / x^2.
double g1(double x, double m) {
    if (std::abs(x) < 1e-5) return 1.0 - x * (0.5 - x / 6.0);
    return -m / x;
}
double g2(double x, double m) {
    if (x < 1e-2) return 0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0 - x / 720.0)));
    return (x + m) / (x * x);
}
double h2(double x, double m) {
    if (x < 1e-2) return 0.5 - x * (1.0 / 3.0 - x * (1.0 / 8.0 - x * (1.0 / 30.0 - x / 144.0)));
    return (-m - x * (1.0 + m)) / (x * x);
}

double sign(double v) {
    return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0);
}

// The same bits (0.0 and -0.0 differ, a NaN equals itself).
bool same(double a, double b) {
    return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

}  // namespace

Mechanics::Mechanics(const MotorParameters& m, const ControlGains& g) : motor_(m), gains_(g) {
    limit_pos_ = std::numeric_limits<double>::infinity();
    limit_neg_ = std::numeric_limits<double>::infinity();
    derive();
}

ControlGains Mechanics::tuned_for(const MotorParameters& m, double velocity_bandwidth) {
    ControlGains g;
    const double wv = velocity_bandwidth;
    g.velocity_kp = (m.rotor_inertia + m.load_inertia) * wv;
    g.velocity_ti = 4.0 / wv;
    g.position_kp = wv / 4.0;
    g.current_bandwidth = 2000.0;
    return g;
}

unsigned Mechanics::substeps(double dt) {
    if (!(dt > 0.0)) return 1;
    // The small relative margin keeps exact multiples (1 ms / 62.5 us) from rounding up to one more.
    const double n = std::ceil(dt / max_substep * (1.0 - 1e-12));
    return static_cast<unsigned>(std::clamp(n, 1.0, 1e9));
}

void Mechanics::derive() {
    inertia_ = motor_.rotor_inertia + motor_.load_inertia;
    a_ = std::max(motor_.viscous_friction, 0.0) / inertia_;
    c_ = gains_.current_bandwidth > 0.0 ? gains_.current_bandwidth : 0.0;
    peak_torque_ = std::abs(motor_.peak_current * motor_.torque_constant);
    rad_per_count_ = std::ldexp(two_pi, -static_cast<int>(motor_.encoder_bits));
    // 2^bits, by which a multiplication is as exact as ldexp (0: too many bits, ldexp is used).
    counts_per_turn_ =
        motor_.encoder_bits <= 62 ? std::ldexp(1.0, static_cast<int>(motor_.encoder_bits)) : 0.0;
    cached_dt_ = -1.0;
}

void Mechanics::set_gains(const ControlGains& g) {
    if (!same(g.position_kp, gains_.position_kp) || !same(g.velocity_kp, gains_.velocity_kp) ||
        !same(g.velocity_ti, gains_.velocity_ti) || !same(g.current_bandwidth, gains_.current_bandwidth))
        fixed_ = false;
    gains_ = g;
    derive();
}

void Mechanics::command(LoopMode mode, double position, double velocity_ff, double torque_ff) {
    if (mode != mode_ || !same(position, position_cmd_) || !same(velocity_ff, velocity_ff_) ||
        !same(torque_ff, torque_ff_))
        fixed_ = false;
    const double i0 = x_.i, cmd0 = current_cmd_, integral0 = integral_;
    const bool limited0 = limited_;
    mode_ = mode;
    position_cmd_ = position;
    velocity_ff_ = velocity_ff;
    torque_ff_ = torque_ff;
    if (mode != LoopMode::Position && mode != LoopMode::Velocity) integral_ = 0.0;
    if (mode == LoopMode::Off) {
        current_cmd_ = 0.0;
        x_.i = 0.0;
        limited_ = false;
    }
    if (!same(i0, x_.i) || !same(cmd0, current_cmd_) || !same(integral0, integral_) || limited0 != limited_)
        fixed_ = false;
}

void Mechanics::set_torque_limits(double positive, double negative) {
    const double pos0 = limit_pos_, neg0 = limit_neg_;
    if (!std::isnan(positive)) limit_pos_ = std::abs(positive);
    if (!std::isnan(negative)) limit_neg_ = std::abs(negative);
    if (!same(pos0, limit_pos_) || !same(neg0, limit_neg_)) fixed_ = false;
}

void Mechanics::set_load_torque(double nm) {
    if (!same(nm, load_)) fixed_ = false;
    load_ = nm;
}

double Mechanics::position() const {
    return x_.p;
}
double Mechanics::velocity() const {
    return x_.w;
}
double Mechanics::current() const {
    return x_.i;
}
double Mechanics::torque() const {
    return motor_.torque_constant * x_.i;
}
bool Mechanics::torque_limited() const {
    return limited_;
}

std::int64_t Mechanics::count_of(double p) const {
    // floor(p / 2 pi * 2^bits); the scaling by 2^bits is exact. Saturates instead of overflowing.
    const double x = p / two_pi;
    const double v =
        counts_per_turn_ > 0 ? x * counts_per_turn_ : std::ldexp(x, static_cast<int>(motor_.encoder_bits));
    if (std::isnan(v)) return 0;
    if (v >= 9.2e18) return std::numeric_limits<std::int64_t>::max();
    if (v <= -9.2e18) return std::numeric_limits<std::int64_t>::min();
    // floor(v): the conversion truncates (exactly, in this range), one less below a negative fraction.
    const auto t = static_cast<std::int64_t>(v);
    return static_cast<double>(t) > v ? t - 1 : t;
}

std::int64_t Mechanics::encoder() const {
    return encoder_fault_ ? frozen_count_ : count_of(x_.p);
}

void Mechanics::set_position(double rad) {
    x_.p = rad;
    last_count_ = encoder();
    fixed_ = false;
}

void Mechanics::reset() {
    fixed_ = false;
    x_ = {0.0, 0.0, 0.0};
    mode_ = LoopMode::Off;
    position_cmd_ = velocity_ff_ = torque_ff_ = 0.0;
    current_cmd_ = integral_ = 0.0;
    limited_ = false;
    encoder_fault_ = false;
    overcurrent_injected_ = false;
    i2t_ = 0.0;
    last_count_ = count_of(0.0);
    last_h_ = 0.0;
}

void Mechanics::inject_encoder_fault(bool on) {
    if (on != encoder_fault_) fixed_ = false;
    if (on && !encoder_fault_) frozen_count_ = count_of(x_.p);
    if (!on && encoder_fault_) last_count_ = count_of(x_.p);  // no velocity spike when it comes back
    encoder_fault_ = on;
}

void Mechanics::inject_overcurrent(bool on) {  // (no part of a substep: overcurrent() reads it)
    overcurrent_injected_ = on;
}

bool Mechanics::overcurrent() const {
    return overcurrent_injected_ || i2t_ >= 1.0;
}

Mechanics::Span Mechanics::span(double tau) const {
    Span s{};
    const double xa = a_ * tau;
    const double ma = std::expm1(-xa);
    s.ea = 1.0 + ma;
    s.p1 = tau * g1(xa, ma);
    s.p2 = tau * tau * g2(xa, ma);
    if (c_ > 0.0) {
        const double xc = c_ * tau;
        const double mc = std::expm1(-xc);
        s.ec = 1.0 + mc;
        // r1 = exp(-a tau) int_0^tau exp(-(c - a) s) ds; r2 = (p1(a) - p1(c)) / (c - a), which for c close
        // to a is replaced by its value at the mean rate (error of order ((c - a) tau)^2 < 1e-6).
        const double xd = xc - xa;
        s.r1 = s.ea * tau * g1(xd, std::expm1(-xd));
        if (std::abs(xd) >= 1e-3) {
            s.r2 = tau * tau * (g1(xa, ma) - g1(xc, mc)) / xd;
        } else {
            const double xm = 0.5 * (xa + xc);
            s.r2 = tau * tau * h2(xm, std::expm1(-xm));
        }
    }
    return s;
}

// Motion with the friction of direction dir over the span, the current moving from i0 to its command
// through the first-order lag: i(s) = i* + (i0 - i*) exp(-c s). Exact.
Mechanics::State Mechanics::moving(const State& x, const Span& k, double dir) const {
    const double kt = motor_.torque_constant;
    const double di = x.i - current_cmd_;
    const double A = (kt * current_cmd_ - load_ - motor_.coulomb_friction * dir) / inertia_;
    const double D = kt * di / inertia_;
    return {x.p + x.w * k.p1 + A * k.p2 + D * k.r2, x.w * k.ea + A * k.p1 + D * k.r1,
            current_cmd_ + di * k.ec};
}

Mechanics::State Mechanics::stuck(const State& x, const Span& k) const {
    return {x.p, 0.0, current_cmd_ + (x.i - current_cmd_) * k.ec};
}

// First time in (0, left] at which the velocity of a motion in direction dir reaches zero, knowing that it
// has at left. Newton on w(t) (its derivative is the equation of motion), kept inside a bisection bracket.
double Mechanics::crossing_time(const State& x, double dir, double left) const {
    const double kt = motor_.torque_constant;
    double lo = 0.0, hi = left;
    const double f0 = dir * x.w;
    const double fl = dir * moving(x, span(left), dir).w;
    double t = f0 > 0.0 && f0 - fl > 0.0 ? left * f0 / (f0 - fl) : 0.5 * left;
    for (int it = 0; it < 60; ++it) {
        const State s = moving(x, span(t), dir);
        const double f = dir * s.w;
        const double fp = dir * (-a_ * s.w + (kt * s.i - load_ - motor_.coulomb_friction * dir) / inertia_);
        if (f > 0.0)
            lo = t;
        else
            hi = t;
        double next = fp != 0.0 ? t - f / fp : 0.5 * (lo + hi);
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        const bool done = std::abs(next - t) <= 1e-13 * left || hi - lo <= 1e-13 * left;
        t = next;
        if (done) break;
    }
    return std::clamp(t, 0.0, left);
}

void Mechanics::control(double h) {
    const std::int64_t count = encoder();
    double w_enc = 0.0;
    if (last_h_ > 0.0) w_enc = static_cast<double>(count - last_count_) * rad_per_count_ / last_h_;
    last_count_ = count;
    last_h_ = h;

    if (mode_ == LoopMode::Off) {
        current_cmd_ = 0.0;
        x_.i = 0.0;
        integral_ = 0.0;
        limited_ = false;
        return;
    }
    const double hi = std::min(limit_pos_, peak_torque_);
    const double lo = std::min(limit_neg_, peak_torque_);
    double t = torque_ff_;
    bool saturated = false;
    if (mode_ == LoopMode::Torque) {
        integral_ = 0.0;
    } else {
        double v = velocity_ff_;
        if (mode_ == LoopMode::Position)
            v += gains_.position_kp * (position_cmd_ - static_cast<double>(count) * rad_per_count_);
        const double e = v - w_enc;
        const double p = gains_.velocity_kp * e;
        double integral = integral_;
        if (gains_.velocity_ti > 0.0) integral += gains_.velocity_kp * h / gains_.velocity_ti * e;
        const double u = p + integral + torque_ff_;
        // Anti-windup by clamping: the integrator grows only until the output reaches the limit.
        saturated = (u > hi && e > 0.0) || (u < -lo && e < 0.0);
        if (u > hi && e > 0.0)
            integral_ = std::max(integral_, hi - p - torque_ff_);
        else if (u < -lo && e < 0.0)
            integral_ = std::min(integral_, -lo - p - torque_ff_);
        else
            integral_ = integral;
        t = p + integral_ + torque_ff_;
    }
    limited_ = saturated || t > hi || t < -lo;
    t = std::clamp(t, -lo, hi);
    current_cmd_ = t / motor_.torque_constant;
    if (c_ <= 0.0) x_.i = current_cmd_;
}

void Mechanics::integrate(double h) {
    const double kt = motor_.torque_constant;
    const double tc = std::abs(motor_.coulomb_friction);
    double left = h;
    bool whole = true;    // left == h: the cached span applies
    double forced = 0.0;  // direction of a break-away located inside this substep
    for (int event = 0; event < 8 && left > 0.0; ++event) {
        const Span k = whole ? full_ : span(left);
        double dir = x_.w != 0.0 ? sign(x_.w) : forced;
        if (dir == 0.0) {
            // At rest: stick while the driving torque stays within the Coulomb friction.
            const double t0 = kt * x_.i - load_;
            if (std::abs(t0) > tc) {
                dir = sign(t0);
            } else {
                const State end = stuck(x_, k);
                const double t1 = kt * end.i - load_;
                if (std::abs(t1) <= tc) {
                    x_ = end;
                    return;
                }
                // The current (monotonic in between) breaks away at tb, where kt i(tb) - load = tc dir.
                dir = sign(t1);
                const double ratio = ((load_ + tc * dir) / kt - current_cmd_) / (x_.i - current_cmd_);
                double tb = 0.0;
                if (ratio > 0.0 && ratio < 1.0 && c_ > 0.0) tb = std::min(left, -std::log(ratio) / c_);
                x_ = stuck(x_, span(tb));
                left -= tb;
                whole = false;
                forced = dir;
                continue;
            }
        }
        const State end = moving(x_, k, dir);
        if (dir * end.w > 0.0) {
            x_ = end;
            return;
        }
        // The velocity reaches zero inside the interval: stop there, then decide stick or slip again.
        const double tz = crossing_time(x_, dir, left);
        x_ = moving(x_, span(tz), dir);
        x_.w = 0.0;
        left -= tz;
        whole = false;
        forced = 0.0;
    }
    if (left > 0.0) x_ = stuck(x_, span(left));  // event budget exhausted (degenerate): rest
}

// A substep with the loop off: control() zeroes the current command, the current, the integrator and the
// limit flag and takes the encoder count and h as the last ones; integrate() then sticks at rest while the
// load stays within the Coulomb friction (the current stays 0: cmd + (0 - cmd) e = 0); the I2t load stays
// at 0. If all of these hold already (positive zeros, as those assignments leave them), the substep changes
// nothing.
bool Mechanics::resting_unpowered() const {
    const auto plus_zero = [](double v) { return v == 0.0 && !std::signbit(v); };
    return mode_ == LoopMode::Off && plus_zero(x_.w) && plus_zero(x_.i) && plus_zero(current_cmd_) &&
           plus_zero(integral_) && !limited_ && plus_zero(i2t_) && last_h_ == h_ &&
           std::abs(motor_.torque_constant * 0.0 - load_) <= std::abs(motor_.coulomb_friction) &&
           std::isfinite(full_.ec) && last_count_ == encoder();
}

void Mechanics::step(double dt) {
    if (!(dt > 0.0) || !std::isfinite(dt)) return;
    if (dt != cached_dt_) {
        n_ = substeps(dt);
        h_ = dt / n_;
        full_ = span(h_);
        cached_dt_ = dt;
        fixed_ = false;
    }
    // A drive that the master is bringing up (INIT to SAFEOP) has its power stage off and the motor at rest:
    // then every substep leaves the state as it is, and none needs computing (the same result, bit for bit).
    // So does a held motor once its substeps reached a fixed point.
    if (fixed_ || resting_unpowered()) return;
    const double ir2 = motor_.rated_current * motor_.rated_current;
    const double den = (motor_.peak_current * motor_.peak_current - ir2) * motor_.peak_time;
    for (unsigned k = 0; k < n_; ++k) {
        // (Only a motor at rest can stay where it is: the state is compared only then.)
        const bool resting = x_.w == 0.0;
        const State x0 = x_;
        const double cmd0 = current_cmd_, integral0 = integral_, i2t0 = i2t_, h0 = last_h_;
        const std::int64_t count0 = last_count_;
        const bool limited0 = limited_;
        control(h_);
        const double i0 = x_.i;
        integrate(h_);
        if (den > 0.0) i2t_ = std::max(0.0, i2t_ + (0.5 * (i0 * i0 + x_.i * x_.i) - ir2) * h_ / den);
        ++substeps_run_;
        if (resting && same(x0.p, x_.p) && same(x0.w, x_.w) && same(x0.i, x_.i) && same(cmd0, current_cmd_) &&
            same(integral0, integral_) && same(i2t0, i2t_) && same(h0, last_h_) && count0 == last_count_ &&
            limited0 == limited_) {
            fixed_ = true;  // the substeps left of this step, and of the next ones, change nothing either
            return;
        }
    }
}

}  // namespace vecat::cia402
