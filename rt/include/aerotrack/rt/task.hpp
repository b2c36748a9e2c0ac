// Tasks and the task table. A task is a thin adapter that connects a pure library to channels;
// the executor decides when it runs. Its TaskSpec is one row of the task table (config YAML),
// which reads as the system's timing contract: rate and/or trigger, rate cap, time budget, priority,
// CPU.
//
// When a task runs (both executors apply the same rules; TaskSpec::periodic() and triggered()):
//   periodic (rate_hz, no trigger): released every period on a fixed grid from the start.
//   event (trigger, no rate_hz): released when its doorbell rang (a write to the channel it names),
//     but not sooner than min_period_ms after its previous run (the rate cap): a ring inside the cap
//     is deferred to the cap's end, never dropped.
//   event with a periodic fallback (trigger and rate_hz): as event, and also released one period
//     after its previous run when no ring came (the period restarts at every run). So it runs at most
//     every min_period_ms and at least every period.
#pragma once

#include <string>
#include <vector>

#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/time.hpp"

namespace aerotrack::rt {

class Doorbell;

/// One row of the task table.
struct TaskSpec {
  std::string name;
  double rate_hz = 0.0;  ///< > 0: periodic at this rate (with a trigger: the fallback rate).
  std::string trigger;   ///< Non-empty: name of the channel whose data wakes the task.
  /// With a trigger: the rate cap, the least time between two runs (0: none). At most the period.
  double min_period_ms = 0.0;
  double budget_ms = 0.0;  ///< Execution-time budget per run; a longer run counts as an overrun.
  int priority = 0;        ///< SCHED_FIFO priority 1..99 on the real-time executor; 0: normal.
  int cpu = -1;            ///< CPU to pin the task's thread to; -1: any.
  /// Lockstep only, for an OverlappedTask: its outputs appear this long after its release, and its
  /// work runs on a second thread meanwhile. 0: it runs inline, outputs at the release. At most the
  /// period (a task delivers before it is released again) and at most budget_ms (the contract).
  double latency_ms = 0.0;
  /// A recorder (the flight log, issue 24): it only reads channels, and nothing the flight's tasks do
  /// depends on it. Lockstep leaves its steps out of the trace hash, so a run with an observer hashes
  /// as the same run without it (set by the app, never by the task table).
  bool observer = false;

  /// Released by a timer (alone, or as the fallback of a trigger).
  bool periodic() const { return rate_hz > 0.0; }
  /// Released by its doorbell (and, if also periodic, by the fallback timer).
  bool triggered() const { return !trigger.empty(); }
};

/// Checks one spec for consistency (a rate_hz or a trigger or both, a rate cap only with a trigger and
/// at most the period, budget > 0, ranges).
Status validate(const TaskSpec& spec);

/// Checks a whole table: each spec valid and names unique.
Status validate(const std::vector<TaskSpec>& table);

/// Work the executor runs. step() is called from one thread at a time.
class Task {
 public:
  virtual ~Task() = default;
  /// Runs one step. now_ns is the executor clock's time at the release of this step: the
  /// scheduled release in lockstep, the wake-up time on the real-time executor.
  virtual void step(TimeNs now_ns) = 0;
};

/// A task whose work can overlap the other tasks' in lockstep simulation, deterministically. One step
/// is split in three: gather() takes the step's inputs from the channels at the release, work() does
/// the computing on nothing but the task's own state and what gather took (no channel is touched),
/// publish() writes the results to the channels. The real-time executor runs the three in a row on the
/// task's thread (step()). The lockstep executor, for a task with a latency (TaskSpec::latency_ms),
/// runs work() on a worker thread while the other tasks go on, and publish() on its own thread at
/// release + latency: what the other tasks see, and when, does not depend on how fast work() ran.
class OverlappedTask : public Task {
 public:
  /// At the release, on the executor's thread. False: nothing to do this step (no work, no publish).
  virtual bool gather(TimeNs now_ns) = 0;
  /// Anywhere, after gather() returned true. Publishes nothing.
  virtual void work() = 0;
  /// On the executor's thread, after work(): the results appear at publish_ns.
  virtual void publish(TimeNs publish_ns) = 0;

  void step(TimeNs now_ns) final {
    if (!gather(now_ns)) return;
    work();
    publish(now_ns);
  }
};

/// A task bound to its row of the table and, if event-triggered, to the doorbell of its input.
struct TaskBinding {
  TaskSpec spec;
  Task* task = nullptr;          ///< Not owned; outlives the executor run.
  Doorbell* doorbell = nullptr;  ///< Required for triggered tasks, ignored otherwise.
};

}  // namespace aerotrack::rt
