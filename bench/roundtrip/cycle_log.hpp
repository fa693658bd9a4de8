// vecat-roundtrip --cycle-log: a CSV line per soak cycle (bench/README.md, "Runs of misses"), so that a run
// of misses can be looked at cycle by cycle: how late the master woke, both exchanges, and what the serve
// loop's thread did in the cycle.
#pragma once

#include <fmt/format.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace vecat::bench {

// --cycle-log: one soak cycle. Times in ns; an exchange that missed keeps the time the master gave up.
struct CycleRow {
    std::uint32_t wake_ns = 0;
    std::uint32_t vecat_ns = 0;
    std::uint32_t reflector_ns = 0;
    std::uint32_t serve_cpu_ns = 0;  // the serve loop's thread's CPU time since the cycle before
    std::uint32_t long_waits = 0;    // the serve thread's waits for a worker's items since the cycle before
    std::uint32_t wakeups = 0;       // the serve loop's wake-ups since the cycle before
    bool vecat_ok = true, reflector_ok = true, reflector_first = false;
};

inline void write_cycle_log(const std::string& path, const std::vector<CycleRow>& rows) {
    std::FILE* f = std::fopen(path.c_str(), "w");
    if (!f) {
        fmt::print(stderr, "vecat-roundtrip: cannot write {}\n", path);
        return;
    }
    fmt::print(f,
               "cycle,wake_us,vecat_us,vecat_ok,reflector_us,reflector_ok,reflector_first,serve_cpu_us,"
               "long_waits,serve_wakeups\n");
    for (std::size_t i = 0; i < rows.size(); ++i) {
        const CycleRow& r = rows[i];
        fmt::print(f, "{},{:.1f},{:.1f},{},{:.1f},{},{},{:.1f},{},{}\n", i, r.wake_ns / 1e3, r.vecat_ns / 1e3,
                   int{r.vecat_ok}, r.reflector_ns / 1e3, int{r.reflector_ok}, int{r.reflector_first},
                   r.serve_cpu_ns / 1e3, r.long_waits, r.wakeups);
    }
    const bool written = std::fclose(f) == 0;
    fmt::print("cycle log: {} cycles {} {}\n", rows.size(), written ? "written to" : "NOT written to", path);
}

}  // namespace vecat::bench
