// Set-point generator of the profile modes: a jerk-limited seven-phase motion profile (TwinCAT NC PTP,
// ../shared/seeds/002) or a trapezoid (jerk unlimited), from any current state, with online changes.
// Pure math in double precision, in whatever position unit the caller uses (the drive uses user units).
#pragma once

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

class ProfileGenerator {
  public:
    // Position move from the current state to target, ending at rest. Accepted while moving (new target,
    // new limits): when the new target was already overshot the profile stops and returns. false when the
    // limits are not usable (non-positive, NaN); the current plan then continues unchanged.
    bool move_to(double target, const ProfileLimits& lim);
    // Velocity profile: reach the signed velocity and hold it (profile velocity mode, homing searches).
    bool run_at(double velocity, const ProfileLimits& lim);
    // Brake to rest with the given deceleration and jerk (quick stop, halt); 0 jerk = no jerk limit.
    void stop(double deceleration, double jerk);
    // Velocity override as TwinCAT NC PTP describes it: fraction 0..1 of the commanded velocity (0 = stop),
    // applied online with the brake-phase rules of the manual. 1 by default.
    void set_override(double fraction);
    double override_fraction() const;
    // Position compensation (TwinCAT NC PTP 2.5): an extra distance d travelled within a length l of the
    // basic move. false when it cannot start (no move, stop phase, already compensating); when d is not
    // fully achievable the maximum possible compensation is carried out.
    bool compensate(double d, double l);
    // Forget every plan and stand at k (the drive follows the actual position while disabled).
    void reset(const Kinematics& k);
    // Advance by dt seconds and return the new demand.
    const Kinematics& step(double dt);
    const Kinematics& state() const;
    // Position moves: target reached and at rest. Velocity profiles: velocity reached.
    bool done() const;
    // The target of the current position move (or the current position).
    double target() const;
    // Closed-form duration of a rest-to-rest move over distance with these limits.
    static double rest_to_rest_duration(double distance, const ProfileLimits& lim);
};

}  // namespace vecat::cia402
