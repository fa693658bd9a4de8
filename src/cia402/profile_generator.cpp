// The profile generator (profile_generator.hpp explains the approach). About 650 lines because the planning,
// the online changes of TX1250 chapter 2 (override and its types, compensation and its stop) and the
// closed-form evaluation share the runtime table and its state; splitting them would expose that state.
#include "cia402/profile_generator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vecat::cia402 {

namespace {

constexpr double kMaxMagnitude = 1e30;
constexpr double kMinLimit = 1e-30;
constexpr double kInf = std::numeric_limits<double>::infinity();

bool usable_limit(double x) {
    return std::isfinite(x) && x >= kMinLimit && x <= kMaxMagnitude;
}
bool trapezoid_jerk(double j) {
    return j == 0 || j > kMaxMagnitude;
}
bool usable(const ProfileLimits& lim) {
    return usable_limit(lim.velocity) && usable_limit(lim.acceleration) && usable_limit(lim.deceleration) &&
           (trapezoid_jerk(lim.jerk) || usable_limit(lim.jerk));
}
double sign_of(double x) {
    return x > 0 ? 1.0 : x < 0 ? -1.0 : 0.0;
}

// Dynamics in a frame where speeds are >= 0: up limits a > 0 (speeding up), down limits a < 0 (braking).
struct Dyn {
    double up = 0, down = 0, jerk = kInf;
    bool trap = true;
};
Dyn dyn_of(double up, double down, double jerk) {
    const bool trap = trapezoid_jerk(jerk) || !std::isfinite(jerk);
    return {up, down, trap ? kInf : jerk, trap};
}

// Up to three constant-jerk pieces of a velocity change, in the frame.
struct Ramp {
    double t[3] = {0, 0, 0}, a[3] = {0, 0, 0}, j[3] = {0, 0, 0};
    int n = 0;
    void push(double dt, double acc, double jerk) {
        if (!(dt > 0)) return;
        t[n] = dt;
        a[n] = acc;
        j[n] = jerk;
        ++n;
    }
    void negate() {
        for (int i = 0; i < n; ++i) {
            a[i] = -a[i];
            j[i] = -j[i];
        }
    }
    // Distance travelled from velocity v0; v0 becomes the end velocity.
    double distance(double& v) const {
        double d = 0;
        for (int i = 0; i < n; ++i) {
            const double T = t[i];
            d += T * (v + T * (a[i] / 2 + T * j[i] / 6));
            v += T * (a[i] + T * j[i] / 2);
        }
        return d;
    }
};

// (v0, a0) -> (v1, 0) raising the velocity (v1 >= v0 + a0|a0|/2J): peak acceleration <= lim.
void raise_velocity(double v0, double a0, double v1, double lim, const Dyn& d, Ramp& r) {
    const double dv = v1 - v0;
    if (d.trap) {
        if (dv > 0) r.push(dv / lim, lim, 0);
        return;
    }
    const double J = d.jerk;
    if (a0 > lim) {  // start beyond the limit: back to it first
        const double hold = (dv - (a0 * a0 - lim * lim) / (2 * J) - lim * lim / (2 * J)) / lim;
        r.push((a0 - lim) / J, a0, -J);
        r.push(std::max(0.0, hold), lim, 0);
        r.push(lim / J, lim, -J);
        return;
    }
    double peak = std::sqrt(std::max(0.0, J * dv + a0 * a0 / 2));
    peak = std::max(peak, std::max(a0, 0.0));
    double hold = 0;
    if (peak > lim) {
        peak = lim;
        hold = std::max(0.0, (dv - (2 * lim * lim - a0 * a0) / (2 * J)) / lim);
    }
    r.push((peak - a0) / J, a0, J);
    r.push(hold, peak, 0);
    r.push(peak / J, peak, -J);
}

// (v0, a0) -> (v1, 0) in a frame where speeds are >= 0.
Ramp velocity_change(double v0, double a0, double v1, const Dyn& d) {
    Ramp r;
    const double reached = d.trap ? v0 : v0 + a0 * std::abs(a0) / (2 * d.jerk);
    if (v1 >= reached) {
        raise_velocity(v0, a0, v1, d.up, d, r);
    } else {
        raise_velocity(-v0, -a0, -v1, d.down, d, r);
        r.negate();
    }
    return r;
}

// Direction in which (v, a) moves now: the sign of v, else of a (+1 at rest).
double motion_sign(double v, double a) {
    return v != 0 ? sign_of(v) : a < 0 ? -1.0 : 1.0;
}

}  // namespace

