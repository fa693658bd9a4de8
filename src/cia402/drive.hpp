// The CiA 402 drive: the application of a CoE slave (coe::CoeApplication) that acts on its dictionary.
// Every servo period (250 us of simulated time) it reads the controlword and the set-points from the
// dictionary, runs the device control state machine and the active operation mode, steps the simulated
// mechanics, and writes statusword and actual values back. Time comes from the slave (frames, SYNC0 and
// timer ticks); the simulation advances in fixed periods, so it is deterministic for a given cycle time.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include "cia402/factor_group.hpp"
#include "cia402/mechanics.hpp"
#include "cia402/profile_generator.hpp"
#include "cia402/state_machine.hpp"
#include "cia402/touch_probe.hpp"
#include "cia402/twinsync_port.hpp"
#include "coe/coe_application.hpp"
#include "twinsync/status.hpp"

namespace vecat::cia402 {

class Homing;

// Modes of operation (0x6060/0x6061), protocol/cia402.hpp.
using protocol::cia402::Mode;
bool supported(Mode m) noexcept;

// 0x603F error codes the drive raises (IEC 61800-7-201 / CiA 402 error code table).
namespace fault {
inline constexpr std::uint16_t OverCurrent = 0x2310;     // continuous over current
inline constexpr std::uint16_t Encoder = 0x7305;         // incremental sensor 1 fault
inline constexpr std::uint16_t FollowingError = 0x8611;  // following error
inline constexpr std::uint16_t ReferenceLimit = 0x8612;  // reference limit (limit switch reached)
bool injectable(std::uint16_t code) noexcept;
}  // namespace fault

// Statusword bits (CiA 402 6.3.3), protocol/cia402.hpp.
namespace sw = protocol::cia402::sw;

class Drive : public coe::CoeApplication {
    friend std::shared_ptr<twinsync::Channel> connect_twinsync(Drive&, Drive&, double, double);

  public:
    static constexpr std::uint64_t kServoPeriodNs = 250'000;

    // objects: see CoeApplication.
    explicit Drive(const device::DeviceDescription& d,
                   std::shared_ptr<const std::vector<device::ObjectDescription>> objects = {});
    ~Drive() override;

    State cia402_state() const { return sm_.state(); }
    Mode mode() const { return mode_; }
    const Mechanics& mechanics() const { return *mech_; }
    // Demand and actual values in user units (as in 0x6062/0x6064, without the 32-bit wrap).
    double position_demand() const { return demand_.p; }
    double position_actual() const { return actual_user_; }
    double velocity_actual() const { return velocity_user_; }
    std::uint64_t servo_steps() const { return steps_; }
    std::uint64_t simulated_time_ns() const { return sim_ns_; }
    // The TWINsync option card of this drive, and its status (nullptr when no cable is connected).
    twinsync::Port& twinsync_port() { return *twin_; }
    const twinsync::LinkStatus* twinsync_status() const {
        return twin_->channel() ? &twin_->status() : nullptr;
    }
    // The TWINsync error the drive has raised as a fault (40-xx, 39-xx), if any.
    std::optional<twinsync::ErrorId> twinsync_error() const { return twin_error_; }

    // esc::Application
    void tick(std::uint64_t now_ns) override;

    // The dictionary entries the drive uses, bound once (drive.cpp).
    struct Objects;

  protected:
    void cycle(std::uint64_t now_ns, bool outputs_applied) override;

  private:
    void advance(std::uint64_t now_ns);
    void step_to(std::uint64_t t_ns);
    void servo_step();
    void read_configuration();
    void apply_gains();
    void update_inputs();
    void run_mode(double dt);
    void run_profile_position(double dt);
    void run_profile_velocity(double dt);
    void run_torque(double dt, bool profile);
    void run_homing(double dt);
    void run_cyclic_position(double dt);
    void run_cyclic_velocity(double dt);
    void run_stop(StopKind k, double dt);
    void run_twinsync(double dt);
    void run_decoupled(double dt);
    void hold_for_coupling();
    twinsync::LocalState twinsync_local() const;
    void write_twinsync_values();
    void enter_twinsync_fault(twinsync::ErrorId e);
    void run_touch_probe(double previous_inc, double machine_inc);
    bool blocked(double direction) const;
    void start_move(double target);
    void hold_disabled();
    void check_faults(double dt);
    void enter_fault(std::uint16_t code, std::uint8_t register_bits);
    void write_feedback();
    void on_mode_change();
    ProfileLimits profile_limits() const;
    double max_velocity() const;
    double interpolation_period() const;
    double clamp_to_software_limits(double p) const;
    bool software_limits_enabled() const;
    double machine_increments() const;  // motor position in encoder increments (homing does not move it)
    // From the dictionary by read_configuration(), before the servo steps of each advance.
    double standstill_velocity() const { return standstill_velocity_; }
    double nm_per_permille() const { return nm_per_permille_; }
    double user_to_rad(double user) const { return ratios_.user_to_radians(user - home_shift_); }
    double rad_to_user(double rad) const { return ratios_.radians_to_user(rad) + home_shift_; }
    double user_velocity_to_rad(double v) const { return ratios_.user_to_radians(v); }

