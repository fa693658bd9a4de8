// The factor group of CiA 402 (6.2): position encoder resolution 0x608F, gear ratio 0x6091 and feed
// constant 0x6092 relate user position units to encoder increments:
//   increments per user unit = (encoder increments / motor revolutions)
//                            * (motor revolutions / shaft revolutions) / (feed / shaft revolutions)
// Integer conversions are exact (128-bit intermediate products, rounded towards minus infinity).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

namespace vecat::cia402 {

// The conversions of a factor group with its reduced fraction worked out once: the gcd of 128-bit
// products costs hundreds of instructions, and a drive converts several values every servo step, so it
// keeps these for its current factors. FactorGroup's own conversions go through the same functions.
struct FactorRatios {
    std::int64_t num = 1, den = 1;     // increments = user * num / den (1:1 for an invalid group)
    double per_user = 1.0;             // num / den
    double per_revolution = 1u << 20;  // encoder increments per motor revolution
    std::int64_t user_to_increments(std::int64_t user) const;
    std::int64_t increments_to_user(std::int64_t increments) const;
    double user_to_radians(double user) const {
        return user * per_user / per_revolution * 2.0 * std::numbers::pi;
    }
    double radians_to_user(double rad) const {
        return rad / (2.0 * std::numbers::pi) * per_revolution / per_user;
    }
};

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
    FactorRatios ratios() const;
};

// Positions as the drive's integer objects hold them. floor() as a 64-bit integer, saturated: with absurd
// parameters the simulated machine can run away past the 64-bit range, and converting such a double is
// undefined (found by the random-values test under UBSan).
inline std::int64_t floor64(double v) {
    if (!(v == v)) return 0;
    return static_cast<std::int64_t>(std::floor(std::clamp(v, -9.2e18, 9.2e18)));
}

// The low 32 bits, as a position object such as 0x6064 or 0x60BA wraps around (two's complement).
inline std::int32_t wrap32(std::int64_t v) {
    return static_cast<std::int32_t>(static_cast<std::uint32_t>(static_cast<std::uint64_t>(v)));
}

}  // namespace vecat::cia402