// ---- Table ----------------------------------------------------------------------------------------------

void ProfileGenerator::Table::clear(const Kinematics& k) {
    origin = k;
    n = 0;
    duration = 0;
    brake_time = -1;
    end = k;
}

void ProfileGenerator::Table::push(double t, double a, double j) {
    if (!(t > 0) || n >= kMaxSegments) return;
    seg[n] = Segment{t, a, j, duration, 0, 0};
    duration += t;
    ++n;
}

void ProfileGenerator::Table::finish() {
    double p = origin.p, v = origin.v, a = origin.a, t0 = 0;
    for (std::size_t i = 0; i < n; ++i) {
        Segment& s = seg[i];
        s.t0 = t0;
        s.p0 = p;
        s.v0 = v;
        const double T = s.t;
        p += T * (v + T * (s.a / 2 + T * s.j / 6));
        v += T * (s.a + T * s.j / 2);
        a = s.a + s.j * T;
        t0 += T;
    }
    duration = t0;
    end = {p, v, a};
}

Kinematics ProfileGenerator::Table::at(double t, std::size_t& cursor) const {
    if (n == 0 || t >= duration) return end;
    if (cursor >= n) cursor = 0;
    while (cursor > 0 && t < seg[cursor].t0)
        --cursor;
    while (cursor + 1 < n && t >= seg[cursor + 1].t0)
        ++cursor;
    const Segment& s = seg[cursor];
    const double T = std::max(0.0, t - s.t0);
    return {s.p0 + T * (s.v0 + T * (s.a / 2 + T * s.j / 6)), s.v0 + T * (s.a + T * s.j / 2), s.a + s.j * T};
}

void ProfileGenerator::Table::shift(double dp) {
    origin.p += dp;
    for (std::size_t i = 0; i < n; ++i)
        seg[i].p0 += dp;
    end.p += dp;
}

// ---- Planning -------------------------------------------------------------------------------------------

