// Lockstep executor: see lockstep_executor.hpp. The next step is found by a linear scan over the
// table (a dozen tasks), which keeps the order rule obvious: earliest release, then higher
// priority, then table order.
#include "aerotrack/rt/lockstep_executor.hpp"

#include <algorithm>
#include <condition_variable>
#include <limits>
#include <mutex>
#include <thread>
#include <utility>

#include "aerotrack/rt/doorbell.hpp"

namespace aerotrack::rt {
namespace {

// Event tasks that keep re-triggering each other at one instant would never let time advance.
constexpr int kMaxEventRoundsPerInstant = 1000;

void hashMix(std::uint64_t& hash, std::uint64_t value) {
  for (int byte = 0; byte < 8; ++byte) {
    hash ^= (value >> (8 * byte)) & 0xFFU;
    hash *= 1099511628211ULL;
  }
}

}  // namespace

/// One thread that runs one OverlappedTask::work() at a time. The hand-over is a mutex and a
/// condition variable: this is the simulator's executor, not a real-time path.
class LockstepExecutor::Worker {
 public:
  explicit Worker(const Clock& stats_clock) : stats_clock_(stats_clock), thread_([this] { run(); }) {}
  ~Worker() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      quit_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
  Worker(const Worker&) = delete;
  Worker& operator=(const Worker&) = delete;

  /// Hands over a job; the worker must be idle (the executor joins first).
  void start(OverlappedTask* task) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      job_ = task;
    }
    wake_.notify_all();
  }

  /// Waits until the job is done; returns how long work() took.
  DurationNs join() {
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [this] { return job_ == nullptr; });
    return work_ns_;
  }

 private:
  void run() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      wake_.wait(lock, [this] { return quit_ || job_ != nullptr; });
      if (job_ == nullptr) return;  // quit, and nothing left to do
      OverlappedTask* task = job_;
      lock.unlock();
      const TimeNs begin_ns = stats_clock_.now();
      task->work();
      const DurationNs work_ns = stats_clock_.now() - begin_ns;
      lock.lock();
      work_ns_ = work_ns;
      job_ = nullptr;
      done_.notify_all();
    }
  }

  const Clock& stats_clock_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable done_;
  OverlappedTask* job_ = nullptr;
  DurationNs work_ns_ = 0;
  bool quit_ = false;
  std::thread thread_;  // last: starts after the members it uses
};

LockstepExecutor::LockstepExecutor(ManualClock& sim_clock, const Clock& stats_clock)
    : clock_(sim_clock), stats_clock_(stats_clock) {}

LockstepExecutor::~LockstepExecutor() = default;

void LockstepExecutor::joinWorker() {
  if (!busy_) return;
  const DurationNs work_ns = worker_->join();
  busy_ = false;
  tasks_.entries()[in_flight_].stats->recordRun(in_flight_gather_ns_ + work_ns);
}

bool LockstepExecutor::startOverlapped(std::size_t index, TimeNs now_ns, DurationNs stall_ns) {
  TaskSet::Entry& entry = tasks_.entries()[index];
  if (!(entry.binding.spec.latency_ms > 0.0) && stall_ns <= 0) return false;
  auto* task = dynamic_cast<OverlappedTask*>(entry.binding.task);
  if (task == nullptr) return false;
  // Released again before its outputs appeared (an event task, or a latency of a whole period).
  for (std::size_t i = 0; i < pending_.size(); ++i) {
    if (pending_[i].index == index) {
      publish(i, now_ns);
      break;
    }
  }
  hashMix(trace_hash_, index);
  hashMix(trace_hash_, static_cast<std::uint64_t>(now_ns));
  ++steps_;
  const TimeNs begin_ns = stats_clock_.now();
  const bool has_work = task->gather(now_ns);
  const DurationNs gather_ns = stats_clock_.now() - begin_ns;
  if (!has_work) {
    entry.stats->recordRun(gather_ns);
    return true;
  }
  joinWorker();  // one job at a time
  if (!worker_) worker_ = std::make_unique<Worker>(stats_clock_);
  worker_->start(task);
  busy_ = true;
  in_flight_ = index;
  in_flight_gather_ns_ = gather_ns;
  const auto latency_ns = stall_ns > 0 ? stall_ns : static_cast<DurationNs>(entry.binding.spec.latency_ms * 1e6);
  pending_.push_back({index, now_ns + latency_ns});
  return true;
}

