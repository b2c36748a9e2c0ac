// Real-time executor: see realtime_executor.hpp.
#include "aerotrack/rt/realtime_executor.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <limits>

#include "aerotrack/rt/doorbell.hpp"

namespace aerotrack::rt {
namespace {

timespec toTimespec(TimeNs t_ns) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t_ns / kNsPerSecond);
  ts.tv_nsec = static_cast<long>(t_ns % kNsPerSecond);
  return ts;
}

// Sleeps until deadline_ns on CLOCK_MONOTONIC, waking at least every poll_ns to check stop.
// Returns false if stop was requested.
bool sleepUntil(TimeNs deadline_ns, const MonotonicClock& clock, DurationNs poll_ns, const std::atomic<bool>& stop) {
  for (;;) {
    if (stop.load(std::memory_order_acquire)) return false;
    const TimeNs now = clock.now();
    if (now >= deadline_ns) return true;
    const TimeNs wake_ns = std::min(deadline_ns, now + poll_ns);
    const timespec ts = toTimespec(wake_ns);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
  }
}

}  // namespace

RealtimeExecutor::RealtimeExecutor(const MonotonicClock& clock, RealtimeOptions options)
    : clock_(clock), options_(options) {}

RealtimeExecutor::~RealtimeExecutor() {
  requestStop();
  join();
}

Status RealtimeExecutor::add(const TaskBinding& binding) {
  if (!threads_.empty()) return Error{"cannot add task '" + binding.spec.name + "' after start()"};
  return tasks_.add(binding);
}

Status RealtimeExecutor::stall(const std::string& task, TimeNs from_ns, TimeNs until_ns, DurationNs run_ns) {
  if (!threads_.empty()) return Error{"stall: cannot stall task '" + task + "' after start()"};
  const Expected<std::size_t> index = tasks_.stallIndex(task, from_ns, until_ns, run_ns);
  if (!index) return index.error();
  stalls_.resize(tasks_.entries().size());
  if (stalls_[*index].from_ns != kNeverNs) return Error{"stall: task '" + task + "' already has a stall"};
  stalls_[*index] = {from_ns, until_ns, run_ns};
  return ok();
}

void RealtimeExecutor::runStep(TaskSet::Entry& e, TimeNs wake_ns) {
  const auto index = static_cast<std::size_t>(&e - tasks_.entries().data());
  if (index < stalls_.size() && wake_ns >= stalls_[index].from_ns && wake_ns < stalls_[index].until_ns)
    sleepUntil(wake_ns + stalls_[index].run_ns, clock_, options_.stop_poll_ns, stop_);
  e.binding.task->step(wake_ns);
}

