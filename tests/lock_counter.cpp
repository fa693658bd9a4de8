#include "lock_counter.hpp"

#include <dlfcn.h>
#include <pthread.h>
#include <semaphore.h>
#include <sys/syscall.h>

#include <atomic>
#include <cstdarg>
#include <cstdlib>

namespace {

std::atomic<std::uint64_t> g_calls{0};

void count() {
    g_calls.fetch_add(1, std::memory_order_relaxed);
}

// The next definition of a function (glibc's), looked up once.
template <typename F>
F next(const char* name) {
    void* f = dlsym(RTLD_NEXT, name);
    if (!f) std::abort();
    return reinterpret_cast<F>(f);
}

}  // namespace

std::uint64_t vecat::test::lock_calls() {
    return g_calls.load(std::memory_order_relaxed);
}

// Each wrapper counts and calls glibc's function of the same name.
#define VECAT_INTERPOSE(ret, name, params, args)             \
    extern "C" ret name params {                             \
        static const auto real = next<ret(*) params>(#name); \
        count();                                             \
        return real args;                                    \
    }

VECAT_INTERPOSE(int, pthread_mutex_lock, (pthread_mutex_t * m), (m))
VECAT_INTERPOSE(int, pthread_mutex_trylock, (pthread_mutex_t * m), (m))
VECAT_INTERPOSE(int, pthread_mutex_timedlock, (pthread_mutex_t * m, const struct timespec* t), (m, t))
VECAT_INTERPOSE(int, pthread_rwlock_rdlock, (pthread_rwlock_t * l), (l))
VECAT_INTERPOSE(int, pthread_rwlock_wrlock, (pthread_rwlock_t * l), (l))
VECAT_INTERPOSE(int, pthread_rwlock_tryrdlock, (pthread_rwlock_t * l), (l))
VECAT_INTERPOSE(int, pthread_rwlock_trywrlock, (pthread_rwlock_t * l), (l))
VECAT_INTERPOSE(int, pthread_spin_lock, (pthread_spinlock_t * l), (l))
VECAT_INTERPOSE(int, pthread_cond_wait, (pthread_cond_t * c, pthread_mutex_t* m), (c, m))
VECAT_INTERPOSE(int, pthread_cond_timedwait,
                (pthread_cond_t * c, pthread_mutex_t* m, const struct timespec* t), (c, m, t))
VECAT_INTERPOSE(int, pthread_cond_clockwait,
                (pthread_cond_t * c, pthread_mutex_t* m, clockid_t k, const struct timespec* t), (c, m, k, t))
VECAT_INTERPOSE(int, pthread_mutex_clocklock, (pthread_mutex_t * m, clockid_t k, const struct timespec* t),
                (m, k, t))
VECAT_INTERPOSE(int, pthread_rwlock_clockrdlock,
                (pthread_rwlock_t * l, clockid_t k, const struct timespec* t), (l, k, t))
VECAT_INTERPOSE(int, pthread_rwlock_clockwrlock,
                (pthread_rwlock_t * l, clockid_t k, const struct timespec* t), (l, k, t))
VECAT_INTERPOSE(int, sem_wait, (sem_t * s), (s))
VECAT_INTERPOSE(int, sem_clockwait, (sem_t * s, clockid_t k, const struct timespec* t), (s, k, t))
VECAT_INTERPOSE(int, sem_timedwait, (sem_t * s, const struct timespec* t), (s, t))

// syscall() is variadic: the futex calls of libstdc++ (atomic wait/notify) pass at most six arguments.
extern "C" long syscall(long number, ...) {
    static const auto real = next<long (*)(long, ...)>("syscall");
    va_list ap;
    va_start(ap, number);
    long a[6];
    for (long& x : a)
        x = va_arg(ap, long);
    va_end(ap);
    if (number == SYS_futex) count();
    return real(number, a[0], a[1], a[2], a[3], a[4], a[5]);
}
