#include "cia402/factor_group.hpp"

#include <array>
#include <limits>
#include <numbers>

namespace vecat::cia402 {

namespace {

__extension__ using i128 = __int128;  // products of two 64-bit values

std::int64_t floor_div(i128 a, i128 b) {
    // Most products fit in 64 bits, where the division is a single instruction (the 128-bit one is a
    // library call); the result is the same.
    constexpr i128 kLo = std::numeric_limits<std::int64_t>::min() + 1,
                   kHi = std::numeric_limits<std::int64_t>::max();
    if (a >= kLo && a <= kHi && b >= kLo && b <= kHi) {
        const auto a64 = static_cast<std::int64_t>(a), b64 = static_cast<std::int64_t>(b);
        std::int64_t q = a64 / b64;
        if ((a64 % b64 != 0) && ((a64 < 0) != (b64 < 0))) --q;
        return q;
    }
    i128 q = a / b;
    if ((a % b != 0) && ((a < 0) != (b < 0))) --q;
    return static_cast<std::int64_t>(q);
}

}  // namespace

namespace {

// The reduced fraction increments/user unit; zero when a factor is zero or the fraction needs more than
// 62 bits (then products with 64-bit positions still fit in 128 bits).
struct Fraction {
    std::int64_t num = 0, den = 0;
};

i128 gcd(i128 a, i128 b) {
    while (b != 0) {
        const i128 t = a % b;
        a = b;
        b = t;
    }
    return a;
}

Fraction reduce(const FactorGroup& f) {
    if (!(f.encoder_increments && f.motor_revolutions && f.gear_motor_revolutions &&
          f.gear_shaft_revolutions && f.feed && f.feed_shaft_revolutions))
        return {};
    i128 n = static_cast<i128>(f.encoder_increments) * f.gear_motor_revolutions * f.feed_shaft_revolutions;
    i128 d = static_cast<i128>(f.motor_revolutions) * f.gear_shaft_revolutions * f.feed;
    const i128 g = gcd(n, d);
    n /= g;
    d /= g;
    constexpr i128 kMax = static_cast<i128>(1) << 62;
    if (n >= kMax || d >= kMax) return {};
    return {static_cast<std::int64_t>(n), static_cast<std::int64_t>(d)};
}

// Every servo step converts several values with the same factors, and the gcd of 128-bit products is
// costly (hundreds of ns): the last result is kept, per thread, keyed by the six factors.
Fraction reduced(const FactorGroup& f) {
    struct Memo {
        std::uint64_t k0 = 0, k1 = 0, k2 = 0;  // the six factors, two per word
        Fraction r;
        bool set = false;
    };
    thread_local Memo memo;
    const auto pair = [](std::uint32_t lo, std::uint32_t hi) {
        return lo | static_cast<std::uint64_t>(hi) << 32;
    };
    const std::uint64_t k0 = pair(f.encoder_increments, f.motor_revolutions);
    const std::uint64_t k1 = pair(f.gear_motor_revolutions, f.gear_shaft_revolutions);
    const std::uint64_t k2 = pair(f.feed, f.feed_shaft_revolutions);
    if (!memo.set || memo.k0 != k0 || memo.k1 != k1 || memo.k2 != k2) memo = {k0, k1, k2, reduce(f), true};
    return memo.r;
}

}  // namespace

bool FactorGroup::valid() const {
    return reduced(*this).num != 0;
}

std::int64_t FactorGroup::numerator() const {
    const Fraction r = reduced(*this);
    return r.num ? r.num : 1;
}

std::int64_t FactorGroup::denominator() const {
    const Fraction r = reduced(*this);
    return r.num ? r.den : 1;
}

FactorRatios FactorGroup::ratios() const {
    const Fraction raw = reduced(*this);
    FactorRatios r;
    if (raw.num != 0) {
        r.num = raw.num;
        r.den = raw.den;
        r.per_revolution = static_cast<double>(encoder_increments) / motor_revolutions;
    }
    r.per_user = static_cast<double>(r.num) / static_cast<double>(r.den);
    return r;
}

std::int64_t FactorRatios::user_to_increments(std::int64_t user) const {
    return floor_div(static_cast<i128>(user) * num, den);
}

std::int64_t FactorRatios::increments_to_user(std::int64_t increments) const {
    return floor_div(static_cast<i128>(increments) * den, num);
}

std::int64_t FactorGroup::user_to_increments(std::int64_t user) const {
    return ratios().user_to_increments(user);
}

std::int64_t FactorGroup::increments_to_user(std::int64_t increments) const {
    return ratios().increments_to_user(increments);
}

double FactorGroup::increments_per_user() const {
    return ratios().per_user;
}

double FactorGroup::increments_per_revolution() const {
    return ratios().per_revolution;
}

double FactorGroup::user_to_radians(double user) const {
    return ratios().user_to_radians(user);
}

double FactorGroup::radians_to_user(double rad) const {
    return ratios().radians_to_user(rad);
}

}  // namespace vecat::cia402
