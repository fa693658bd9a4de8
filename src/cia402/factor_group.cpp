#include "cia402/factor_group.hpp"

#include <array>
#include <numbers>

namespace vecat::cia402 {

namespace {

__extension__ using i128 = __int128;  // products of two 64-bit values

std::int64_t floor_div(i128 a, i128 b) {
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
    using Key = std::array<std::uint32_t, 6>;
    struct Memo {
        Key key{};
        Fraction r;
        bool set = false;
    };
    thread_local Memo memo;
    const Key key{f.encoder_increments,
                  f.motor_revolutions,
                  f.gear_motor_revolutions,
                  f.gear_shaft_revolutions,
                  f.feed,
                  f.feed_shaft_revolutions};
    if (!memo.set || memo.key != key) memo = {key, reduce(f), true};
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

std::int64_t FactorGroup::user_to_increments(std::int64_t user) const {
    return floor_div(static_cast<i128>(user) * numerator(), denominator());
}

std::int64_t FactorGroup::increments_to_user(std::int64_t increments) const {
    return floor_div(static_cast<i128>(increments) * denominator(), numerator());
}

double FactorGroup::increments_per_user() const {
    return static_cast<double>(numerator()) / static_cast<double>(denominator());
}

double FactorGroup::increments_per_revolution() const {
    if (!valid()) return 1u << 20;
    return static_cast<double>(encoder_increments) / motor_revolutions;
}

double FactorGroup::user_to_radians(double user) const {
    return user * increments_per_user() / increments_per_revolution() * 2.0 * std::numbers::pi;
}

double FactorGroup::radians_to_user(double rad) const {
    return rad / (2.0 * std::numbers::pi) * increments_per_revolution() / increments_per_user();
}

}  // namespace vecat::cia402
