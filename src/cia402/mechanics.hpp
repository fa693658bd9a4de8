// The simulated mechanics of one axis: a servo motor with torque constant, rotor and load inertia, viscous
// and Coulomb friction, an incremental/absolute encoder, and the drive's cascaded position, velocity and
// current loops. Deterministic for a given step size. SI units on the motor side (rad, rad/s, Nm, A).
#pragma once

#include <cstdint>

namespace vecat::cia402 {

struct MotorParameters {
    double torque_constant = 0.6;   // Nm/A
    double rotor_inertia = 1.2e-5;  // kg m^2
    double load_inertia = 2.4e-5;   // kg m^2 (reflected to the motor)
    double viscous_friction = 5e-5; // Nm s/rad
    double coulomb_friction = 0.01; // Nm
    double rated_current = 3.0;     // A
    double peak_current = 9.0;      // A
    unsigned encoder_bits = 20;     // increments per revolution = 2^bits
};

struct ControlGains {
    double position_kp = 100.0;      // 1/s: velocity command per position error
    double velocity_kp = 0.05;       // Nm s/rad
    double velocity_ti = 0.01;       // s, integral time of the velocity loop
    double current_bandwidth = 2000; // rad/s, first-order current loop
};

enum class LoopMode : std::uint8_t { Off, Position, Velocity, Torque };

class Mechanics {
  public:
    Mechanics(const MotorParameters& m = {}, const ControlGains& g = {});
    // Set-points for the loops; feed-forwards are added to the loop outputs.
    void command(LoopMode mode, double position, double velocity_ff, double torque_ff);
    void set_torque_limits(double positive, double negative);  // Nm, magnitudes
    void set_load_torque(double nm);                           // external load
    void step(double dt);                                      // s
    double position() const;        // rad, true mechanical position (multi-turn)
    std::int64_t encoder() const;   // increments, quantised
    double velocity() const;        // rad/s
    double torque() const;          // Nm (electromagnetic)
    double current() const;         // A
    bool torque_limited() const;
};

}  // namespace vecat::cia402
