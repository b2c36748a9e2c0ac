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
#include <vector>

#include "aerotrack/rt/clock.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/task_set.hpp"

namespace aerotrack::rt {

class LockstepExecutor {
 public:
  /// sim_clock: the clock the executor moves (devices and tasks read it).
  /// stats_clock: measures execution time for statistics only (normally a MonotonicClock).
  LockstepExecutor(ManualClock& sim_clock, const Clock& stats_clock);

  /// Adds a task (see TaskSet::add). Tasks added between runs start at the clock's time.
  Status add(const TaskBinding& binding) { return tasks_.add(binding); }

  /// Runs until the simulated clock reaches end_ns (releases at end_ns included) or until *stop
  /// becomes true (checked between steps). May be called again to continue.
  Status runUntil(TimeNs end_ns, const std::atomic<bool>* stop = nullptr);

  /// FNV-1a hash over every (task index, release time) step so far.
  std::uint64_t traceHash() const { return trace_hash_; }
  std::uint64_t steps() const { return steps_; }

  std::vector<TaskSet::NamedStats> stats() const { return tasks_.stats(); }

 private:
  void runOne(std::size_t index, TimeNs now_ns);
  Status runPendingEvents(TimeNs now_ns);

  ManualClock& clock_;
  const Clock& stats_clock_;
  TaskSet tasks_;
  std::vector<TimeNs> next_release_ns_;  // per task, in table order
  std::uint64_t trace_hash_ = 1469598103934665603ULL;
  std::uint64_t steps_ = 0;
};

}  // namespace aerotrack::rt
