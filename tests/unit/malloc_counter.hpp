// Counting allocations in a test binary (the "no allocation once warm" claims of the modules). malloc is
// interposed (Eigen allocates through malloc, not operator new) and counts calls while a MallocCount is
// alive. The interposer is tests/unit/malloc_counter.cpp, which tests/CMakeLists.txt links into every
// binary declared COUNTS_MALLOCS (and a fresh configure refuses a binary that includes this header
// without it). Under AddressSanitizer or ThreadSanitizer, which own malloc, nothing is interposed and
// kMallocCounted is false: tests skip.
#pragma once

#include <atomic>
#include <cstddef>

#include "../support/sanitizers.hpp"

namespace aerotrack::test {

inline std::atomic<bool> g_counting_mallocs{false};
inline std::atomic<long> g_mallocs{0};

#if defined(AEROTRACK_TEST_ASAN) || defined(AEROTRACK_TEST_TSAN)
inline constexpr bool kMallocCounted = false;
#else
inline constexpr bool kMallocCounted = true;
#endif

/// Counts the mallocs made while it is alive (not thread-aware: keep other threads idle).
class MallocCount {
 public:
  MallocCount() {
    g_mallocs = 0;
    g_counting_mallocs = true;
  }
  ~MallocCount() { g_counting_mallocs = false; }
  MallocCount(const MallocCount&) = delete;
  MallocCount& operator=(const MallocCount&) = delete;
  long count() const { return g_mallocs.load(); }
};

/// Mallocs counted while a 100-double heap buffer is made (>= 1 when the interposer works): the check
/// every allocation test starts with, so that a zero count later means something.
inline long mallocsOfAHeapBuffer() {
  const MallocCount count;
  auto* volatile buffer = new double[100];
  delete[] buffer;
  return count.count();
}

}  // namespace aerotrack::test
