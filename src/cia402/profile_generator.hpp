// Set-point generator of the profile modes: a jerk-limited seven-phase motion profile (TwinCAT NC PTP,
// ../shared/seeds/002) or a trapezoid (jerk unlimited), from any current state, with online changes.
// Pure math in double precision, in whatever position unit the caller uses (the drive uses user units).
//
// Approach. Every command plans a short table of segments of constant jerk (the manual's "runtime table")
// from the current state (p, v, a); step(dt) advances the time and evaluates that table in closed form at
// the new time (no integration), so every sample lies exactly on the planned curve. When the table ends
// the state snaps to its exact end (a position move: target, v = 0, a = 0).
// - Velocity change (v0, a0) -> (v1, a = 0): ramp the acceleration with +-J to a peak (limited by A+ while
//   the speed grows, by A- while it falls), hold it, ramp it back to 0. A start acceleration beyond the
//   limit is first ramped back to the limit. Trapezoid (J = 0 or infinite): the acceleration jumps.
// - Position move: phase A = velocity change to a cruise velocity vc <= V (decelerating first when the
//   current speed is above V), a cruise at vc, phase B = braking from vc to rest (the brake phase). vc = V
//   when the distance allows it; otherwise, as the manual says, the largest vc is found with the symmetric
//   A+ = A- = min(A+, A-) (falling back to A+/A- when that cannot stop in time from the current state), by
//   regula falsi (Illinois) on the distance of phases A+B, which is continuous in vc and grows with vc
//   above the velocity v_r reached by ramping the acceleration to 0 (that range is searched first).
// - New target behind the current position, or one the axis cannot stop before, or moving away from it:
//   stop (A-, J), then a move from rest back to the target, both in the same table.
// - No jerk rescaling is ever needed: a table exists for every J > 0 (the stop-and-return covers every
//   target that cannot be reached directly), and the sampled |da|/dt never exceeds J even when jerk phases
//   are shorter than a cycle, because the table is evaluated exactly.
// - Override f (0..1): the velocity limit becomes f V (or f times the level calculated at the start, by
//   the override type) and the table is replanned from the current state, unless a stop is active or the
//   brake phase (phase B) of the move was reached; f = 0 brakes to rest and the move waits for f > 0.
//   Types 1/2 keep the old table when the new level is not achievable. run_at profiles are scaled by the
//   override at any time.
// - Position compensation: a trapezoidal velocity profile g(tau) of the compensation (slopes AK+/AK-,
//   peak <= VK, length T = L/VP) is superposed as a function of the distance s travelled by the basic move
//   since the compensation started: offset = g(s/VP). This is the manual's "linear path control": the
//   compensation follows every change of the basic dynamics (override, stop) and ends after the length L.
//   When D is not achievable in T, the maximum possible (triangle of slopes AK+/AK-, peak <= VK) is used.
//   The output velocity and acceleration then exceed the move's limits by up to the compensation's limits.
// Accepted magnitudes: limits in [1e-30, 1e30] (jerk 0 or above 1e30: trapezoid), positions up to 1e30.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace vecat::cia402 {

struct Kinematics {
    double p = 0;  // position
    double v = 0;  // velocity (units/s)
    double a = 0;  // acceleration (units/s^2)
};

struct ProfileLimits {
    double velocity = 0;      // V > 0: magnitude of the cruise velocity
    double acceleration = 0;  // A+ > 0: magnitude while speeding up
    double deceleration = 0;  // A- > 0: magnitude while braking
    double jerk = 0;          // J > 0; 0 (or infinity) means no jerk limit: trapezoid
};

// Dynamics of a position compensation (TwinCAT NC PTP 2.5, "Position compensation: start parameters").
struct CompensationLimits {
    double velocity = 0;          // VK > 0: velocity increase/reduction relative to the process velocity
    double acceleration = 0;      // AK+ > 0: slope while the compensation velocity rises
    double deceleration = 0;      // AK- > 0: slope while it falls
    double process_velocity = 0;  // VP > 0; 0 = the planned cruise velocity of the current move
};

