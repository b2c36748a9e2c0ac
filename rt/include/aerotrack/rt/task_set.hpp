// The tasks an executor runs, each with its checked spec, its period and its timing statistics.
// Both executors keep their tasks in a TaskSet, so they accept exactly the same task tables and
// report statistics the same way. Not thread-safe: filled before the executor starts.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/task.hpp"
#include "aerotrack/rt/timing_stats.hpp"

namespace aerotrack::rt {

class TaskSet {
 public:
  struct Entry {
    TaskBinding binding;
    DurationNs period_ns = 0;      ///< 0 for event tasks without a periodic fallback.
    DurationNs min_period_ns = 0;  ///< The rate cap of a triggered task (0: none).
    std::unique_ptr<TimingStats> stats;
  };

  struct NamedStats {
    std::string name;
    const TimingStats* stats;
  };

  /// Adds a task. Fails on an invalid spec, a duplicate name, a null task, or a triggered task
  /// without a doorbell.
  Status add(const TaskBinding& binding);

  std::vector<Entry>& entries() { return entries_; }
  const std::vector<Entry>& entries() const { return entries_; }
  /// Checks a stall of both executors (LockstepExecutor::stall, RealtimeExecutor::stall) and finds its task:
  /// the index of the task named `name`. Error ("stall: ..."): no such task (the message lists those there
  /// are), a window that does not end after it begins, or run_ns <= 0.
  Expected<std::size_t> stallIndex(const std::string& name, TimeNs from_ns, TimeNs until_ns, DurationNs run_ns) const;
  /// Statistics in table order; pointers stay valid as long as the set.
  std::vector<NamedStats> stats() const;

 private:
  std::vector<Entry> entries_;
};

}  // namespace aerotrack::rt
