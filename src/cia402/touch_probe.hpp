// The touch probe function (CiA 402 / IEC 61800-7-201 touch probe, objects 0x60B8-0x60BD): two probes,
// each latching the position on the rising and/or falling edge of its input (the simulated machine's touch
// probe inputs) or of the motor's index pulse, once or continuously. Pure: the drive hands it the function
// 0x60B8, the inputs and the motor's travel over the servo period, and stores what it latched.
#pragma once

#include <cstdint>
#include <optional>

#include "cia402/factor_group.hpp"

namespace vecat::cia402 {

class TouchProbe {
  public:
    struct Period {
        std::uint16_t function = 0;  // 0x60B8: probe 1 in bits 0-7, probe 2 in bits 8-15
        std::uint8_t inputs = 0;     // touch probe inputs 1 (bit 0) and 2 (bit 1)
        double previous_inc = 0;     // machine position in increments at the start of the period
        double machine_inc = 0;      // ... and at its end
        double index_offset = 0;     // increments of the index pulse within a motor revolution
        // HIWIN guide 10: one probe, whose trigger is always the encoder's zero signal (Z phase).
        bool on_index_only = false;
    };
    // A value latched this period for 0x60BA-0x60BD: [probe][0 positive edge, 1 negative edge].
    struct Latched {
        bool set[2][2] = {};
        std::int32_t value[2][2] = {};
    };

    // One servo period; ratios and home_shift convert increments to the user position (as 0x6064).
    Latched step(const Period& p, const FactorRatios& ratios, double home_shift);
    std::uint16_t status() const { return status_; }  // 0x60B9
    // The first index pulse (one per revolution of `period` increments, at `offset`) crossed moving from
    // `from` to `to` (increments), if any.
    static std::optional<double> index_crossing(double from, double to, double period, double offset);

  private:
    std::uint8_t previous_inputs_ = 0;
    std::uint16_t previous_function_ = 0;
    std::uint16_t status_ = 0;
};

}  // namespace vecat::cia402
