// The spread of a benchmark's times: median, p99, p99.9, max and mean of a set of samples (ns), for the
// programs of bench/ that print it (vecat-roundtrip, vecat-cache-cycles).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace vecat::bench {

struct Summary {
    std::size_t n = 0;
    double mean = 0;
    std::uint32_t p50 = 0, p99 = 0, p999 = 0, max = 0;
};

// Sorts v.
inline Summary summarize(std::vector<std::uint32_t>& v) {
    Summary s;
    s.n = v.size();
    if (v.empty()) return s;
    std::sort(v.begin(), v.end());
    auto q = [&](double p) {
        return v[std::min(v.size() - 1,
                          static_cast<std::size_t>(p * static_cast<double>(v.size() - 1) + 0.5))];
    };
    double sum = 0;
    for (auto x : v)
        sum += x;
    s.mean = sum / static_cast<double>(v.size());
    s.p50 = q(0.5);
    s.p99 = q(0.99);
    s.p999 = q(0.999);
    s.max = v.back();
    return s;
}

}  // namespace vecat::bench