Expected<std::vector<std::string>> RealtimeExecutor::start() {
  if (!threads_.empty()) return Error{"executor already started"};
  std::vector<std::string> warnings;
  if (options_.lock_memory && mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
    warnings.push_back(std::string("mlockall refused (") + std::strerror(errno) + "): memory may be paged out");

  // Threads wait at this gate until every one has its priority and affinity, then all start
  // from one common release time so that rate-related tasks stay in phase.
  std::atomic<bool> go{false};
  TimeNs first_release_ns = 0;
  try {
    for (TaskSet::Entry& e : tasks_.entries()) {
      threads_.emplace_back([this, &e, &go, &first_release_ns] {
        go.wait(false, std::memory_order_acquire);
        if (e.binding.spec.triggered())
          runTriggered(e, first_release_ns);
        else
          runPeriodic(e, first_release_ns);
      });
    }
  } catch (const std::system_error& ex) {
    requestStop();
    go.store(true, std::memory_order_release);
    go.notify_all();
    join();
    return Error{std::string("could not start a task thread: ") + ex.what()};
  }

  for (std::size_t i = 0; i < tasks_.entries().size(); ++i) {
    const TaskSpec& spec = tasks_.entries()[i].binding.spec;
    const pthread_t handle = threads_[i].native_handle();
    pthread_setname_np(handle, spec.name.substr(0, 15).c_str());
    if (options_.use_realtime_priority && spec.priority > 0) {
      sched_param param{};
      param.sched_priority = spec.priority;
      if (const int err = pthread_setschedparam(handle, SCHED_FIFO, &param); err != 0)
        warnings.push_back("task '" + spec.name + "': SCHED_FIFO priority " + std::to_string(spec.priority) +
                           " refused (" + std::strerror(err) + "); running at normal priority");
    }
    if (options_.use_affinity && spec.cpu >= 0) {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(spec.cpu, &set);
      if (const int err = pthread_setaffinity_np(handle, sizeof(set), &set); err != 0)
        warnings.push_back("task '" + spec.name + "': pinning to CPU " + std::to_string(spec.cpu) + " refused (" +
                           std::strerror(err) + ")");
    }
  }
  first_release_ns = clock_.now();
  go.store(true, std::memory_order_release);
  go.notify_all();
  // `go` and `first_release_ns` live on this stack frame: wait until every thread has passed the
  // gate before returning. Each thread copies first_release_ns before its first sleep.
  for (std::size_t n = started_.load(std::memory_order_acquire); n < tasks_.entries().size();
       n = started_.load(std::memory_order_acquire))
    started_.wait(n, std::memory_order_acquire);
  return warnings;
}

void RealtimeExecutor::runPeriodic(TaskSet::Entry& e, TimeNs first_release_ns) {
  started_.fetch_add(1, std::memory_order_acq_rel);
  started_.notify_all();
  TimingStats& stats = *e.stats;
  TimeNs release_ns = first_release_ns;
  while (sleepUntil(release_ns, clock_, options_.stop_poll_ns, stop_)) {
    const TimeNs wake_ns = clock_.now();
    stats.recordWakeLatency(wake_ns - release_ns);
    runStep(e, wake_ns);
    const TimeNs end_ns = clock_.now();
    stats.recordRun(end_ns - wake_ns);
    release_ns += e.period_ns;
    if (end_ns > release_ns) {
      // Overran into later periods: skip them and resynchronise to the next future release.
      const auto skipped = static_cast<std::uint64_t>((end_ns - release_ns) / e.period_ns) + 1;
      stats.addMissedDeadlines(skipped);
      // An observer's misses are its own (a recorder starved by the flight): the flight is not told.
      if (options_.deadline_misses != nullptr && !e.binding.spec.observer)
        options_.deadline_misses->fetch_add(skipped, std::memory_order_relaxed);
      release_ns += static_cast<DurationNs>(skipped) * e.period_ns;
    }
  }
}

void RealtimeExecutor::runTriggered(TaskSet::Entry& e, TimeNs first_release_ns) {
  started_.fetch_add(1, std::memory_order_acq_rel);
  started_.notify_all();
  TimingStats& stats = *e.stats;
  Doorbell& doorbell = *e.binding.doorbell;
  // The fallback release (kNeverNs without a rate) and the previous run (kNeverNs: none yet).
  TimeNs fallback_ns = e.period_ns > 0 ? first_release_ns : kNeverNs;
  TimeNs last_run_ns = kNeverNs;
  while (!stop_.load(std::memory_order_acquire)) {
    const TimeNs now_ns = clock_.now();
    const bool rang = doorbell.pending();
    // A ring releases it now, the fallback at its time, and neither before the cap's end (a late
    // wake-up must not bring the fallback closer to it than the cap either).
    TimeNs release_ns = rang ? std::min(fallback_ns, now_ns) : fallback_ns;
    if (last_run_ns != kNeverNs) release_ns = std::max(release_ns, last_run_ns + e.min_period_ns);
    if (now_ns < release_ns) {
      if (rang)  // inside the rate cap: sleep to its end (the ring stays pending)
        sleepUntil(release_ns, clock_, options_.stop_poll_ns, stop_);
      else  // wait for a ring, or the fallback release
        doorbell.waitFor(std::min(release_ns - now_ns, options_.stop_poll_ns));
      continue;
    }
    doorbell.consume();  // before the step reads its inputs: a ring during the step stays pending
    const TimeNs wake_ns = clock_.now();
    stats.recordWakeLatency(wake_ns - release_ns);
    runStep(e, wake_ns);
    const TimeNs end_ns = clock_.now();
    stats.recordRun(end_ns - wake_ns);
    last_run_ns = wake_ns;
    if (e.period_ns > 0) {
      fallback_ns = release_ns + e.period_ns;  // the fallback restarts at every run
      if (end_ns > fallback_ns) {
        const auto skipped = static_cast<std::uint64_t>((end_ns - fallback_ns) / e.period_ns) + 1;
        stats.addMissedDeadlines(skipped);
        if (options_.deadline_misses != nullptr && !e.binding.spec.observer)
          options_.deadline_misses->fetch_add(skipped, std::memory_order_relaxed);
        fallback_ns += static_cast<DurationNs>(skipped) * e.period_ns;
      }
    }
  }
}

void RealtimeExecutor::join() {
  for (std::thread& t : threads_)
    if (t.joinable()) t.join();
}

}  // namespace aerotrack::rt
