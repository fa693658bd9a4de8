// Real-time settings for the threads of the cyclic path: CPU pinning, SCHED_FIFO, locked memory. Each
// returns false with a reason (missing rights, no such CPU) and changes nothing else.
#pragma once

#include <string>

namespace vecat::net {

struct RealtimeOptions {
    int cpu = -1;              // pin the thread to this CPU (-1: leave it to the scheduler)
    int fifo_priority = 0;     // SCHED_FIFO with this priority (1..99; 0: the normal scheduler)
    bool lock_memory = false;  // mlockall(current and future): no page faults on the cyclic path
};

bool pin_current_thread(int cpu, std::string* why = nullptr);
bool set_current_thread_fifo(int priority, std::string* why = nullptr);
bool lock_all_memory(std::string* why = nullptr);
// All of the above that opt asks for, on the calling thread.
bool apply_realtime(const RealtimeOptions& opt, std::string* why = nullptr);

}  // namespace vecat::net
