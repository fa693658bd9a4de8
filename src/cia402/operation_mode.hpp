// What the operation modes act on, and the interface they share (CiA 402 / IEC 61800-7-201 clause 6:
// each mode turns the set-points of its objects into the demand of the control loops, and gives bits 10,
// 12 and 13 of the statusword their meaning).
//
// Axis is the set-point path of one axis: the profile generator, the demand handed to the loops (position
// demand, velocity or torque command, torque feed-forward), the stop ramps, and what the modes read of the
// drive (controlword edges, actual values, limit switches, the parameters of this period). DriveCore owns
// it; the modes (profile_modes, homing_mode, cyclic_modes) and the TWINsync coupling work on it.
#pragma once

#include <cstdint>

#include "cia402/drive_io.hpp"
#include "cia402/factor_group.hpp"
#include "cia402/mechanics.hpp"
#include "cia402/profile_generator.hpp"
#include "cia402/state_machine.hpp"

namespace vecat::cia402 {

// How long a condition has held, advanced by the servo periods: the window times of the statusword (0x6068,
// 0x606E, 0x6070), the following error timeout (0x6066), the time since the last cyclic set-point. It is
// read as "at least" or "more than" a time, and once such a read says yes it says yes as the time grows.
//
// That is what lets DriveCore skip the periods of a settled drive (drive_core.hpp, "Settled"): a timer that
// runs does not stop the drive from settling as long as every read of the period said yes. The skipped
// periods' time is added afterwards (catch_up), period by period as the steps would have added it.
class HoldTimer {
  public:
    // Once per period of the timer's owner, before its reads.
    void advance(bool held, double dt) {
        t_ = held ? t_ + dt : 0.0;
        running_ = held;
    }
    // The condition starts to hold anew (an advance follows in the same period).
    void restart() { t_ = 0.0; }
    bool at_least(double s) { return noted(t_ >= s); }
    bool more_than(double s) { return noted(t_ > s); }

    // For DriveCore's settled check: the period starts (no advance, no read yet).
    void begin_period() { running_ = said_no_ = false; }
    // The timer does not hold a period back from being a fixed point: it did not change, or it runs and
    // every read said yes.
    bool settled(double before) const { return running_ ? !said_no_ : t_ == before; }
    double seconds() const { return t_; }
    bool running() const { return running_; }
    // Add the time of `periods` skipped periods in which it ran (the same sum as those periods' advances;
    // DriveCore catches up once per advance, so these are a few).
    void catch_up(std::uint64_t periods, double dt) {
        for (; periods > 0; --periods)
            t_ += dt;
    }

  private:
    bool noted(bool yes) {
        said_no_ = said_no_ || !yes;
        return yes;
    }
    double t_ = 0;  // s
    bool running_ = false;
    bool said_no_ = false;
};

class Axis {
  public:
    static constexpr std::uint64_t kPeriodNs = 250'000;  // the servo period
    static constexpr double kPeriod = kPeriodNs * 1e-9;  // s
    // 0x60F2 bits 6/7, the rotary axis direction option (CiA 402 / ETG.6010 table 78).
    static constexpr unsigned kRotaryDirectionShift = 6;
    static constexpr unsigned kRotaryLinear = 0, kRotaryOnlyNegative = 1, kRotaryOnlyPositive = 2,
                              kRotaryShortest = 3;

    // The parameters and command of this period (the adapter's DriveIo; set by DriveCore).
    const DriveIo* io = nullptr;
    const DriveParameters& par() const { return io->parameters; }
    const DriveCommand& cmd() const { return io->command; }
    // Derived from the parameters once per advance (DriveCore::configure).
    FactorRatios ratios = FactorGroup{}.ratios();
    double nm_per_permille = 1e-3;      // rated torque 0x6076 / 1000
    double standstill_velocity = 10.0;  // 0x606F, at least one unit per second
    double inertia = 0;                 // kg m^2, motor and load, for the acceleration feed-forward

    // The controlword of this period (0x6040, or TWINsync's on a controlled slave) and of the previous.
    std::uint16_t controlword = 0;
    std::uint16_t previous_controlword = 0;
    bool rising(std::uint16_t bit) const { return (controlword & bit) && !(previous_controlword & bit); }

    // Actual values (user units), and the limit and home switches (0x60FD bits 0-2).
    double actual = 0;
    double velocity = 0;
    double home_shift = 0;  // user position = machine position (converted) + home_shift
    bool negative_limit = false, positive_limit = false, home_switch = false;
    double following_error = 0;      // demand - actual (position loop)
    HoldTimer following_error_time;  // outside the window 0x6065

