#include "net/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>

#include <cerrno>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>

namespace vecat::net {

bool pin_current_thread(int cpu, std::string* why) {
    if (cpu < 0 || cpu >= CPU_SETSIZE) {
        if (why) *why = "CPU " + std::to_string(cpu) + " out of range";
        return false;
    }
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(static_cast<unsigned>(cpu), &set);
    const int rc = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
    if (rc != 0) {
        if (why) *why = "pin to CPU " + std::to_string(cpu) + ": " + std::strerror(rc);
        return false;
    }
    return true;
}

bool set_current_thread_fifo(int priority, std::string* why) {
    sched_param p{};
    p.sched_priority = priority;
    const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p);
    if (rc != 0) {
        if (why) *why = "SCHED_FIFO " + std::to_string(priority) + ": " + std::strerror(rc);
        return false;
    }
    return true;
}

bool lock_all_memory(std::string* why) {
    if (::mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
        if (why) *why = std::string("mlockall: ") + std::strerror(errno);
        return false;
    }
    return true;
}

bool back_heap_with_huge_pages(std::string* why) {
#ifdef MADV_COLLAPSE
    constexpr int kCollapse = MADV_COLLAPSE;
#else
    constexpr int kCollapse = 25;  // <sys/mman.h> of an older libc; the kernel's value (Linux 6.1)
#endif
    constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;
    std::ifstream maps("/proc/self/maps");
    std::string line;
    while (std::getline(maps, line)) {
        if (line.find("[heap]") == std::string::npos) continue;
        std::uintptr_t from = 0, to = 0;
        if (std::sscanf(line.c_str(), "%" SCNxPTR "-%" SCNxPTR, &from, &to) != 2) break;
        from = (from + kHuge - 1) & ~(kHuge - 1);
        to &= ~(kHuge - 1);
        if (to <= from) return true;  // no whole huge page in it: nothing to do
        void* at = reinterpret_cast<void*>(from);
        if (::madvise(at, to - from, MADV_HUGEPAGE) != 0 || ::madvise(at, to - from, kCollapse) != 0) {
            if (why) *why = std::string("huge pages for the heap: ") + std::strerror(errno);
            return false;
        }
        return true;
    }
    return true;  // no [heap] (all of it mapped elsewhere, e.g. under a sanitizer)
}

bool set_current_thread_timer_slack(unsigned long ns, std::string* why) {
    if (::prctl(PR_SET_TIMERSLACK, ns, 0, 0, 0) != 0) {
        if (why) *why = "timer slack " + std::to_string(ns) + " ns: " + std::strerror(errno);
        return false;
    }
    return true;
}

unsigned long current_thread_timer_slack() {
    const int v = ::prctl(PR_GET_TIMERSLACK, 0, 0, 0, 0);
    return v < 0 ? 0 : static_cast<unsigned long>(v);
}

bool apply_realtime(const RealtimeOptions& opt, std::string* why) {
    // Every setting is tried, so that one that fails (e.g. SCHED_FIFO without the right) leaves the others
    // in effect for a caller that carries on; the reasons of all failures are joined.
    bool ok = true;
    std::string reasons;
    const auto apply = [&](bool wanted, auto&& set) {
        std::string r;
        if (!wanted || set(&r)) return;
        ok = false;
        reasons += (reasons.empty() ? "" : "; ") + r;
    };
    apply(opt.lock_memory, [](std::string* r) { return lock_all_memory(r); });
    apply(opt.timer_slack_ns > 0,
          [&](std::string* r) { return set_current_thread_timer_slack(opt.timer_slack_ns, r); });
    apply(opt.cpu >= 0, [&](std::string* r) { return pin_current_thread(opt.cpu, r); });
    apply(opt.fifo_priority > 0,
          [&](std::string* r) { return set_current_thread_fifo(opt.fifo_priority, r); });
    if (!ok && why) *why = reasons;
    return ok;
}

}  // namespace vecat::net
