// The lockstep executor (DESIGN.md rule 3): a simulated clock and the task table run in deadline
// order on the calling thread, as fast as the CPU allows. Deterministic: for the same tasks and
// the same inputs the sequence of (task, time) steps is identical, bit for bit; traceHash()
// summarises it so tests can compare runs.
//
// Order: periodic releases by time, ties by priority (higher first) then table order. After each
// step, event-triggered tasks whose doorbell rang run at the same simulated time, in table order,
// until none is pending.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "aerotrack/rt/clock.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/task.hpp"
#include "aerotrack/rt/timing_stats.hpp"

namespace aerotrack::rt {

class LockstepExecutor {
 public:
  /// sim_clock: the clock the executor moves (devices and tasks read it).
  /// stats_clock: measures execution time for statistics only (normally a MonotonicClock).
  LockstepExecutor(ManualClock& sim_clock, const Clock& stats_clock);

  /// Adds a task; call before run(). Fails on an invalid spec, a duplicate name, a null task,
  /// or an event task without a doorbell.
  Status add(const TaskBinding& binding);

  /// Runs until the simulated clock reaches end_ns (releases at end_ns included) or until *stop
  /// becomes true (checked between steps). May be called again to continue.
  Status runUntil(TimeNs end_ns, const std::atomic<bool>* stop = nullptr);

  /// FNV-1a hash over every (task index, release time) step so far.
  std::uint64_t traceHash() const { return trace_hash_; }
  std::uint64_t steps() const { return steps_; }

  struct NamedStats {
    std::string name;
    const TimingStats* stats;
  };
  std::vector<NamedStats> stats() const;

 private:
  struct Entry {
    TaskBinding binding;
    DurationNs period_ns = 0;
    TimeNs next_release_ns = 0;
    bool started = false;
    std::unique_ptr<TimingStats> stats;
  };

  void runOne(Entry& entry, std::size_t index, TimeNs now_ns);
  Status runPendingEvents(TimeNs now_ns);

  ManualClock& clock_;
  const Clock& stats_clock_;
  std::vector<Entry> entries_;
  std::uint64_t trace_hash_ = 1469598103934665603ULL;
  std::uint64_t steps_ = 0;
};

}  // namespace aerotrack::rt