    std::unique_ptr<Objects> o_;
    StateMachine sm_;
    OptionCodes options_;
    FactorGroup factors_;
    FactorRatios ratios_ = factors_.ratios();  // kept with factors_
    double nm_per_permille_ = 1e-3;
    double standstill_velocity_ = 10.0;
    std::unique_ptr<Mechanics> mech_;
    ProfileGenerator profile_;
    std::unique_ptr<Homing> homing_;
    Mode mode_ = Mode::None;

    std::uint64_t sim_ns_ = 0;
    bool started_ = false;
    std::uint64_t steps_ = 0;

    // Set-points and the demand sent to the loops.
    Kinematics demand_;  // position demand (user units)
    LoopMode loop_ = LoopMode::Off;
    double velocity_cmd_ = 0;  // user units/s (velocity modes)
    double torque_cmd_ = 0;    // per mille of rated torque (torque modes)
    double torque_ff_ = 0;     // per mille

    // Actual values.
    double actual_user_ = 0;
    double velocity_user_ = 0;
    double home_shift_ = 0;  // user position = machine position (converted) + home_shift_
    std::int64_t increments_ = 0;
    double inertia_ = 0;          // kg m^2, for the acceleration feed-forward
    double temperature_ = 350.0;  // 0.1 C

    // Controlword edges and profile position handshake.
    std::uint16_t controlword_ = 0;
    std::uint16_t previous_controlword_ = 0;
    bool setpoint_ack_ = false;
    std::optional<double> pending_target_;  // set of set-points: buffered next target
    bool pp_moving_ = false;
    double pp_target_ = 0;
    bool halted_ = false;
    std::uint32_t override_ppm_ = 1'000'000;
    StopKind stopping_ = StopKind::None;  // the stop ramp being executed
    double pv_target_ = 0;
    bool pv_running_ = false;
    bool cyclic_following_ = false;
    std::uint16_t homing_bits_ = 0;  // statusword bits 10, 12, 13 from the homing method
    bool homing_active_ = false;
    bool homing_error_ = false;   // the method could not start (unsupported method, bad speeds)
    double homing_velocity_ = 0;  // velocity the profile runs at for the homing method

    // Cyclic modes: interpolation between the last two set-points.
    double csp_from_ = 0, csp_to_ = 0;
    std::int32_t csp_raw_ = 0;
    double csp_since_ = 0;  // s since the latest set-point arrived
    bool csp_valid_ = false;

    // Windows and timers (s).
    double following_error_ = 0;
    double following_error_time_ = 0;
    double position_window_time_ = 0;
    double velocity_window_time_ = 0;
    double speed_zero_time_ = 0;
    bool internal_limit_ = false;

    // Switches, index pulse and touch probe.
    bool negative_limit_ = false, positive_limit_ = false, home_switch_ = false;
    std::uint8_t probe_inputs_ = 0;
    double previous_machine_inc_ = 0;
    TouchProbe probe_;

    // Faults.
    std::uint16_t active_fault_ = 0;

    // TWINsync: the option card, the coupling of a slave drive to its master drive, and decoupling in
    // motion (the axis goes on at its velocity until it is stopped or given a new set-point).
    std::unique_ptr<twinsync::Port> twin_;
    Drive* twin_partner_ = nullptr;  // the drive at the other end of the cable (steps in lockstep)
    std::optional<twinsync::ErrorId> twin_error_;
    bool coupled_ = false;
    std::int32_t twin_master_last_ = 0;  // master position at the previous cycle (PCON increments)
    std::uint16_t twin_control_ = 0, previous_twin_control_ = 0;
    bool continuing_ = false, continue_halting_ = false;
    double continue_velocity_ = 0;
    std::int32_t continue_target_position_ = 0, continue_target_velocity_ = 0;
    bool homed_ = false;
};

// Connects the TWINsync option cards of two drives by a cable (a: end 0, b: end 1). Their oscillators
// differ by the given ppm, which the slave's synchronisation controller has to follow.
std::shared_ptr<twinsync::Channel> connect_twinsync(Drive& a, Drive& b, double ppm_a = 20.0,
                                                    double ppm_b = -20.0);

// Ready-made TWINsync set-ups of the first two drives of a line (`vecat run --twinsync ...`).
enum class TwinsyncPreset { None, Gantry, Position, Speed };
// Writes the parameters of both drives (drive a master, drive b slave controlled through TWINsync).
void apply_twinsync_preset(Drive& master, Drive& slave, TwinsyncPreset p);

// A segment of n drives; drives 1 and 2 (if there are two) are connected by a TWINsync cable, with the
// preset applied.
std::unique_ptr<esc::Segment> make_drive_segment(const device::DeviceDescription& d, std::size_t n,
                                                 const esc::EscConfig& cfg, TwinsyncPreset preset);
std::unique_ptr<esc::Segment> make_drive_segment(const device::DeviceDescription& d, std::size_t n,
                                                 const esc::EscConfig& cfg = {});
// The same from a model built once (esc::DeviceModel::of).
std::unique_ptr<esc::Segment> make_drive_segment(const esc::DeviceModel& m, std::size_t n,
                                                 const esc::EscConfig& cfg = {},
                                                 TwinsyncPreset preset = TwinsyncPreset::None);

}  // namespace vecat::cia402