void ProfileGenerator::plan_position() {
    table_.clear(base_);
    t_ = 0;
    cursor_ = 0;
    Table& tb = table_;
    const Dyn full = dyn_of(lim_.acceleration, lim_.deceleration, lim_.jerk);

    auto push_ramp = [&tb](const Ramp& r, double s) {
        for (int i = 0; i < r.n; ++i)
            tb.push(r.t[i], s * r.a[i], s * r.j[i]);
    };
    // A stop from (v, a) (absolute); returns the signed distance.
    auto push_stop = [&](double v, double a, const Dyn& d) {
        const double s = motion_sign(v, a);
        const Ramp r = velocity_change(s * v, s * a, 0, d);
        double vv = s * v;
        const double dist = r.distance(vv);
        push_ramp(r, s);
        return s * dist;
    };

    if (override_ <= 0) {  // held by override 0: brake to rest and wait
        waiting_ = true;
        cruise_ = 0;
        push_stop(base_.v, base_.a, full);
        tb.finish();
        tb.end.v = 0;
        tb.end.a = 0;
        return;
    }
    waiting_ = false;
    const double vmax = override_level() * override_;

    // Direct move in the frame s (target ahead at distance d >= 0) from speed v0 >= 0 (or 0 with any a0).
    auto direct = [&](double s, double v0, double a0, double d) {
        const Dyn minimal = dyn_of(std::min(full.up, full.down), std::min(full.up, full.down), lim_.jerk);
        auto phases = [&](double vc, const Dyn& dy, Ramp& ra, Ramp& rb) {
            ra = velocity_change(v0, a0, vc, dy);
            double v = v0;
            const double da = ra.distance(v);
            rb = velocity_change(vc, 0, 0, dy);
            double w = vc;
            return da + rb.distance(w);
        };
        Ramp ra, rb;
        // Rounding allowed where the plan is continued at a boundary (absorbed by the final snap).
        const double tol = 1e-12 * d + 4 * std::numeric_limits<double>::epsilon() * std::abs(target_);
        double vc = vmax, cruise_time = 0;
        const double dv = phases(vmax, full, ra, rb);
        if (dv <= d) {
            cruise_time = (d - dv) / vmax;
        } else {
            // The largest vc whose phases fit: with min(A+, A-) as the manual says, when that can stop in
            // time. Above the velocity reached by ramping the acceleration to 0 (v_r) the distance grows
            // with vc; below it (braking at once) it need not, so [v_r, V] is searched when v_r fits.
            double lo = 0, hi = 0;
            auto bracket = [&](const Dyn& dy) {
                const double vr =
                    std::clamp(dy.trap ? v0 : v0 + a0 * std::abs(a0) / (2 * dy.jerk), 0.0, vmax);
                lo = 0;
                hi = vr;
                if (vr < vmax && phases(vr, dy, ra, rb) <= d + tol) {
                    lo = vr;
                    hi = vmax;
                    return true;
                }
                return phases(0, dy, ra, rb) <= d + tol;
            };
            const Dyn& dy = bracket(minimal) ? minimal : full;
            if (&dy == &full) bracket(full);
            // Regula falsi (Illinois) on D(vc) - d, keeping D(lo) <= d < D(hi); bisection as fallback.
            double flo = phases(lo, dy, ra, rb) - d, fhi = phases(hi, dy, ra, rb) - d;
            int side = 0;
            vc = fhi <= 0 ? hi : lo;
            for (int i = 0; i < 200 && flo < 0 && fhi > 0 && hi - lo > 1e-15 * hi; ++i) {
                double x = (lo * fhi - hi * flo) / (fhi - flo);
                if (!(x > lo && x < hi)) x = 0.5 * (lo + hi);
                if (x <= lo || x >= hi) break;
                const double fx = phases(x, dy, ra, rb) - d;
                if (fx <= 0) {
                    lo = x;
                    flo = fx;
                    if (side == -1) fhi /= 2;
                    side = -1;
                } else {
                    hi = x;
                    fhi = fx;
                    if (side == 1) flo /= 2;
                    side = 1;
                }
                vc = lo;
                if (std::abs(fx) <= tol) {
                    vc = x;  // close enough: the snap at the end absorbs the rest
                    break;
                }
            }
            phases(vc, dy, ra, rb);  // the residual distance (tiny) is absorbed by the final snap
        }
        push_ramp(ra, s);
        tb.push(cruise_time, 0, 0);
        tb.brake_time = tb.duration;
        push_ramp(rb, s);
        return vc;
    };

    const double dist = target_ - base_.p;
    if (dist == 0 && base_.v == 0 && base_.a == 0) {
        cruise_ = 0;
        tb.finish();
        tb.end = {target_, 0, 0};
        return;
    }
    const double s = dist != 0 ? sign_of(dist) : motion_sign(base_.v, base_.a);
    const double d = s * dist, v0 = s * base_.v, a0 = s * base_.a;

    // Where would a stop end (relative, in the frame)?
    double stop_dist = 0;
    {
        const double ss = motion_sign(v0, a0);
        double vv = ss * v0;
        stop_dist = ss * velocity_change(ss * v0, ss * a0, 0, full).distance(vv);
    }
    const double tol = 1e-12 * (std::abs(d) + std::abs(stop_dist)) +
                       4 * std::numeric_limits<double>::epsilon() * std::abs(target_);
    if (v0 < 0 || stop_dist > d + tol) {
        // Overshot or cannot stop before the target: stop, then move back from rest.
        const double moved = push_stop(base_.v, base_.a, full);
        const double rest = target_ - (base_.p + moved);
        const double s2 = rest >= 0 ? 1.0 : -1.0;
        cruise_ = direct(s2, 0, 0, std::abs(rest));
    } else {
        cruise_ = direct(s, std::max(v0, 0.0), a0, d);
    }
    tb.finish();
    tb.end = {target_, 0, 0};
}

void ProfileGenerator::plan_velocity() {
    table_.clear(base_);
    t_ = 0;
    cursor_ = 0;
    waiting_ = false;
    const Dyn full = dyn_of(lim_.acceleration, lim_.deceleration, lim_.jerk);
    const double goal = velocity_ * override_;
    auto push = [this, &full](double s, double v, double a, double v1) {
        const Ramp r = velocity_change(s * v, s * a, s * v1, full);
        for (int i = 0; i < r.n; ++i)
            table_.push(r.t[i], s * r.a[i], s * r.j[i]);
    };
    const bool moving = base_.v != 0 || base_.a != 0;
    const double s0 = motion_sign(base_.v, base_.a);
    if (moving && goal * s0 < 0) {  // reverse: brake to rest first
        push(s0, base_.v, base_.a, 0);
        push(sign_of(goal), 0, 0, goal);
    } else {
        push(moving ? s0 : (goal >= 0 ? 1.0 : -1.0), base_.v, base_.a, goal);
    }
    table_.finish();
    table_.end.v = goal;
    table_.end.a = 0;
    cruise_ = std::abs(goal);
}

