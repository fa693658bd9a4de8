// Counts every blocking synchronisation call of the test program: linking lock_counter.cpp interposes
// pthread_mutex_lock/trylock/timedlock/clocklock, the rwlock and spinlock calls,
// pthread_cond_wait/timedwait/clockwait, sem_wait/timedwait and syscall(SYS_futex) (std::atomic::wait,
// std::latch). std::mutex, std::shared_mutex and std::condition_variable end in these. glibc's internal locks
// (malloc arenas, stdio) do not go through them: allocations are counted by allocation_counter.cpp, and the
// cyclic path does no stdio.
#pragma once

#include <cstdint>

namespace vecat::test {
std::uint64_t lock_calls();
}  // namespace vecat::test
