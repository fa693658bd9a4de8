// The CiA 402 drive core, without EtherCAT: one servo period on a typed DriveIo (drive_io.hpp). The CoE
// adapter (cia402::Drive) copies the dictionary into the DriveIo before each period and the feedback back
// after it; a test or another fieldbus could drive the core the same way.
//
// A servo period (DriveCore::step, CiA 402 / IEC 61800-7-201):
//   1. the controlword (0x6040, or TWINsync's), the limit switches and inputs;
//   2. fault monitoring: injected faults, encoder, I2t over-current, following error, limit switch reaction,
//      TWINsync errors;
//   3. the device control state machine (state_machine.hpp) with the option codes 0x605A-0x605E;
//   4. the mode of operation 0x6060 (shown in 0x6061 once it took effect), the set-points: disabled, a stop
//      ramp, following TWINsync, decoupled motion, or the active mode (profile_modes, homing_mode,
//      cyclic_modes: one class per mode, with its statusword bits);
//   5. the loops and the simulated motor (mechanics.hpp), the touch probe;
//   6. the feedback: statusword, actual values, TWINsync values.
#pragma once

#include <array>
#include <cstdint>
#include <memory>

#include "cia402/cyclic_modes.hpp"
#include "cia402/drive_io.hpp"
#include "cia402/homing_mode.hpp"
#include "cia402/mechanics.hpp"
#include "cia402/operation_mode.hpp"
#include "cia402/profile_modes.hpp"
#include "cia402/state_machine.hpp"
#include "cia402/touch_probe.hpp"
#include "cia402/twinsync_coupling.hpp"

namespace vecat::cia402 {

class DriveCore {
  public:
    static constexpr std::uint64_t kPeriodNs = Axis::kPeriodNs;

    explicit DriveCore(const MotorParameters& motor);
    ~DriveCore();
    DriveCore(const DriveCore&) = delete;
    DriveCore& operator=(const DriveCore&) = delete;

    // Once before the periods of an advance: option codes, factor group, rated torque, threshold.
    void configure(const DriveIo& io);
    // Before the first period: the inputs and the feedback of the drive as it starts.
    void start(DriveIo& io);
    // One servo period. With publish false, the feedback's values (positions, velocities, torques, the
    // statusword...) are not worked out: a caller that runs several periods in a row and shows only the
    // last one's values asks for them in the last. The period's events (faults raised and cleared, probe
    // latches, the TWINsync values) and the state behind the values (the status bits' timers, the
    // temperature) are the same either way, so the last period's values are too.
    //
    // A period that finds the core and the DriveIo as a settled period left them is skipped: it would do
    // the same again (drive_core.cpp, "Settled"). The results are the same bits either way.
    void step(DriveIo& io, bool publish = true);
    // The next period, for a caller that knows nothing wrote the DriveIo's inputs since the last period
    // (cia402::Drive between the periods of one advance): skipped if the core is settled, without comparing
    // the inputs; false, and nothing done, if step() has to run it.
    bool skip_unchanged_period(DriveIo& io, bool publish);
    // The servo period, the speed control's sampling time (the TWIN sampling time of P0302 on a drive
    // with the TWINsync parameters: 250 us, 125 us at 8 kHz). kPeriodNs until set.
    void set_period_ns(std::uint64_t ns);
    std::uint64_t period_ns() const { return period_ns_; }

    // Position compensation 0x2111 (TwinCAT NC PTP 2.5): the move ends at its target plus the achievable
    // part of `distance`, spread over `length`, with the compensation's dynamics (a 0 field: the move's).
    void compensate(double distance, double length, const CompensationLimits& limits = {});
    // Compensation stop 0x2111:8 (TX1250 2.5).
    void stop_compensation();
    // The actual position reads 0 from now on (HIWIN 0x2060 0->1, multi-turn position to zero).
    void zero_position();

