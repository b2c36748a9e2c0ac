// Lockstep executor: see lockstep_executor.hpp. The next step is found by a linear scan over the
// table (a dozen tasks), which keeps the order rule obvious: earliest release, then higher
// priority, then table order.
#include "aerotrack/rt/lockstep_executor.hpp"

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

LockstepExecutor::LockstepExecutor(ManualClock& sim_clock, const Clock& stats_clock)
    : clock_(sim_clock), stats_clock_(stats_clock) {}

void LockstepExecutor::runOne(std::size_t index, TimeNs now_ns) {
  TaskSet::Entry& entry = tasks_.entries()[index];
  const TimeNs begin = stats_clock_.now();
  entry.binding.task->step(now_ns);
  entry.stats->recordRun(stats_clock_.now() - begin);
  hashMix(trace_hash_, index);
  hashMix(trace_hash_, static_cast<std::uint64_t>(now_ns));
  ++steps_;
}

Status LockstepExecutor::runPendingEvents(TimeNs now_ns) {
  for (int round = 0; round < kMaxEventRoundsPerInstant; ++round) {
    bool ran = false;
    for (std::size_t i = 0; i < tasks_.entries().size(); ++i) {
      const TaskBinding& b = tasks_.entries()[i].binding;
      if (b.spec.periodic() || !b.doorbell->pending()) continue;
      b.doorbell->consume();
      runOne(i, now_ns);
      ran = true;
    }
    if (!ran) return ok();
  }
  return Error{"event tasks kept triggering each other at t=" + std::to_string(now_ns) + " ns"};
}

Status LockstepExecutor::runUntil(TimeNs end_ns, const std::atomic<bool>* stop) {
  const std::vector<TaskSet::Entry>& entries = tasks_.entries();
  next_release_ns_.resize(entries.size(), clock_.now());  // new tasks start now
  for (;;) {
    if (stop != nullptr && stop->load(std::memory_order_acquire)) return ok();
    std::size_t next = entries.size();
    for (std::size_t i = 0; i < entries.size(); ++i) {
      if (!entries[i].binding.spec.periodic()) continue;
      if (next == entries.size() || next_release_ns_[i] < next_release_ns_[next] ||
          (next_release_ns_[i] == next_release_ns_[next] &&
           entries[i].binding.spec.priority > entries[next].binding.spec.priority))
        next = i;
    }
    if (next == entries.size() || next_release_ns_[next] > end_ns) {
      // Nothing periodic left before the end: advance to it so a later call continues from there.
      if (end_ns > clock_.now()) clock_.set(end_ns);
      return runPendingEvents(clock_.now());
    }
    const TimeNs release_ns = next_release_ns_[next];
    clock_.set(release_ns);
    runOne(next, release_ns);
    next_release_ns_[next] += entries[next].period_ns;
    if (Status s = runPendingEvents(release_ns); !s) return s;
  }
}

}  // namespace aerotrack::rt