// ---- Commands -------------------------------------------------------------------------------------------

bool ProfileGenerator::move_to(double target, const ProfileLimits& lim) {
    if (!usable(lim) || !std::isfinite(target) || std::abs(target) > kMaxMagnitude) return false;
    fold_compensation();
    mode_ = Mode::Position;
    lim_ = lim;
    target_ = target;
    // The level of this move at override 1 (V, or less when the distance is short), for the odd types.
    const double f = override_;
    override_ = 1;
    level_ = 0;
    plan_position();
    level_ = cruise_;
    override_ = f;
    if (f != 1) plan_position();
    out_ = base_;
    return true;
}

bool ProfileGenerator::run_at(double velocity, const ProfileLimits& lim) {
    if (!usable(lim) || !std::isfinite(velocity)) return false;
    fold_compensation();
    mode_ = Mode::Velocity;
    lim_ = lim;
    velocity_ = std::clamp(velocity, -lim.velocity, lim.velocity);
    plan_velocity();
    out_ = base_;
    return true;
}

void ProfileGenerator::stop(double deceleration, double jerk) {
    mode_ = Mode::Stopping;
    waiting_ = false;
    cruise_ = 0;
    t_ = 0;
    cursor_ = 0;
    if (!usable_limit(deceleration)) {  // no usable ramp: stand still at once
        fold_compensation();
        base_.v = 0;
        base_.a = 0;
        table_.clear(base_);
        out_ = base_;
        return;
    }
    table_.clear(base_);
    const Dyn d = dyn_of(deceleration, deceleration, std::isnan(jerk) || jerk < 0 ? 0 : jerk);
    const double s = motion_sign(base_.v, base_.a);
    const Ramp r = velocity_change(s * base_.v, s * base_.a, 0, d);
    for (int i = 0; i < r.n; ++i)
        table_.push(r.t[i], s * r.a[i], s * r.j[i]);
    table_.finish();
    table_.end.v = 0;
    table_.end.a = 0;
}

void ProfileGenerator::set_override(double fraction) {
    if (std::isnan(fraction)) return;
    override_ = std::clamp(fraction, 0.0, 1.0);
    if (mode_ == Mode::Position) {
        if (done() || in_brake_phase()) return;  // the manual: not in the brake phase
        // Types 1 and 2: "if the new velocity level is not achievable, the old runtime table is maintained
        // without notification" (a move held by override 0 takes the achievable level: it must go on).
        const bool keep_if_short = override_type_ <= 2 && !waiting_;
        const Table table = table_;
        const double t = t_, cruise = cruise_;
        const std::size_t cursor = cursor_;
        plan_position();
        if (keep_if_short && !waiting_ && cruise_ < override_level() * override_ * (1 - 1e-9)) {
            table_ = table;
            t_ = t;
            cursor_ = cursor;
            cruise_ = cruise;
        }
    } else if (mode_ == Mode::Velocity) {
        plan_velocity();
    }
}

double ProfileGenerator::override_fraction() const {
    return override_;
}

double ProfileGenerator::override_level() const {
    // Odd override types refer to the level calculated at the start (TX1250 2.2), even ones to V.
    return override_type_ % 2 == 1 && level_ > 0 ? std::min(level_, lim_.velocity) : lim_.velocity;
}

void ProfileGenerator::set_override_type(int type) {
    override_type_ = type >= 1 && type <= 4 ? type : 4;
}

bool ProfileGenerator::compensate(double d, double l) {
    return compensate(d, l, CompensationLimits{lim_.velocity, lim_.acceleration, lim_.deceleration, 0});
}