void LockstepExecutor::reportMisses(std::size_t index) {
  const std::uint64_t n = unreported_misses_[index];
  if (n == 0) return;
  unreported_misses_[index] = 0;
  tasks_.entries()[index].stats->addMissedDeadlines(n);
  if (deadline_misses_ != nullptr) deadline_misses_->fetch_add(n, std::memory_order_relaxed);
}

void LockstepExecutor::publish(std::size_t i, TimeNs now_ns) {
  const Publication p = pending_[i];
  reportMisses(p.index);
  pending_.erase(pending_.begin() + static_cast<std::ptrdiff_t>(i));
  if (busy_ && in_flight_ == p.index) joinWorker();
  const TimeNs publish_ns = std::max(p.publish_ns, now_ns);
  if (publish_ns > clock_.now()) clock_.set(publish_ns);
  static_cast<OverlappedTask*>(tasks_.entries()[p.index].binding.task)->publish(publish_ns);
  // Numbered after the flight's tasks (observers, which come last, left out of the count).
  std::size_t flight_tasks = 0;
  for (const TaskSet::Entry& e : tasks_.entries()) flight_tasks += e.binding.spec.observer ? 0 : 1;
  hashMix(trace_hash_, p.index + flight_tasks);
  hashMix(trace_hash_, static_cast<std::uint64_t>(publish_ns));
}

void LockstepExecutor::runOne(std::size_t index, TimeNs now_ns) {
  reportMisses(index);  // a stalled step's, now that it runs
  if (startOverlapped(index, now_ns)) return;
  TaskSet::Entry& entry = tasks_.entries()[index];
  const TimeNs begin = stats_clock_.now();
  entry.binding.task->step(now_ns);
  entry.stats->recordRun(stats_clock_.now() - begin);
  if (entry.binding.spec.observer) return;  // not part of the flight: not in its trace
  hashMix(trace_hash_, index);
  hashMix(trace_hash_, static_cast<std::uint64_t>(now_ns));
  ++steps_;
}

Status LockstepExecutor::stall(const std::string& task, TimeNs from_ns, TimeNs until_ns, DurationNs run_ns) {
  const Expected<std::size_t> index = tasks_.stallIndex(task, from_ns, until_ns, run_ns);
  if (!index) return index.error();
  for (const Stall& s : stalls_)
    if (s.index == *index) return Error{"stall: task '" + task + "' already has a stall"};
  stalls_.push_back({*index, from_ns, until_ns, run_ns});
  return ok();
}

DurationNs LockstepExecutor::takeStall(std::size_t index, TimeNs now_ns) {
  for (const Stall& s : stalls_)
    if (s.index == index && now_ns >= s.from_ns && now_ns < s.until_ns) return s.run_ns;
  return 0;
}

void LockstepExecutor::releaseStalled(std::size_t index, TimeNs now_ns, DurationNs stall_ns) {
  TaskSet::Entry& entry = tasks_.entries()[index];
  const TaskSpec& spec = entry.binding.spec;
  const TimeNs end_ns = now_ns + stall_ns;
  busy_until_ns_[index] = end_ns;
  last_run_ns_[index] = now_ns;
  // The periods that begin inside the stall go unserved. They are counted when the stall ends, as the
  // real-time executor counts them when the late run returns (the supervisor sees them then, not before).
  const std::uint64_t skipped = entry.period_ns > 0 ? static_cast<std::uint64_t>((stall_ns - 1) / entry.period_ns) : 0;
  unreported_misses_[index] = skipped;
  if (startOverlapped(index, now_ns, stall_ns)) {  // outputs at end_ns; released again from then on
    if (!spec.triggered())
      next_release_ns_[index] += static_cast<DurationNs>(skipped + 1) * entry.period_ns;  // the grid, resynchronised
    else
      next_release_ns_[index] = spec.periodic() ? end_ns : kNeverNs;
    return;
  }
  // The step itself, at the stall's end, given the release's time as its now_ns: what the real-time
  // executor does for a step stalled after its wake-up (a task's time base is its release, its effects
  // are as late as the stall). Its schedule goes on from the stall's end.
  stalled_release_ns_[index] = now_ns;
  next_release_ns_[index] = end_ns;
}

