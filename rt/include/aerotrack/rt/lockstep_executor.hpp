// The lockstep executor (DESIGN.md rule 3): a simulated clock and the task table run in deadline
// order on the calling thread, as fast as the CPU allows. Deterministic: for the same tasks and
// the same inputs the sequence of (task, time) steps is identical, bit for bit; traceHash()
// summarises it so tests can compare runs.
//
// Order: timed releases by time, ties by priority (higher first) then table order. After each
// step, triggered tasks whose doorbell rang run at the same simulated time, in table order, until
// none is pending. A ring inside a task's rate cap (TaskSpec::min_period_ms) schedules a timed
// release at the cap's end instead, which runs in priority order among that instant's releases
// (not after whichever step came first: removing unrelated tasks, as a replay does, changes
// nothing); a triggered task with a rate also has a timed release one period after its previous
// run (task.hpp). So when a task runs is a function of the simulated time and of which steps wrote
// to its channel, nothing else: the run stays deterministic.
//
// Overlap: an OverlappedTask with a latency (TaskSpec::latency_ms > 0) has its gather() run at the
// release, its work() on the executor's one worker thread while the other tasks go on, and its
// publish() at release + latency, before the releases due at that instant (then the event tasks
// its outputs woke). So a second core shortens the wall time while the simulated run stays the
// same, bit for bit, however fast the work ran. A task released again before its outputs appeared
// publishes them first; runUntil() returns only with the worker idle.
//
// Stalls (issue 23's fault matrix): stall() makes a task's releases in a window take a given time of
// the simulated clock, as a task overrunning its budget does on the real-time executor, where the
// task's thread is busy and its periods go by unserved.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
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
  ~LockstepExecutor();
  LockstepExecutor(const LockstepExecutor&) = delete;
  LockstepExecutor& operator=(const LockstepExecutor&) = delete;

  /// Adds a task (see TaskSet::add). Tasks added between runs start at the clock's time.
  Status add(const TaskBinding& binding) { return tasks_.add(binding); }

  /// Fault injection: each release of the task named `task` in [from_ns, until_ns) takes run_ns of
  /// simulated time (run_ns = until_ns - from_ns: one stall; less: a task slowed down). An
  /// OverlappedTask gathers its inputs at the release and publishes run_ns later (outputs computed from
  /// old inputs). Any other task's step runs run_ns after the release with the release's time as its
  /// now_ns, as on the real-time executor when a thread is held up after waking: its time base is old,
  /// its inputs are those of when it runs, its outputs as late (lockstep cannot split a step). Either
  /// way the task is not released meanwhile; the periods it skips count as missed deadlines when the
  /// late step runs (its statistics, and the counter of countMissedDeadlinesIn()). Error: no task of
  /// that name, an empty window, run_ns <= 0, a second stall of the task.
  Status stall(const std::string& task, TimeNs from_ns, TimeNs until_ns, DurationNs run_ns);
  /// Where missed deadlines are also counted (a stall's are the only ones in lockstep): the counter
  /// the supervisor watches for an overrun storm (RealtimeOptions::deadline_misses). May be null.
  void countMissedDeadlinesIn(std::atomic<std::uint64_t>* counter) { deadline_misses_ = counter; }

  /// Runs until the simulated clock reaches end_ns (releases at end_ns included) or until *stop
  /// becomes true (checked between steps). May be called again to continue.
  Status runUntil(TimeNs end_ns, const std::atomic<bool>* stop = nullptr);

  /// FNV-1a hash over every (task index, release time) step so far, and every (task index + number of
  /// tasks, publish time) publication of an overlapped task. An observer's steps are left out (and
  /// its index must come after every other task's, as the app adds it: the indices hashed stay the same).
  std::uint64_t traceHash() const { return trace_hash_; }
  std::uint64_t steps() const { return steps_; }

  std::vector<TaskSet::NamedStats> stats() const { return tasks_.stats(); }

 private:
  class Worker;
  struct Publication {
    std::size_t index;
    TimeNs publish_ns;
  };
  struct Stall {
    std::size_t index;
    TimeNs from_ns;
    TimeNs until_ns;
    DurationNs run_ns;
  };

  void runOne(std::size_t index, TimeNs now_ns);
  /// gather() now, work() on the worker, publication scheduled; false if the task is not overlapped.
  /// A stall's time replaces the spec's latency when stall_ns > 0 (then any OverlappedTask qualifies).
  bool startOverlapped(std::size_t index, TimeNs now_ns, DurationNs stall_ns = 0);
  /// How long this release of task `index` takes under its stall, or 0.
  DurationNs takeStall(std::size_t index, TimeNs now_ns);
  /// Starts a stalled release: the task is busy until now_ns + stall_ns.
  void releaseStalled(std::size_t index, TimeNs now_ns, DurationNs stall_ns);
  /// Counts the periods a stall of task `index` skipped, once its late step runs or publishes.
  void reportMisses(std::size_t index);
  /// Waits for the worker's job, if any, and books its time to its task's statistics.
  void joinWorker();
  /// Publishes pending_[i] at its time (or at now_ns if that is later) and removes it.
  void publish(std::size_t i, TimeNs now_ns);
  Status runPendingEvents(TimeNs now_ns);

  ManualClock& clock_;
  const Clock& stats_clock_;
  TaskSet tasks_;
  /// Runs task `index` at now_ns: consumes its doorbell first (a ring during the step stays pending),
  /// runs it, and sets its next timed release.
  void release(std::size_t index, TimeNs now_ns);

  std::vector<TimeNs> next_release_ns_;           // per task, in table order; kNever: none scheduled
  std::vector<TimeNs> last_run_ns_;               // per task; kNever: not run yet
  std::vector<TimeNs> busy_until_ns_;             // per task: released no sooner than this (a stall)
  std::vector<std::uint64_t> unreported_misses_;  // per task: a stall's skipped periods, not yet counted
  std::vector<TimeNs> stalled_release_ns_;        // per task: the release a late step belongs to (kNever: none)
  std::vector<Publication> pending_;              // at most one per overlapped task, in start order
  std::vector<Stall> stalls_;
  std::atomic<std::uint64_t>* deadline_misses_ = nullptr;
  std::unique_ptr<Worker> worker_;  // started with the first overlapped step
  std::size_t in_flight_ = 0;       // task whose work the worker has (if busy)
  bool busy_ = false;
  DurationNs in_flight_gather_ns_ = 0;
  std::uint64_t trace_hash_ = 1469598103934665603ULL;
  std::uint64_t steps_ = 0;
};

}  // namespace aerotrack::rt