    // The demand the loops follow.
    ProfileGenerator profile;
    Kinematics demand;  // position demand (user units)
    LoopMode loop = LoopMode::Off;
    double velocity_cmd = 0;  // user units/s (velocity loop)
    double torque_cmd = 0;    // per mille of rated torque (torque loop)
    double torque_ff = 0;     // per mille

    StopKind stopping = StopKind::None;  // the stop ramp being executed (none: following set-points)
    bool halted = false;            // controlword bit 8 in a mode that obeys it (last set by a mode step)
    bool internal_limit = false;    // statusword bit 11, this period
    bool cyclic_following = false;  // bit 12 of the cyclic modes: the drive follows the command value
    bool coupled = false;           // a TWINsync slave follows its master drive

    // Stops with a ramp, at the current or voltage limit (not Coast: that is DriveCore's hold_disabled).
    void stop(StopKind k, double dt);
    // A hardware limit switch blocks motion towards it (motion away from it is allowed).
    bool blocked(double direction) const {
        return (direction > 0 && positive_limit) || (direction < 0 && negative_limit);
    }
    // Max profile velocity 0x607F and max motor speed 0x6080, in user units/s.
    double max_velocity() const;
    // 0x6081, 0x6083, 0x6084, 0x60C5, 0x60C6, 0x6086, 0x60A4.
    ProfileLimits profile_limits() const;
    // Interpolation time period 0x60C2 (s), at least one servo period.
    double interpolation_period() const;
    // Software position limit 0x607D: on when min < max.
    bool software_limits_enabled() const;
    double software_limit_min() const { return par().software_limit_min.value_or(0); }
    double software_limit_max() const { return par().software_limit_max.value_or(0); }
    double clamp_to_software_limits(double p) const;
    // Position range limit 0x607B: a range narrower than INT32 (min < max) makes the axis modulo, of
    // length max - min (max is the same point as min); 0 when the axis is linear. Set from the parameters
    // by DriveCore::configure, once per advance.
    void set_position_range(std::int32_t min, std::int32_t max);
    double modulo_range() const { return modulo_range_; }
    bool modulo() const { return modulo_range_ > 0; }
    // A position as 0x6062/0x6064 show it: in [min, max) on a modulo axis, unchanged on a linear one.
    std::int64_t wrap_position(std::int64_t p) const { return modulo() ? wrap_in_range(p) : p; }
    // Where a profile position target of a modulo axis lies on the continuous axis, from position `from`,
    // by the rotary axis direction option of 0x60F2 (bits 6/7, CiA 402 / ETG.6010): 0 as a linear axis
    // within the range, 1 only negative, 2 only positive, 3 the shortest way (half a range: positive).
    // With only one direction a target beyond the range adds its whole ranges as turns (TX1250 2.1).
    double modulo_target(double target, double from) const;
    // The continuous position nearest to `from` of a position given in the range (cyclic set-points).
    double modulo_nearest(double target, double from) const;
    // Set by profile position when a target beyond 0x607D was refused with limit_reaction::Fault; the
    // core raises the fault and clears it.
    bool target_refused = false;
    double user_velocity_to_rad(double v) const { return ratios.user_to_radians(v); }

  private:
    std::int64_t wrap_in_range(std::int64_t p) const;
    double modulo_range_ = 0;
    std::int32_t range_min_ = 0;
};

// Statusword bits 10, 12 and 13 as the active mode defines them.
struct ModeStatus {
    bool target_reached = false;  // bit 10
    bool bit12 = false;
    bool bit13 = false;
};

// What the statusword of every mode may use, computed once per period by DriveCore.
struct StatusInputs {
    bool standing = false;            // |velocity| at most the threshold 0x606F
    HoldTimer* speed_zero = nullptr;  // standing
    bool following_error = false;     // the following error exceeded 0x6065 for longer than 0x6066
    double dt = Axis::kPeriod;
};

// One operation mode: its state, its servo period and its statusword bits in one place.
class OperationMode {
  public:
    // halt: controlword bit 8 stops the axis in this mode (not in the torque modes).
    explicit OperationMode(bool obeys_halt) : obeys_halt_(obeys_halt) {}
    virtual ~OperationMode() = default;
    bool obeys_halt() const { return obeys_halt_; }
    // A mode was selected or the drive entered OPERATION ENABLED: forget what the mode was doing.
    virtual void reset() {}
    // The drive function is off (or coasting): no set-point is pending.
    virtual void disable() {}
    // One servo period in OPERATION ENABLED: the demand of the loops from the mode's set-points.
    virtual void step(Axis& a, double dt) = 0;
    // Bits 10, 12, 13 while the mode runs in OPERATION ENABLED (the window timers advance here).
    virtual ModeStatus status(const Axis& a, const StatusInputs& in) = 0;

  private:
    bool obeys_halt_;
};

}  // namespace vecat::cia402