void LockstepExecutor::release(std::size_t index, TimeNs now_ns) {
  const TaskSet::Entry& entry = tasks_.entries()[index];
  const TaskSpec& spec = entry.binding.spec;
  if (spec.triggered()) entry.binding.doorbell->consume();
  // A late step (its release's time kept) runs now; else this release may be one the stall holds up.
  const TimeNs stalled_ns = std::exchange(stalled_release_ns_[index], kNeverNs);
  if (stalled_ns == kNeverNs) {
    if (const DurationNs stall_ns = takeStall(index, now_ns); stall_ns > 0) {
      releaseStalled(index, now_ns, stall_ns);
      return;
    }
  }
  runOne(index, stalled_ns == kNeverNs ? now_ns : stalled_ns);
  last_run_ns_[index] = now_ns;
  if (!spec.triggered())
    next_release_ns_[index] += entry.period_ns;  // the fixed grid (now_ns was the release on it)
  else
    next_release_ns_[index] = spec.periodic() ? now_ns + entry.period_ns : kNeverNs;  // the fallback restarts
}

Status LockstepExecutor::runPendingEvents(TimeNs now_ns) {
  for (int round = 0; round < kMaxEventRoundsPerInstant; ++round) {
    bool ran = false;
    for (std::size_t i = 0; i < tasks_.entries().size(); ++i) {
      const TaskSet::Entry& e = tasks_.entries()[i];
      if (!e.binding.spec.triggered() || !e.binding.doorbell->pending()) continue;
      if (now_ns < busy_until_ns_[i]) {  // stalled: the ring is served when the stall ends
        next_release_ns_[i] = std::min(next_release_ns_[i], busy_until_ns_[i]);
        continue;
      }
      // A timed release due now (a cap's end, the fallback) runs in its priority order among the
      // releases of this instant, not after whichever step came first: so that when a task runs
      // depends only on its own writers and releases, not on the other tasks in the table (a replay
      // leaves the simulator's out and must run the same).
      if (next_release_ns_[i] <= now_ns) continue;
      const TimeNs earliest_ns = last_run_ns_[i] == kNeverNs ? now_ns : last_run_ns_[i] + e.min_period_ns;
      if (earliest_ns > now_ns) {
        // Inside the rate cap: a timed release at its end (left pending, consumed by that release).
        next_release_ns_[i] = std::min(next_release_ns_[i], earliest_ns);
        continue;
      }
      release(i, now_ns);
      ran = true;
    }
    if (!ran) return ok();
  }
  return Error{"event tasks kept triggering each other at t=" + std::to_string(now_ns) + " ns"};
}

Status LockstepExecutor::runUntil(TimeNs end_ns, const std::atomic<bool>* stop) {
  const std::vector<TaskSet::Entry>& entries = tasks_.entries();
  for (std::size_t i = next_release_ns_.size(); i < entries.size(); ++i) {  // new tasks start now
    next_release_ns_.push_back(entries[i].binding.spec.periodic() ? clock_.now() : kNeverNs);
    last_run_ns_.push_back(kNeverNs);
    busy_until_ns_.push_back(std::numeric_limits<TimeNs>::min());
    unreported_misses_.push_back(0);
    stalled_release_ns_.push_back(kNeverNs);
  }
  for (;;) {
    if (stop != nullptr && stop->load(std::memory_order_acquire)) break;
    std::size_t next = entries.size();
    for (std::size_t i = 0; i < entries.size(); ++i) {
      if (next_release_ns_[i] == kNeverNs) continue;
      if (next == entries.size() || next_release_ns_[i] < next_release_ns_[next] ||
          (next_release_ns_[i] == next_release_ns_[next] &&
           entries[i].binding.spec.priority > entries[next].binding.spec.priority))
        next = i;
    }
    const bool release_due = next != entries.size() && next_release_ns_[next] <= end_ns;
    // The earliest publication (first started on ties) goes before the releases at its instant.
    std::size_t first = pending_.size();
    for (std::size_t i = 0; i < pending_.size(); ++i)
      if (first == pending_.size() || pending_[i].publish_ns < pending_[first].publish_ns) first = i;
    if (first < pending_.size() && pending_[first].publish_ns <= end_ns &&
        (!release_due || pending_[first].publish_ns <= next_release_ns_[next])) {
      const TimeNs publish_ns = pending_[first].publish_ns;
      publish(first, publish_ns);
      if (Status s = runPendingEvents(publish_ns); !s) {
        joinWorker();
        return s;
      }
      continue;
    }
    if (!release_due) {
      // Nothing left before the end: advance to it so a later call continues from there.
      if (end_ns > clock_.now()) clock_.set(end_ns);
      Status s = runPendingEvents(clock_.now());
      joinWorker();
      return s;
    }
    const TimeNs release_ns = next_release_ns_[next];
    clock_.set(release_ns);
    release(next, release_ns);
    if (Status s = runPendingEvents(release_ns); !s) {
      joinWorker();
      return s;
    }
  }
  joinWorker();
  return ok();
}

}  // namespace aerotrack::rt
