// common/rounding.hpp against the library functions it stands in for.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "common/rounding.hpp"

using namespace vecat;

TEST(Rounding, TheSameAsTheLibraryButForTheSignOfZero) {
    const double edge[] = {0.0,
                           -0.0,
                           0.5,
                           -0.5,
                           1.5,
                           -2.5,
                           0.49999999999999994,
                           -0.49999999999999994,
                           4503599627370495.5,
                           0x1p52,
                           -0x1p52 - 2,
                           0x1p60,
                           32767.5,
                           -32768.5,
                           std::numeric_limits<double>::infinity(),
                           -std::numeric_limits<double>::infinity(),
                           std::numeric_limits<double>::denorm_min()};
    for (const double v : edge) {
        EXPECT_EQ(trunc_to_integral(v), std::trunc(v)) << v;
        EXPECT_EQ(round_half_away(v), std::round(v)) << v;
    }
    EXPECT_TRUE(std::isnan(round_half_away(std::numeric_limits<double>::quiet_NaN())));
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> near(-70000.0, 70000.0);
    for (int i = 0; i < 100000; ++i) {
        const double v = i % 2 ? near(rng) : std::ldexp(near(rng), static_cast<int>(rng() % 80) - 20);
        ASSERT_EQ(round_half_away(v), std::round(v)) << v;
        ASSERT_EQ(trunc_to_integral(v), std::trunc(v)) << v;
    }
}
