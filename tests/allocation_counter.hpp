// Counts every allocation of the test program: linking allocation_counter.cpp replaces the global
// operator new/delete. A test takes the count before and after the code that must not allocate.
#pragma once

#include <cstdint>

namespace vecat::test {
std::uint64_t allocations();
}  // namespace vecat::test
