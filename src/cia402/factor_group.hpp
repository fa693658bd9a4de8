// The factor group of CiA 402 (6.2): position encoder resolution 0x608F, gear ratio 0x6091 and feed
// constant 0x6092 relate user position units to encoder increments:
//   increments per user unit = (encoder increments / motor revolutions)
//                            * (motor revolutions / shaft revolutions) / (feed / shaft revolutions)
// Integer conversions are exact (128-bit intermediate products, rounded towards minus infinity).
#pragma once

#include <cstdint>

namespace vecat::cia402 {

struct FactorGroup {
    std::uint32_t encoder_increments = 1u << 20;  // 0x608F:1
    std::uint32_t motor_revolutions = 1;          // 0x608F:2
    std::uint32_t gear_motor_revolutions = 1;     // 0x6091:1
    std::uint32_t gear_shaft_revolutions = 1;     // 0x6091:2
    std::uint32_t feed = 1u << 20;                // 0x6092:1
    std::uint32_t feed_shaft_revolutions = 1;     // 0x6092:2

    // Every factor is non-zero and the reduced fraction fits in 62 bits (otherwise the conversions use
    // 1:1 and the drive keeps its previous factors).
    bool valid() const;
    // increments = user * num / den, the reduced fraction
    std::int64_t numerator() const;
    std::int64_t denominator() const;
    std::int64_t user_to_increments(std::int64_t user) const;
    std::int64_t increments_to_user(std::int64_t increments) const;
    double increments_per_user() const;
    double increments_per_revolution() const;  // of the motor
    // Motor angle (rad) of a position in user units, and back.
    double user_to_radians(double user) const;
    double radians_to_user(double rad) const;
};

}  // namespace vecat::cia402