class ProfileGenerator {
  public:
    // Position move from the current state to target, ending at rest. Accepted while moving (new target,
    // new limits): when the new target was already overshot the profile stops and returns. false when the
    // limits are not usable (non-positive, NaN); the current plan then continues unchanged. A compensation
    // in progress ends here: the distance compensated so far is kept.
    bool move_to(double target, const ProfileLimits& lim);
    // Velocity profile: reach the signed velocity (|velocity| limited to lim.velocity) and hold it
    // (profile velocity mode, homing searches). A change of sign brakes to rest first.
    bool run_at(double velocity, const ProfileLimits& lim);
    // Brake to rest with the given deceleration and jerk (quick stop, halt); 0 jerk = no jerk limit.
    // Always takes effect (also in the brake phase); a non-usable deceleration stops at once.
    void stop(double deceleration, double jerk);
    // Velocity override as TwinCAT NC PTP describes it: fraction 0..1 of the commanded velocity (0 = stop),
    // applied online with the brake-phase rules of the manual. 1 by default. The fraction is stored even
    // when it cannot act now (brake phase, stop); it then applies to the next move.
    void set_override(double fraction);
    double override_fraction() const;
    // The override type of TX1250 2.2 (1-4, others read as 4): odd types scale the velocity level
    // calculated (and possibly reduced) at the start of the move, even types the velocity V the user
    // commanded; types 1 and 2 keep the current table when the new level is not achievable, types 3 and 4
    // go to the largest achievable level below it. Takes effect at the next override change or move.
    void set_override_type(int type);
    int override_type() const { return override_type_; }
    // Position compensation (TwinCAT NC PTP 2.5): an extra distance d travelled within a length l of the
    // basic move, both counted along its direction (d > 0 travels further, d < 0 less; L > the rest of the
    // move is cut to the rest). false when it cannot start (no move, stop, already compensating); when d is
    // not fully achievable the maximum possible compensation is carried out. The two-argument form uses the
    // move's limits as the compensation's limits (VK = V, AK+ = A+, AK- = A-, VP = cruise velocity).
    bool compensate(double d, double l);
    bool compensate(double d, double l, const CompensationLimits& c);
    // The extra distance of the compensation in progress along the path (the achievable part of d); 0 when
    // none.
    double compensation() const;
    bool compensating() const { return comp_.active; }
    // Compensation stop (TX1250 2.5): a compensation that has not reached its falling ramp starts it now,
    // so the distance compensated becomes what is travelled until that ramp ends. false when there is no
    // compensation or it is already in its falling ramp.
    bool stop_compensation();
    // Forget every plan and stand at k (the drive follows the actual position while disabled). Until the
    // next command step() holds k unchanged.
    void reset(const Kinematics& k);
    // Advance by dt seconds and return the new demand. dt <= 0 or not finite: no change.
    const Kinematics& step(double dt);
    const Kinematics& state() const;
    // Position moves: target reached and at rest. Velocity profiles: velocity reached.
    bool done() const;
    // The target of the current position move (or the current position). During a compensation: the
    // target plus the achievable compensation.
    double target() const;
    // The final braking phase of a position move has begun (override is then ignored).
    bool in_brake_phase() const;
    // Time left in the current table (0 when it has ended).
    double remaining_time() const;
    // Magnitude of the cruise velocity of the current position move (V, f V or the reduced level).
    double cruise_velocity() const { return cruise_; }
    // Closed-form duration of a rest-to-rest move over distance with these limits (0 for unusable limits).
    static double rest_to_rest_duration(double distance, const ProfileLimits& lim);

    // One constant-jerk piece of a table: acceleration a at its start, jerk j, duration t.
    struct Segment {
        double t = 0, a = 0, j = 0;
        double t0 = 0, p0 = 0, v0 = 0;  // start time and state, filled in by finish()
    };
    static constexpr std::size_t kMaxSegments = 12;

  private:
    enum class Mode : std::uint8_t { Idle, Position, Velocity, Stopping };

    struct Table {
        Kinematics origin;
        std::array<Segment, kMaxSegments> seg{};
        std::size_t n = 0;
        double duration = 0;
        double brake_time = -1;  // start of the final braking phase (position moves), -1 = none
        Kinematics end;          // exact end state
        void clear(const Kinematics& k);
        void push(double t, double a, double j);
        void finish();  // start times and states of the segments; end = propagated end
        Kinematics at(double t, std::size_t& cursor) const;
        void shift(double dp);
    };

    struct Compensation {
        bool active = false;
        double start = 0;  // base position at the start
        double dir = 1;    // direction of the basic move
        double sign = 1;   // sign of d
        double vp = 1, length = 0, duration = 0;
        double rise = 1, fall = 1;  // slopes of the first and second ramp
        double peak = 0, t1 = 0, t2 = 0, t3 = 0, distance = 0;
        double tau(double base_p) const;
        void eval(double tau, double& g, double& g1, double& g2) const;
    };

    void plan_position();
    void plan_velocity();
    void fold_compensation();
    double override_level() const;  // what the override scales: V or the level at the start
    void apply_compensation();

    Mode mode_ = Mode::Idle;
    Table table_;
    double t_ = 0;
    std::size_t cursor_ = 0;
    Kinematics base_;  // the basic dynamics
    Kinematics out_;   // base plus compensation
    ProfileLimits lim_;
    double target_ = 0;
    double velocity_ = 0;  // run_at command
    double override_ = 1;
    int override_type_ = 4;
    double level_ = 0;  // the velocity level calculated at the start of the move, at override 1
    double cruise_ = 0;
    bool waiting_ = false;  // position move held by override 0
    Compensation comp_;
};

}  // namespace vecat::cia402
