// Marks memory inside one allocation as unusable for AddressSanitizer (no-ops without it), so that pooled
// buffers keep the out-of-bounds checks separate allocations would have (the object dictionary's values).
#pragma once

#include <cstddef>

#if defined(__SANITIZE_ADDRESS__)
#define VECAT_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define VECAT_ASAN 1
#endif
#endif

#ifdef VECAT_ASAN
#include <sanitizer/asan_interface.h>
#endif

namespace vecat {

#ifdef VECAT_ASAN
inline constexpr bool kAsan = true;
inline void asan_poison(const void* p, std::size_t n) {
    ASAN_POISON_MEMORY_REGION(p, n);
}
inline void asan_unpoison(const void* p, std::size_t n) {
    ASAN_UNPOISON_MEMORY_REGION(p, n);
}
#else
inline constexpr bool kAsan = false;
inline void asan_poison(const void*, std::size_t) {}
inline void asan_unpoison(const void*, std::size_t) {}
#endif

}  // namespace vecat
