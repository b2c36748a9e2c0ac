// Doorbell on a Linux futex: ring() bumps a counter and wakes a waiter; waitFor() sleeps only
// while the counter equals the last consumed value, so a ring between the check and the sleep
// makes the futex call return at once (no lost wake-up).
#include "aerotrack/rt/doorbell.hpp"

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <ctime>

namespace aerotrack::rt {
namespace {

long futex(const std::atomic<std::uint32_t>* word, int op, std::uint32_t value, const timespec* timeout) {
  // The futex word is the atomic's object representation (lock-free 32-bit atomics on Linux).
  return syscall(SYS_futex, reinterpret_cast<const std::uint32_t*>(word), op, value, timeout, nullptr, 0);
}

}  // namespace

void Doorbell::ring() {
  rings_.fetch_add(1, std::memory_order_acq_rel);
  futex(&rings_, FUTEX_WAKE_PRIVATE, 1, nullptr);
}

bool Doorbell::waitFor(DurationNs timeout_ns) const {
  const std::uint32_t seen = consumed_.load(std::memory_order_relaxed);
  if (rings_.load(std::memory_order_acquire) != seen) return true;
  if (timeout_ns > 0) {
    timespec timeout{};
    timeout.tv_sec = static_cast<time_t>(timeout_ns / kNsPerSecond);
    timeout.tv_nsec = static_cast<long>(timeout_ns % kNsPerSecond);
    // Relative timeout; returns early on a ring (value changed), EINTR or EAGAIN.
    futex(&rings_, FUTEX_WAIT_PRIVATE, seen, &timeout);
  }
  return pending();
}

}  // namespace aerotrack::rt
