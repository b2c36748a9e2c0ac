// Clocks (DESIGN.md rule 2: time is a device). Algorithms never read the wall clock; they receive
// `now`. Executors and devices read time from a Clock: MonotonicClock on the drone and in 1x
// replay, ManualClock in lockstep simulation, where the executor sets the time explicitly.
#pragma once

#include <atomic>

#include "aerotrack/rt/time.hpp"

namespace aerotrack::rt {

/// Source of the current time. Thread-safe: now() may be called from any thread.
class Clock {
 public:
  virtual ~Clock() = default;
  virtual TimeNs now() const = 0;
};

/// CLOCK_MONOTONIC: never jumps, counts from an arbitrary epoch (boot). The real-time executor
/// sleeps on the same clock with clock_nanosleep, so deadlines and now() agree.
class MonotonicClock final : public Clock {
 public:
  TimeNs now() const override;
};

/// A clock that only moves when told to. The lockstep executor owns the moves; other threads may
/// read it. Time never goes backwards: set() to an earlier time is refused.
class ManualClock final : public Clock {
 public:
  explicit ManualClock(TimeNs start_ns = 0) : now_ns_(start_ns) {}

  TimeNs now() const override { return now_ns_.load(std::memory_order_acquire); }

  /// Moves the clock to t_ns. Returns false (and does nothing) if t_ns is earlier than now().
  bool set(TimeNs t_ns) {
    if (t_ns < now()) return false;
    now_ns_.store(t_ns, std::memory_order_release);
    return true;
  }

  /// Moves the clock forward by d_ns (>= 0; a negative step is refused and returns false).
  bool advance(DurationNs d_ns) { return d_ns >= 0 && set(now() + d_ns); }

 private:
  std::atomic<TimeNs> now_ns_;
};

}  // namespace aerotrack::rt
