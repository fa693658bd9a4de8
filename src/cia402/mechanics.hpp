// The simulated mechanics of one axis: a servo motor with torque constant, rotor and load inertia, viscous
// and Coulomb friction, an incremental/absolute encoder, and the drive's cascaded position, velocity and
// current loops. Deterministic for a given step size. SI units on the motor side (rad, rad/s, Nm, A).
//
// Model. J dw/dt = Kt i - B w - Tc sign(w) - T_load, with J = rotor + load inertia. At rest (w == 0) the
// axis sticks while |Kt i - T_load| <= Tc. The current follows its command through a first-order lag
// (the current loop). step(dt) runs the loops at a fixed substep h = dt / N, N = ceil(dt / max_substep):
// each substep samples the encoder, computes the loops (zero-order hold), then integrates the mechanics
// and the current lag in closed form over h (exact for piecewise constant current commands; friction
// reversals and stiction break-away are located inside the substep). Same dt, same commands: same bits.
//
// Loops (Position mode): v* = position_kp (p* - p_enc) + velocity_ff; T* = PI(v* - w_enc) + torque_ff,
// clamped to the torque limits and to peak_current * Kt; i* = T* / Kt. p_enc is the quantised encoder
// position and w_enc its difference quotient over one substep, so the loops see what a real drive sees
// (and lose the axis when the encoder is faulted). Velocity mode: v* = velocity_ff. Torque mode:
// T* = torque_ff (still clamped). Off: amplifier disabled, no current, the axis coasts until friction
// stops it (or a load torque above Tc drives it).
#pragma once

#include <cstdint>

namespace vecat::cia402 {

struct MotorParameters {
    double torque_constant = 0.6;    // Nm/A
    double rotor_inertia = 1.2e-5;   // kg m^2
    double load_inertia = 2.4e-5;    // kg m^2 (reflected to the motor)
    double viscous_friction = 5e-5;  // Nm s/rad
    double coulomb_friction = 0.01;  // Nm
    double rated_current = 3.0;      // A
    double peak_current = 9.0;       // A
    unsigned encoder_bits = 20;      // increments per revolution = 2^bits
    double peak_time = 1.0;          // s at peak current (from cold) until the I2t protection trips
};

// Defaults = Mechanics::tuned_for(MotorParameters{}): velocity bandwidth 400 rad/s for J = 3.6e-5 kg m^2.
struct ControlGains {
    double position_kp = 100.0;       // 1/s: velocity command per position error
    double velocity_kp = 0.0144;      // Nm s/rad
    double velocity_ti = 0.01;        // s, integral time of the velocity loop (<= 0: no integral action)
    double current_bandwidth = 2000;  // rad/s, first-order current loop (<= 0: ideal, no lag)
};

enum class LoopMode : std::uint8_t { Off, Position, Velocity, Torque };

class Mechanics {
  public:
    // Longest substep of the internal loops and of the integration (16 kHz).
    static constexpr double max_substep = 62.5e-6;

    Mechanics(const MotorParameters& m = {}, const ControlGains& g = {});
    // Gains for a motor: velocity loop crossover at velocity_bandwidth (rad/s) for the total inertia
    // (velocity_kp = J wv), integral time 4 / wv, position_kp = wv / 4, current bandwidth 2000 rad/s.
    static ControlGains tuned_for(const MotorParameters& m, double velocity_bandwidth = 400.0);
    // Substeps step(dt) uses: ceil(dt / max_substep), at least 1.
    static unsigned substeps(double dt);

    // Set-points for the loops; feed-forwards are added to the loop outputs. Held constant during the next
    // step (zero-order hold). Leaving Position/Velocity mode clears the velocity integrator.
    void command(LoopMode mode, double position, double velocity_ff, double torque_ff);
    // Nm, magnitudes (NaN: unchanged). Initially none but peak_current * Kt, which always applies.
    void set_torque_limits(double positive, double negative);
    // External load, Nm, subtracted from the motor torque (positive: pulls towards negative positions).
    void set_load_torque(double nm);
    void step(double dt);          // s
    double position() const;       // rad, true mechanical position (multi-turn)
    std::int64_t encoder() const;  // increments, quantised
    double velocity() const;       // rad/s
    double torque() const;         // Nm (electromagnetic)
    double current() const;        // A
    bool torque_limited() const;   // the last torque command was clamped (by a limit or the peak current)

