// The cyclic synchronous modes (CiA 402 / IEC 61800-7-201 6.10-6.12): the master's trajectory generator
// sends a set-point every cycle and the drive follows it; statusword bit 12 "drive follows the command
// value" (cleared by an internal limit and by halt).
#pragma once

#include <cstdint>

#include "cia402/operation_mode.hpp"

namespace vecat::cia402 {

// Cyclic synchronous position (CSP, mode 8): 0x607A + 0x60B0 interpolated linearly over the interpolation
// period 0x60C2, velocity and torque offsets 0x60B1/0x60B2 as feed-forward. Bit 10 with the position
// window 0x6067 around the set-point, bit 13 following error.
class CyclicPositionMode final : public OperationMode {
  public:
    CyclicPositionMode() : OperationMode(true) {}
    void reset() override { valid_ = false; }
    void disable() override { valid_ = false; }
    void step(Axis& a, double dt) override;
    ModeStatus status(const Axis& a, const StatusInputs& in) override;
    HoldTimer& setpoint_timer() { return since_; }

  private:
    // Interpolation between the last two set-points.
    double from_ = 0, to_ = 0;
    std::int32_t raw_ = 0;
    HoldTimer since_;  // since the latest set-point arrived
    bool valid_ = false;
};

// Cyclic synchronous velocity (CSV, mode 9): 0x60FF + 0x60B1, torque offset 0x60B2 as feed-forward.
class CyclicVelocityMode final : public OperationMode {
  public:
    CyclicVelocityMode() : OperationMode(true) {}
    void step(Axis& a, double dt) override;
    ModeStatus status(const Axis& a, const StatusInputs& in) override;
};

// Cyclic synchronous torque (CST, mode 10): 0x6071 + 0x60B2. Halt does not apply.
class CyclicTorqueMode final : public OperationMode {
  public:
    CyclicTorqueMode() : OperationMode(false) {}
    void step(Axis& a, double dt) override;
    ModeStatus status(const Axis& a, const StatusInputs& in) override;
};

}  // namespace vecat::cia402
