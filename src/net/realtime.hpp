// Real-time settings for the threads of the cyclic path: CPU pinning, SCHED_FIFO, locked memory, timer
// slack. Each returns false with a reason (missing rights, no such CPU) and changes nothing else.
#pragma once

#include <string>

namespace vecat::net {

struct RealtimeOptions {
    int cpu = -1;              // pin the thread to this CPU (-1: leave it to the scheduler)
    int fifo_priority = 0;     // SCHED_FIFO with this priority (1..99; 0: the normal scheduler)
    bool lock_memory = false;  // mlockall(current and future): no page faults on the cyclic path
    // Timer slack of the thread in ns. Linux lets a normal (not SCHED_FIFO) thread's timed sleeps end up to
    // 50 us late by default, so that wake-ups can be merged; a cyclic loop wants its wake-ups on time.
    // 0: leave the thread's slack as it is.
    unsigned long timer_slack_ns = kTightTimerSlackNs;
    static constexpr unsigned long kTightTimerSlackNs = 1;
};

bool pin_current_thread(int cpu, std::string* why = nullptr);
bool set_current_thread_fifo(int priority, std::string* why = nullptr);
bool lock_all_memory(std::string* why = nullptr);
// prctl(PR_SET_TIMERSLACK): how late the calling thread's timed sleeps (poll, clock_nanosleep) may end.
bool set_current_thread_timer_slack(unsigned long ns, std::string* why = nullptr);
unsigned long current_thread_timer_slack();
// The heap (where a network's slaves keep their state) on transparent huge pages: madvise MADV_HUGEPAGE
// and MADV_COLLAPSE (Linux 6.1) over the 2 MiB pages of [heap] that exist now. A serve loop walks the state
// of every slave each cycle; with 4 KiB pages a network of a thousand slaves misses the TLB on most of them.
// False with the reason where the kernel refuses (THP off, an older kernel); nothing else changes then.
bool back_heap_with_huge_pages(std::string* why = nullptr);
// All of the above that opt asks for, on the calling thread. Each is tried even if another failed; false
// with the reasons of all that failed.
bool apply_realtime(const RealtimeOptions& opt, std::string* why = nullptr);

}  // namespace vecat::net
