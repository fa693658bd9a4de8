// Homing mode (CiA 402 / IEC 61800-7-201, 0x6098 methods 1-14, 17-30, 33, 34, 35, 37): a state machine
// that, cycle by cycle, turns the switch and index signals into velocity commands and finally reports the
// home position it found.
//
// Pure model: no EtherCAT, no profile generator, no mechanics. The drive calls start() when homing begins
// (controlword bit 4 rising edge in homing mode), then update() once per cycle with the actual position,
// velocity and switch inputs, and ramps its velocity to HomingOutput::velocity with
// HomingOutput::acceleration. Positions are in whatever unit the caller uses (the drive: user units).
//
// How the methods search (the CiA 402 diagrams; "rising": the switch becomes active while crossing it):
//   1/17   negative limit switch, falling edge moving positive
//   2/18   positive limit switch, falling edge moving negative
//   3/19   home switch active on the positive side, falling edge moving negative
//   4/20   home switch active on the positive side, rising edge moving positive
//   5/21   home switch active on the negative side, falling edge moving positive
//   6/22   home switch active on the negative side, rising edge moving negative
//   7/23   window home switch, lower edge, falling moving negative
//   8/24   window home switch, lower edge, rising moving positive
//   9/25   window home switch, upper edge, rising moving negative
//   10/26  window home switch, upper edge, falling moving positive
//   11/27  window home switch, upper edge, falling moving positive
//   12/28  window home switch, upper edge, rising moving negative
//   13/29  window home switch, lower edge, rising moving positive
//   14/30  window home switch, lower edge, falling moving negative
// 7-10 start moving positive and reverse once at the positive limit switch, 11-14 start negative and
// reverse once at the negative limit switch (while the home switch has not been seen); when the home
// switch is active at the start they move straight towards the wanted edge. 1-14: the home position is the
// first index pulse beyond the edge in the final direction; 17-30: the edge itself. 33/34: the first index
// pulse in the negative/positive direction. 35/37: the current position, no motion.
//
// Speeds: speed_switch (0x6099:01) until the reference switch has changed state once; after that every move
// runs at speed_zero (0x6099:02). An edge counts only when it is crossed at no more than 1.5 x speed_zero in
// the final direction; when it was crossed faster (the first, fast encounter), the axis backs off at
// speed_zero and approaches the edge again, so edges are always taken at the slow speed. The index search
// (methods 1-14, 33, 34) runs at speed_zero.
//
// Signals are sampled once per cycle: an edge is captured at the first actual position past it (at most one
// cycle's travel late); index pulses are computed from index_period/index_phase and interpolated exactly
// between two successive actual positions.
//
// Limit switches: a limit switch that is active in the direction of the commanded motion is a homing error
// unless it is the method's reference signal (1, 2, 17, 18) or the reversal switch of methods 7-14/23-30
// while the home switch has not been found yet. Reaching the second limit switch without having seen the home
// switch (7-14, 23-30) is an error too.
//
// Home offset (0x607C): CiA 402 calls it "the difference between the zero position for the application and
// the machine home position" and says the zero position is found "by adding the home offset to the home
// position". Taken literally that puts the zero at home + offset, so the home position would read as
// -offset; drive manuals are not consistent about the sign. This model uses the other reading, the one in
// the project's brief: once homing is attained, the position actual value at the home position reads as the
// home offset, so the value a user writes to 0x607C is the value 0x6064 shows at the reference point:
//   position_after_homing = raw_position - home_position + home_offset  (see position_shift()).
// The sign lives in position_shift() only.
// The drive applies the shift; Homing ignores positions once the home position is found, so the drive may
// switch its coordinates in the very cycle in which HomingOutput::home_found is set.
#pragma once

#include <cstdint>

namespace vecat::cia402 {

// Switch inputs as the drive samples them each cycle (true = active).
struct HomingSignals {
    bool negative_limit = false;
    bool positive_limit = false;
    bool home_switch = false;
};

struct HomingParameters {
    double speed_switch = 0;  // 0x6099:01, speed during search for switch (> 0)
    double speed_zero = 0;    // 0x6099:02, speed during search for zero (> 0)
    double acceleration = 0;  // 0x609A, homing acceleration (> 0)
    double home_offset = 0;   // 0x607C
    // Index pulses at k * index_period + index_phase (one per motor revolution). index_period > 0 is
    // required by the methods that use the index pulse (1-14, 33, 34).
    double index_period = 0;
    double index_phase = 0;
    // |velocity| at or below this counts as standing still (statusword bit 10); 0: 1 % of speed_zero.
    double standstill_velocity = 0;
};

enum class HomingStatus : std::uint8_t {
    NotStarted,   // never started
    InProgress,   // searching
    Interrupted,  // halt() or abort() before the home position was found
    Attained,     // home position found (the axis may still be braking: see target_reached)
    Error,        // see HomingFault
};

enum class HomingFault : std::uint8_t {
    None,
    LimitSwitch,         // a limit switch was reached where the method does not allow it
    HomeSwitchNotFound,  // 7-14, 23-30: both directions searched up to the limit switches
    IndexNotFound,       // no index pulse within 2 index periods after the edge (a guard: with pulses
                         // computed from index_period it cannot happen)
};

// What the drive should do this cycle.
struct HomingOutput {
    double velocity = 0;      // signed velocity to run at; 0: stop
    double acceleration = 0;  // magnitude of the acceleration/deceleration of the ramp to `velocity`
    HomingStatus status = HomingStatus::NotStarted;
    bool target_reached = false;  // statusword bit 10 as statusword_bits() reports it
    bool home_found = false;      // true in exactly one update(): the one in which the home was found
    double home_position = 0;     // the (raw) actual position of the reference event, valid once found
};

// Statusword bits of homing mode.
namespace homing_status_bits {
constexpr std::uint16_t TargetReached = 1u << 10;
constexpr std::uint16_t HomingAttained = 1u << 12;
constexpr std::uint16_t HomingError = 1u << 13;
constexpr std::uint16_t Mask = TargetReached | HomingAttained | HomingError;
}  // namespace homing_status_bits

class Homing {
  public:
    // true for the methods this model implements: 1-14, 17-30, 33, 34, 35, 37.
    static bool supported(int method);
    // Whether the method uses the index pulse (1-14, 33, 34).
    static bool uses_index(int method);