bool ProfileGenerator::compensate(double d, double l, const CompensationLimits& c) {
    if (comp_.active || mode_ != Mode::Position || waiting_ || done()) return false;
    if (!std::isfinite(d) || d == 0 || std::abs(d) > kMaxMagnitude || !usable_limit(l)) return false;
    if (!usable_limit(c.velocity) || !usable_limit(c.acceleration) || !usable_limit(c.deceleration))
        return false;
    const double vp = c.process_velocity > 0 ? c.process_velocity : cruise_;
    if (!usable_limit(vp)) return false;
    const double dir = sign_of(target_ - base_.p);
    if (dir == 0 || base_.v * dir < 0) return false;  // no move, or the stop of a stop-and-return

    Compensation k;
    k.active = true;
    k.start = base_.p;
    k.dir = dir;
    k.sign = sign_of(d);
    k.vp = vp;
    k.length = std::min(l, std::abs(target_ - base_.p));
    k.duration = k.length / vp;
    // d > 0 starts with the acceleration increase AK+, d < 0 with the deceleration increase AK-.
    k.rise = d > 0 ? c.acceleration : c.deceleration;
    k.fall = d > 0 ? c.deceleration : c.acceleration;
    const double T = k.duration, half = 1 / (2 * k.rise) + 1 / (2 * k.fall);
    const double peak_max = std::min(c.velocity, T / (1 / k.rise + 1 / k.fall));
    const double reach = peak_max * (T - half * peak_max);
    const double want = std::abs(d);
    if (want <= reach) {
        k.peak = 2 * want / (T + std::sqrt(std::max(0.0, T * T - 4 * half * want)));
    } else {
        k.peak = peak_max;
    }
    k.t1 = k.peak / k.rise;
    k.t3 = k.peak / k.fall;
    k.t2 = std::max(0.0, T - k.t1 - k.t3);
    k.distance = want <= reach ? want : k.rise * k.t1 * k.t1 / 2 + k.peak * k.t2 + k.fall * k.t3 * k.t3 / 2;
    comp_ = k;
    return true;
}

bool ProfileGenerator::stop_compensation() {
    if (!comp_.active) return false;
    Compensation& k = comp_;
    const double tau = k.tau(base_.p);
    if (tau >= k.t1 + k.t2) return false;  // already in its falling ramp
    // The rise (or the hold) ends now and the fall follows at once.
    if (tau < k.t1) {
        k.t1 = tau;
        k.peak = k.rise * tau;
        k.t2 = 0;
    } else {
        k.t2 = tau - k.t1;
    }
    k.t3 = k.peak / k.fall;
    k.duration = k.t1 + k.t2 + k.t3;
    k.length = k.duration * k.vp;
    k.distance = k.rise * k.t1 * k.t1 / 2 + k.peak * k.t2 + k.fall * k.t3 * k.t3 / 2;
    if (!(k.distance > 0)) k.active = false;  // nothing compensated yet
    return true;
}

double ProfileGenerator::compensation() const {
    return comp_.active ? comp_.sign * comp_.distance : 0.0;
}

void ProfileGenerator::reset(const Kinematics& k) {
    auto finite = [](double x) { return std::isfinite(x) && std::abs(x) <= kMaxMagnitude ? x : 0.0; };
    base_ = {finite(k.p), finite(k.v), finite(k.a)};
    out_ = base_;
    mode_ = Mode::Idle;
    table_.clear(base_);
    t_ = 0;
    cursor_ = 0;
    target_ = base_.p;
    cruise_ = 0;
    waiting_ = false;
    comp_.active = false;
}

// ---- Compensation ---------------------------------------------------------------------------------------

double ProfileGenerator::Compensation::tau(double base_p) const {
    const double s = std::clamp(dir * (base_p - start), 0.0, length);
    return std::min(s / vp, duration);
}

void ProfileGenerator::Compensation::eval(double t, double& g, double& g1, double& g2) const {
    if (t <= 0) {
        g = g1 = g2 = 0;
    } else if (t < t1) {
        g = rise * t * t / 2;
        g1 = rise * t;
        g2 = rise;
    } else if (t < t1 + t2) {
        g = rise * t1 * t1 / 2 + peak * (t - t1);
        g1 = peak;
        g2 = 0;
    } else if (t < duration) {
        const double u = duration - t;
        g = distance - fall * u * u / 2;
        g1 = fall * u;
        g2 = -fall;
    } else {
        g = distance;
        g1 = g2 = 0;
    }
}

void ProfileGenerator::fold_compensation() {
    if (!comp_.active) return;
    base_ = out_;
    comp_.active = false;
}

