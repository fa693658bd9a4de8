// The profile modes (CiA 402 / IEC 61800-7-201 clause 6): the drive plans the motion itself with its
// profile generator (profile position, profile velocity) or ramps the torque (profile torque).
#pragma once

#include <optional>

#include "cia402/operation_mode.hpp"

namespace vecat::cia402 {

// Profile position (PP, mode 1): controlword bit 4 "new set-point" with the set-point acknowledge of
// statusword bit 12; single set-point or set of set-points (one buffered, bit 5 "change set immediately"
// replaces the move), relative (bit 6), change on set-point (bit 9), halt (bit 8). Target reached (bit 10)
// once the position window 0x6067 held for 0x6068 ms; bit 13 following error.
class ProfilePositionMode final : public OperationMode {
  public:
    ProfilePositionMode() : OperationMode(true) {}
    void reset() override;
    void disable() override;
    void step(Axis& a, double dt) override;
    ModeStatus status(const Axis& a, const StatusInputs& in) override;
    HoldTimer& window_timer() { return position_window_time_; }  // 0x6068

    // A move is under way (position compensation 0x2111 then moves its target).
    bool moving() const { return moving_; }
    void set_target(double t) { target_ = t; }

  private:
    // The target of a new set-point (relative, modulo), or nothing when it is refused (0x607D, 0x2112).
    std::optional<double> accept(Axis& a, std::uint16_t controlword);
    void start_move(Axis& a, double target);
    // TX1250 2.4, new velocity and new end position: the six cases of APos (0x2114:1) and the new end
    // position against the axis, along the direction of the positioning.
    void new_velocity_and_end_position(Axis& a, double end_position);

    bool setpoint_ack_ = false;             // statusword bit 12
    bool refused_ = false;                  // the last set-point was beyond 0x607D: bit 11
    std::optional<double> pending_target_;  // set of set-points: the buffered next target
    bool moving_ = false;
    double target_ = 0;  // kept across modes: a relative move adds to the last target
    HoldTimer position_window_time_;
    std::optional<double> velocity_;  // the move's velocity instead of 0x6081 (TX1250 2.4: VNew)
    // TX1250 2.4 case 1: VNew once the axis crosses APos moving in direction activation_dir_.
    std::optional<double> activation_;
    double activation_dir_ = 1, activation_velocity_ = 0;
};

// Profile velocity (PV, mode 3): target velocity 0x60FF through the profile generator. Bit 10 once the
// velocity stayed in the window 0x606D for 0x606E ms; bit 12 speed zero (0x606F for 0x6070 ms).
class ProfileVelocityMode final : public OperationMode {
  public:
    ProfileVelocityMode() : OperationMode(true) {}
    void reset() override { running_ = false; }
    void disable() override { running_ = false; }
    void step(Axis& a, double dt) override;
    ModeStatus status(const Axis& a, const StatusInputs& in) override;
    HoldTimer& window_timer() { return velocity_window_time_; }  // 0x606E

  private:
    double target_ = 0;
    bool running_ = false;
    HoldTimer velocity_window_time_;
};

// Profile torque (PT, mode 4): target torque 0x6071 reached at the torque slope 0x6087; bit 10 when the
// demand has reached it. Halt does not apply.
class ProfileTorqueMode final : public OperationMode {
  public:
    ProfileTorqueMode() : OperationMode(false) {}
    void step(Axis& a, double dt) override;
    ModeStatus status(const Axis& a, const StatusInputs& in) override;
};

// Both torque modes: the torque demand towards `target` (profile: at the slope), and the speed limit.
void torque_step(Axis& a, double target, bool profile, double dt);

}  // namespace vecat::cia402
