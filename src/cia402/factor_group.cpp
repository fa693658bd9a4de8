#include "cia402/factor_group.hpp"

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

bool FactorGroup::valid() const {
    return encoder_increments && motor_revolutions && gear_motor_revolutions && gear_shaft_revolutions &&
           feed && feed_shaft_revolutions;
}

std::int64_t FactorGroup::numerator() const {
    if (!valid()) return 1;
    return static_cast<std::int64_t>(encoder_increments) * gear_motor_revolutions * feed_shaft_revolutions;
}

std::int64_t FactorGroup::denominator() const {
    if (!valid()) return 1;
    return static_cast<std::int64_t>(motor_revolutions) * gear_shaft_revolutions * feed;
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