void ProfileGenerator::apply_compensation() {
    out_ = base_;
    if (!comp_.active) return;
    const Compensation& k = comp_;
    const double s = k.dir * (base_.p - k.start);
    const bool table_ended = t_ >= table_.duration;
    const bool base_done = table_ended && (mode_ == Mode::Stopping || (mode_ == Mode::Position && !waiting_));
    if (s >= k.length || base_done) {
        // Complete (or the basic move ended): the offset becomes part of the basic move and its target.
        double g = k.distance, g1 = 0, g2 = 0;
        if (s < k.length) k.eval(k.tau(base_.p), g, g1, g2);
        const double off = k.dir * k.sign * g;
        base_.p += off;
        table_.shift(off);
        if (mode_ == Mode::Position) target_ += off;
        comp_.active = false;
        out_ = base_;
        return;
    }
    double g = 0, g1 = 0, g2 = 0;
    k.eval(k.tau(base_.p), g, g1, g2);
    const double q = base_.v / k.vp;  // d tau / dt (times dir)
    out_.p = base_.p + k.dir * k.sign * g;
    out_.v = base_.v + k.sign * g1 * q;
    out_.a = base_.a + k.sign * (k.dir * g2 * q * q + g1 * base_.a / k.vp);
}

// ---- Time -----------------------------------------------------------------------------------------------

const Kinematics& ProfileGenerator::step(double dt) {
    if (!(dt > 0) || !std::isfinite(dt) || mode_ == Mode::Idle) return out_;
    const double t = t_ + dt;
    if (t < table_.duration) {
        t_ = t;
        base_ = table_.at(t_, cursor_);
    } else {
        const double over = t - table_.duration;
        base_ = table_.end;
        if (mode_ == Mode::Velocity) base_.p += base_.v * over;  // holds the reached velocity
        table_.clear(base_);
        t_ = 0;
        cursor_ = 0;
    }
    apply_compensation();
    return out_;
}

const Kinematics& ProfileGenerator::state() const {
    return out_;
}

bool ProfileGenerator::done() const {
    switch (mode_) {
        case Mode::Idle:
            return true;
        case Mode::Position:
            return !waiting_ && t_ >= table_.duration && !comp_.active;
        default:
            return t_ >= table_.duration;
    }
}

double ProfileGenerator::target() const {
    switch (mode_) {
        case Mode::Position:
            return target_ + (comp_.active ? comp_.dir * comp_.sign * comp_.distance : 0.0);
        case Mode::Stopping: {
            double g = 0, g1 = 0, g2 = 0;
            if (comp_.active) comp_.eval(comp_.tau(table_.end.p), g, g1, g2);
            return table_.end.p + (comp_.active ? comp_.dir * comp_.sign * g : 0.0);
        }
        default:
            return out_.p;
    }
}

bool ProfileGenerator::in_brake_phase() const {
    return mode_ == Mode::Position && !waiting_ && table_.brake_time >= 0 && t_ >= table_.brake_time &&
           t_ < table_.duration;
}

double ProfileGenerator::remaining_time() const {
    return std::max(0.0, table_.duration - t_);
}

// ---- Closed form ----------------------------------------------------------------------------------------

double ProfileGenerator::rest_to_rest_duration(double distance, const ProfileLimits& lim) {
    if (!usable(lim) || !std::isfinite(distance)) return 0;
    const double d = std::abs(distance);
    if (d == 0) return 0;
    const double V = lim.velocity;
    const bool trap = trapezoid_jerk(lim.jerk);
    const double J = lim.jerk;
    // Time to reach V from rest (and back): with A reached, without, or without jerk limit.
    auto ramp_time = [&](double A) {
        if (trap) return V / A;
        return V * J >= A * A ? V / A + A / J : 2 * std::sqrt(V / J);
    };
    const double ta = ramp_time(lim.acceleration), tb = ramp_time(lim.deceleration);
    const double ramps = V * (ta + tb) / 2;  // each ramp is point-symmetric: mean velocity V/2
    if (ramps <= d) return ta + tb + (d - ramps) / V;
    // V not reached: the largest peak under the symmetric min(A+, A-) (the manual's rule).
    const double A = std::min(lim.acceleration, lim.deceleration);
    if (trap) return 2 * std::sqrt(d / A);
    const double tj = A / J;
    if (d >= 2 * A * tj * tj) return tj + std::sqrt(tj * tj + 4 * d / A);  // A reached
    return 4 * std::cbrt(d / (2 * J));                                     // A not reached
}

}  // namespace vecat::cia402
