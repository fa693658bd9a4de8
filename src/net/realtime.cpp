#include "net/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>

#include <cerrno>
#include <cstring>

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
    if (opt.lock_memory && !lock_all_memory(why)) return false;
    if (opt.timer_slack_ns > 0 && !set_current_thread_timer_slack(opt.timer_slack_ns, why)) return false;
    if (opt.cpu >= 0 && !pin_current_thread(opt.cpu, why)) return false;
    if (opt.fifo_priority > 0 && !set_current_thread_fifo(opt.fifo_priority, why)) return false;
    return true;
}

}  // namespace vecat::net