    // Gains take effect at the next substep (the integrator keeps its value).
    void set_gains(const ControlGains& g);
    const ControlGains& gains() const { return gains_; }
    const MotorParameters& parameters() const { return motor_; }
    LoopMode mode() const { return mode_; }
    double load_torque() const { return load_; }
    // Moves the axis to rad without changing velocity or current (the encoder and the velocity estimate
    // follow without a jump; a frozen encoder stays frozen).
    void set_position(double rad);
    // Power-on state: at 0 rad, at rest, no current, Off, integrator and I2t cleared, faults cleared.
    // Keeps parameters, gains, torque limits and the load torque.
    void reset();

    // Faults for the drive to detect (it maps them to 0x603F). An encoder fault freezes the encoder value;
    // the loops then see a standing axis, so the drive must disable the loops. Clearing it resumes the
    // encoder at the true position.
    void inject_encoder_fault(bool on);
    bool encoder_ok() const { return !encoder_fault_; }
    // An injected over-current (as the power stage's comparator reports a short circuit).
    void inject_overcurrent(bool on);
    // Injected, or the I2t protection: i2t() >= 1. Not latched (the drive latches its faults).
    bool overcurrent() const;
    // Thermal load of the I2t protection: integral of (i^2 - rated^2) / ((peak^2 - rated^2) peak_time),
    // never below 0. From cold it reaches 1 after peak_time at peak current, never at rated current.
    double i2t() const { return i2t_; }
    // Substeps computed so far. A substep that leaves every member as it found it (a motor held at
    // standstill, its current settled) is a fixed point: with the same inputs every further one is too, and
    // step() skips them until an input changes (the result is the same, bit for bit).
    std::uint64_t substeps_run() const { return substeps_run_; }

  private:
    struct State {
        double p;  // rad
        double w;  // rad/s
        double i;  // A
    };
    // Closed-form coefficients for an interval tau: w(tau) = w0 ea + A p1 + D r1 and
    // p(tau) = p0 + w0 p1 + A p2 + D r2 for w' = -a w + A + D exp(-c s) (a = B/J, c = current bandwidth).
    struct Span {
        double ea;  // exp(-a tau)
        double p1;  // int_0^tau exp(-a s) ds
        double p2;  // int_0^tau p1(s) ds
        double ec;  // exp(-c tau) (0 when the current loop is ideal)
        double r1;  // int_0^tau exp(-a (tau - s)) exp(-c s) ds
        double r2;  // int_0^tau r1(s) ds
    };
    Span span(double tau) const;
    State moving(const State& x, const Span& k, double dir) const;
    State stuck(const State& x, const Span& k) const;
    double crossing_time(const State& x, double dir, double left) const;
    void control(double h);
    void integrate(double h);
    // Whether a substep of h_ would leave every member as it is: see step().
    bool resting_unpowered() const;
    std::int64_t count_of(double p) const;
    void derive();

    MotorParameters motor_;
    ControlGains gains_;
    // Derived from motor_ and gains_.
    double inertia_ = 0, a_ = 0, c_ = 0, peak_torque_ = 0, rad_per_count_ = 0;
    double counts_per_turn_ = 0;
    // Cached for the last dt.
    double cached_dt_ = -1, h_ = 0;
    unsigned n_ = 0;
    Span full_{};

    LoopMode mode_ = LoopMode::Off;
    double position_cmd_ = 0, velocity_ff_ = 0, torque_ff_ = 0;
    double limit_pos_ = 0, limit_neg_ = 0, load_ = 0;

    State x_{0, 0, 0};
    double current_cmd_ = 0;  // A, held over the substep
    double integral_ = 0;     // Nm, velocity loop integrator
    bool limited_ = false;
    std::int64_t last_count_ = 0;
    double last_h_ = 0;  // length of the substep since last_count_ (0: no sample yet)

    // The last substep was a fixed point for the inputs as they are now (see substeps_run); any change of
    // an input (command, limits, load, gains, position, faults, the substep's length) clears it.
    bool fixed_ = false;
    std::uint64_t substeps_run_ = 0;

    bool encoder_fault_ = false;
    std::int64_t frozen_count_ = 0;
    bool overcurrent_injected_ = false;
    double i2t_ = 0;
};

}  // namespace vecat::cia402