    State state() const { return sm_.state(); }
    Mode mode() const { return mode_; }
    const Mechanics& mechanics() const { return mech_; }
    double position_demand() const { return axis_.demand.p; }
    double position_actual() const { return axis_.actual; }
    double velocity_actual() const { return axis_.velocity; }
    std::uint64_t steps() const { return steps_; }
    // Of those, the periods skipped because the drive had settled (for tests and benchmarks).
    std::uint64_t skipped_steps() const;
    // Off: every period runs (a test's twin to compare the skipping with).
    void skip_settled_periods(bool on);
    std::optional<twinsync::ErrorId> twinsync_error() const { return coupling_.error(); }
    // The drive's state for the TWINsync port (before and after a period).
    twinsync::LocalState twinsync_local(std::uint16_t own_controlword, bool synchronised) const;

  private:
    void catch_up_skipped();  // the hold timers' time of the periods skipped while settled
    void wake();              // before a public method changes the core: catch up, compare its bytes again
    bool skippable(const DriveIo& io) const;  // a settled period that need not run (drive_core.cpp)
    void skip(DriveIo& io, bool publish);     // ... skipped: the period count, the timers, the temperature
    void update_inputs(DriveIo& io);
    void check_faults(DriveIo& io, double dt);
    void raise(DriveIo& io, const RaisedFault& f);
    void run_state_machine(DriveIo& io);
    void select_mode(const DriveCommand& c);
    void on_mode_change();
    void run_setpoints(DriveIo& io, double dt);
    void run_mode(double dt);
    void run_stop(StopKind k, double dt);
    void hold_disabled();
    void apply_gains(const DriveParameters& p);
    void run_mechanics(const DriveIo& io, double dt);
    void run_touch_probe(DriveIo& io, double previous_inc, double machine_inc);
    void write_feedback(DriveIo& io, bool publish = true);
    void heat(const DriveParameters& p, double dt);  // the drive temperature, one period
    double machine_increments() const;  // motor position in encoder increments (homing does not move it)
    double user_to_rad(double user) const { return axis_.ratios.user_to_radians(user - axis_.home_shift); }

    StateMachine sm_;
    FactorGroup factors_;  // the last valid factor group
    Mechanics mech_;
    Axis axis_;
    TouchProbe probe_;
    TwinsyncCoupling coupling_;

    // The operation modes; `active_` is the one of mode_ (nullptr: none selected yet).
    ProfilePositionMode pp_;
    ProfileVelocityMode pv_;
    ProfileTorqueMode pt_;
    HomingMode hm_;
    CyclicPositionMode csp_;
    CyclicVelocityMode csv_;
    CyclicTorqueMode cst_;
    std::array<OperationMode*, 7> modes_{&pp_, &pv_, &pt_, &hm_, &csp_, &csv_, &cst_};
    Mode mode_ = Mode::None;
    OperationMode* active_ = nullptr;
    bool modes_disabled_ = false;         // every mode's disable() ran, and no step since
    bool state_machine_stopped_ = false;  // a stop of the state machine ran (its ramp is in axis_.stopping)

    std::uint64_t steps_ = 0;

    std::uint64_t period_ns_ = kPeriodNs;
    std::uint32_t override_ppm_ = 1'000'000;
    std::int64_t increments_ = 0;
    double previous_machine_inc_ = 0;  // the machine position the encoder measured last
    // The actual values are measured: false from an encoder fault (0x7305) until the fault reset.
    bool encoder_valid_ = true;
    std::uint8_t probe_inputs_ = 0;
    HoldTimer speed_zero_;        // standing (0x6070)
    double temperature_ = 350.0;  // 0.1 C
    std::uint16_t active_fault_ = 0;

    // The fixed point of a settled drive and the periods skipped at it (drive_core.cpp).
    class Settled;
    std::array<HoldTimer*, 5> timers_{&speed_zero_, &axis_.following_error_time, &pp_.window_timer(),
                                      &pv_.window_timer(), &csp_.setpoint_timer()};
    std::unique_ptr<Settled> settled_;
};

}  // namespace vecat::cia402
