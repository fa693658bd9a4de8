#include "io/signal.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <system_error>

namespace vecat::io {

double value_at(const Signal& s, std::uint64_t t_ns) noexcept {
    const std::uint64_t t = t_ns + s.phase_ns;
    // Where in its period the signal is, [0, 1) (only the periodic kinds ask: a terminal's every channel
    // asks at every exchange).
    const auto phase = [&] {
        const std::uint64_t period = s.period_ns ? s.period_ns : 1;
        return static_cast<double>(t % period) / static_cast<double>(period);
    };
    switch (s.kind) {
        case SignalKind::Constant:
        case SignalKind::Wire:
            return s.value;
        case SignalKind::Square:
            return phase() < 0.5 ? s.low : s.high;
        case SignalKind::Sine:
            return s.offset + s.amplitude * std::sin(2 * std::numbers::pi * phase());
        case SignalKind::Ramp:
            return s.from + (s.to - s.from) * phase();
        case SignalKind::Table: {
            if (s.table.empty()) return 0;
            const std::uint64_t at = s.period_ns ? t % s.period_ns : t;
            // The last row at or before `at` (before the first row: the first row's value).
            auto it = std::upper_bound(s.table.begin(), s.table.end(), at,
                                       [](std::uint64_t v, const auto& row) { return v < row.first; });
            return it == s.table.begin() ? s.table.front().second : std::prev(it)->second;
        }
    }
    return 0;
}

namespace {

// A number with nothing but blanks around it.
bool number(std::string_view text, double& v) {
    while (!text.empty() && (text.front() == ' ' || text.front() == '\t'))
        text.remove_prefix(1);
    while (!text.empty() && (text.back() == ' ' || text.back() == '\t'))
        text.remove_suffix(1);
    const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
    return !text.empty() && r.ec == std::errc{} && r.ptr == text.data() + text.size() && std::isfinite(v);
}

}  // namespace

std::vector<std::pair<std::uint64_t, double>> parse_table(const std::string& csv) {
    std::vector<std::pair<std::uint64_t, double>> rows;
    std::istringstream in(csv);
    std::string line;
    for (unsigned n = 1; std::getline(in, line); ++n) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        const auto first = line.find_first_not_of(" \t");
        if (first == std::string::npos || line[first] == '#') continue;
        const auto fail = [&](const std::string& what) {
            throw std::invalid_argument(std::to_string(n) + ": " + what);
        };
        const auto comma = line.find(',');
        if (comma == std::string::npos) fail("expected time_ms,value");
        const std::string_view all(line);
        double ms = 0, v = 0;
        if (!number(all.substr(0, comma), ms) || ms < 0 || ms > 1e12)
            fail("the time \"" + line.substr(0, comma) + "\" is no number of milliseconds from 0 to 1e12");
        if (!number(all.substr(comma + 1), v))
            fail("the value \"" + line.substr(comma + 1) + "\" is no number");
        const auto t = static_cast<std::uint64_t>(ms * 1e6);
        if (!rows.empty() && t <= rows.back().first) fail("the times must rise");
        rows.emplace_back(t, v);
    }
    if (rows.empty()) throw std::invalid_argument("1: no rows (time_ms,value)");
    return rows;
}

}  // namespace vecat::io
