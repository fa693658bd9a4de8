// Rounding without the library calls: on x86-64 without SSE4.1, std::trunc, std::round and std::lround are
// calls into libm, and the cyclic paths (a drive's servo period, an analog terminal's channels) round several
// values each time.
#pragma once

#include <cmath>
#include <cstdint>

namespace vecat {

// std::trunc: exact through int64 for |v| < 2^52; larger values (and the infinities, NaN) are integral
// already. A zero result may lose its sign.
inline double trunc_to_integral(double v) noexcept {
    return std::abs(v) < 0x1p52 ? static_cast<double>(static_cast<std::int64_t>(v)) : v;
}

// std::round (halves away from zero): v - trunc(v) is exact, so the result is the same, but for the sign of
// a zero.
inline double round_half_away(double v) noexcept {
    double r = trunc_to_integral(v);
    const double frac = v - r;
    if (frac >= 0.5)
        r += 1.0;
    else if (frac <= -0.5)
        r -= 1.0;
    return r;
}

}  // namespace vecat