    // Starts a homing procedure from actual_position (assumed at rest until the first update()). false,
    // and nothing changes, for an unsupported method or unusable parameters (non-positive or non-finite
    // speeds or acceleration; index_period <= 0 for a method with index pulse). Methods 35 and 37 are
    // attained at once at actual_position; the next update() reports home_found.
    bool start(int method, const HomingParameters& p, double actual_position);
    // One drive cycle.
    HomingOutput update(double actual_position, double actual_velocity, const HomingSignals& s);
    // Controlword bit 8 (halt): the search stops with the homing acceleration; status Interrupted.
    // No effect once the home position is found or after an error.
    void halt();
    // Controlword bit 4 falling edge, or the drive leaves homing mode / operation enabled: the search ends
    // at once (status Interrupted); update() commands velocity 0 from now on. No effect once the home
    // position is found or after an error.
    void abort();

    HomingStatus status() const { return status_; }
    HomingFault fault() const { return fault_; }
    int method() const { return method_; }
    // Statusword bit 10 in homing mode: at standstill (last actual velocity) when not in progress.
    bool target_reached() const;
    // Bits 10, 12, 13 of the statusword (homing_status_bits) per the CiA 402 table:
    //   0/0/0 in progress, 0/0/1 interrupted or not started, 0/1/0 attained but target not reached,
    //   0/1/1 completed, 1/0/0 error with velocity != 0, 1/0/1 error with velocity 0  (bits 13/12/10).
    std::uint16_t statusword_bits() const;
    // The raw actual position of the reference event (valid once Attained).
    double home_position() const { return home_position_; }
    // Added to a raw position once homed: home_offset - home_position (see the header comment).
    double position_shift() const { return params_.home_offset - home_position_; }

  private:
    // How a method searches; regions relative to the reference signal: -1 below (the inactive side on the
    // negative side), 0 inside (active), +1 above.
    enum class Reference : std::uint8_t {
        None,
        NegativeLimit,
        PositiveLimit,
        HomeAbove,
        HomeBelow,
        HomeWindow
    };
    struct Method {
        Reference reference = Reference::None;
        int final_dir = 0;       // direction of the final crossing and of the index search
        bool rising = false;     // the final crossing makes the reference active
        int initial_dir = 0;     // HomeWindow: search direction while the home switch is unknown
        bool index = false;      // home at the first index pulse after the edge
        bool immediate = false;  // 35, 37
    };
    enum class Phase : std::uint8_t { Idle, Edge, Index, Stop };

    static bool describe(int method, Method& m);
    bool reference_active(const HomingSignals& s) const;
    int region_after_change(bool active, int moving) const;
    int pre_region() const { return method_info_.rising ? -method_info_.final_dir : 0; }
    int post_region() const { return method_info_.rising ? 0 : method_info_.final_dir; }
    void step(double pos, double vel, const HomingSignals& s);
    bool search_index(double pos);
    void found(double home);
    void fail(HomingFault f);
    double standstill() const;

    int method_ = 0;
    Method method_info_{};
    HomingParameters params_{};
    HomingStatus status_ = HomingStatus::NotStarted;
    HomingFault fault_ = HomingFault::None;
    Phase phase_ = Phase::Idle;
    bool primed_ = false;    // the first update() after start() has seen the signals
    bool searching_ = true;  // the reference signal has not changed state yet: speed_switch
    bool signal_ = false;    // last state of the reference signal
    bool region_known_ = false;
    int region_ = 0;
    int search_dir_ = 0;  // HomeWindow while the region is unknown
    int reversals_ = 0;
    int command_dir_ = 0;
    double command_velocity_ = 0;
    double prev_position_ = 0;
    double index_from_ = 0;  // the index search starts beyond this position
    double home_position_ = 0;
    double last_velocity_ = 0;
    bool event_pending_ = false;
};

}  // namespace vecat::cia402
