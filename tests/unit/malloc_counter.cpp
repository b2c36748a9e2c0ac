// The malloc interposer behind tests/unit/malloc_counter.hpp: linked into each test binary declared
// COUNTS_MALLOCS (tests/CMakeLists.txt). A source file of its own, not a macro-guarded part of the header:
// in a unity build the header is included once per batch, whichever test file comes first. Under
// AddressSanitizer or ThreadSanitizer, which own malloc, it interposes nothing and the counting tests
// skip (they run in the Release tree: scripts/check.sh release).
#include "malloc_counter.hpp"

#if !defined(AEROTRACK_TEST_ASAN) && !defined(AEROTRACK_TEST_TSAN)
extern "C" void* __libc_malloc(std::size_t size);  // NOLINT: glibc's own allocator

extern "C" void* malloc(std::size_t size) {  // NOLINT: interposes the C library's malloc
  if (aerotrack::test::g_counting_mallocs.load(std::memory_order_relaxed))
    aerotrack::test::g_mallocs.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(size);
}
#endif
