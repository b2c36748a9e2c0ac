// The real-time executor (DESIGN.md rule 3): one thread per task; periodic tasks sleep to
// absolute deadlines with clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME); a run that ends after
// the next release counts the skipped periods as missed deadlines and resynchronises to the next
// future release rather than bursting to catch up (as ArduPilot's PeriodicThread does).
// Triggered tasks wait on their doorbell (a futex: no allocation, writers never block), with the
// rules of task.hpp: a ring inside the rate cap is served at the cap's end, and a periodic fallback
// releases the task one period after its previous run. SCHED_FIFO priorities, CPU affinity and
// mlockall are applied when the process is permitted; when not, start() reports a warning per
// refusal and the tasks run at normal priority.
#pragma once

#include <atomic>
#include <string>
#include <thread>
#include <vector>

#include "aerotrack/rt/clock.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/task_set.hpp"

namespace aerotrack::rt {

struct RealtimeOptions {
  bool use_realtime_priority = true;                 ///< Try SCHED_FIFO with each task's priority (> 0).
  bool use_affinity = true;                          ///< Pin tasks whose cpu >= 0.
  bool lock_memory = true;                           ///< Try mlockall(MCL_CURRENT | MCL_FUTURE).
  DurationNs stop_poll_ns = 50 * kNsPerMillisecond;  ///< Longest sleep before re-checking stop.
  /// When set, every missed deadline (a period skipped by any periodic task) is also counted here,
  /// for whoever watches the process's timing health (the supervisor's overrun-storm failsafe).
  /// Only this executor feeds it: in lockstep, deadlines are not wall-clock facts.
  std::atomic<std::uint64_t>* deadline_misses = nullptr;
};

class RealtimeExecutor {
 public:
  explicit RealtimeExecutor(const MonotonicClock& clock, RealtimeOptions options = {});
  ~RealtimeExecutor();  ///< Stops and joins.

  RealtimeExecutor(const RealtimeExecutor&) = delete;
  RealtimeExecutor& operator=(const RealtimeExecutor&) = delete;

  /// Adds a task before start() (see TaskSet::add).
  Status add(const TaskBinding& binding);

  /// Fault injection (issue 23), before start(): each release of `task` woken in [from_ns, until_ns)
  /// is held up run_ns between its wake-up and its step, which is then given the wake-up time: a thread
  /// held up (LockstepExecutor::stall does the same in simulated time). The periods it overran count as
  /// missed deadlines like any overrun's. Error: no task of that name, an empty window, run_ns <= 0, a
  /// second stall of the task, or after start().
  Status stall(const std::string& task, TimeNs from_ns, TimeNs until_ns, DurationNs run_ns);

  /// Starts one thread per task. Returns warnings (permissions refused), or an Error if a thread
  /// could not be created (then no thread is left running).
  Expected<std::vector<std::string>> start();

  /// Asks every thread to finish its current step and exit; safe from any thread.
  void requestStop() { stop_.store(true, std::memory_order_release); }
  bool stopRequested() const { return stop_.load(std::memory_order_acquire); }

  /// Waits for all threads (after requestStop()).
  void join();

  std::vector<TaskSet::NamedStats> stats() const { return tasks_.stats(); }

 private:
  void runPeriodic(TaskSet::Entry& entry, TimeNs first_release_ns);
  void runTriggered(TaskSet::Entry& entry, TimeNs first_release_ns);
  /// step(wake_ns), after the task's stall if one is due (on the task's own thread).
  void runStep(TaskSet::Entry& entry, TimeNs wake_ns);

  struct Stall {
    TimeNs from_ns = kNeverNs;  // kNever: none
    TimeNs until_ns = kNeverNs;
    DurationNs run_ns = 0;
  };

  const MonotonicClock& clock_;
  RealtimeOptions options_;
  TaskSet tasks_;
  std::vector<Stall> stalls_;  // per task; read-only once started
  std::vector<std::thread> threads_;
  std::atomic<bool> stop_{false};
  std::atomic<std::size_t> started_{0};  // threads that passed the start gate
};

}  // namespace aerotrack::rt
