// A doorbell wakes an event-triggered task when one of its input channels receives data
// (DESIGN.md: tasks are periodic or event-triggered). Producers ring() it; never blocks, never
// allocates (one atomic add and a futex wake system call). The task's executor waits on it: the
// real-time executor with a timeout, the lockstep executor by polling pending() between steps.
#pragma once

#include <atomic>
#include <cstdint>

#include "aerotrack/rt/time.hpp"

namespace aerotrack::rt {

/// Whether a write to a channel rings the doorbell attached to it: a writer whose every step writes
/// (an estimate refreshed at its rate) can wake its triggered reader only when there is news.
enum class Notify : bool { kNo, kYes };

class Doorbell {
 public:
  /// Producer side, any thread: marks new data. Wait-free apart from the wake system call.
  void ring();

  /// True if ring() was called since the last consume(). Any thread.
  bool pending() const { return rings_.load(std::memory_order_acquire) != consumed_.load(std::memory_order_relaxed); }

  /// Consumer side: clears pending() before the task drains its inputs, so that a ring() that
  /// races with the drain is never lost (it leaves pending() true for the next wait).
  void consume() { consumed_.store(rings_.load(std::memory_order_acquire), std::memory_order_relaxed); }

  /// Consumer side: blocks until pending() or until timeout_ns has passed. Returns pending().
  bool waitFor(DurationNs timeout_ns) const;

 private:
  std::atomic<std::uint32_t> rings_{0};  // 32-bit: the futex word
  std::atomic<std::uint32_t> consumed_{0};
};

}  // namespace aerotrack::rt
