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

Status LockstepExecutor::add(const TaskBinding& binding) {
  if (Status s = validate(binding.spec); !s) return s;
  if (binding.task == nullptr) return Error{"task '" + binding.spec.name + "' has no implementation"};
  if (!binding.spec.periodic() && binding.doorbell == nullptr)
    return Error{"event task '" + binding.spec.name + "' has no doorbell for trigger '" + binding.spec.trigger + "'"};
  for (const Entry& e : entries_)
    if (e.binding.spec.name == binding.spec.name) return Error{"task '" + binding.spec.name + "' added twice"};
  Entry entry;
  entry.binding = binding;
  entry.period_ns = binding.spec.periodic() ? periodFromRateHz(binding.spec.rate_hz) : 0;
  entry.stats = std::make_unique<TimingStats>(millisecondsToNs(binding.spec.budget_ms));
  entries_.push_back(std::move(entry));
  return ok();
}

void LockstepExecutor::runOne(Entry& entry, std::size_t index, TimeNs now_ns) {
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
    for (std::size_t i = 0; i < entries_.size(); ++i) {
      Entry& e = entries_[i];
      if (e.binding.spec.periodic() || !e.binding.doorbell->pending()) continue;
      e.binding.doorbell->consume();
      runOne(e, i, now_ns);
      ran = true;
    }
    if (!ran) return ok();
  }
  return Error{"event tasks kept triggering each other at t=" + std::to_string(now_ns) + " ns"};
}

Status LockstepExecutor::runUntil(TimeNs end_ns, const std::atomic<bool>* stop) {
  const TimeNs start_ns = clock_.now();
  for (Entry& e : entries_) {
    if (!e.started) {
      e.next_release_ns = start_ns;
      e.started = true;
    }
  }
  for (;;) {
    if (stop != nullptr && stop->load(std::memory_order_acquire)) return ok();
    Entry* next = nullptr;
    std::size_t next_index = 0;
    for (std::size_t i = 0; i < entries_.size(); ++i) {
      Entry& e = entries_[i];
      if (!e.binding.spec.periodic()) continue;
      if (next == nullptr || e.next_release_ns < next->next_release_ns ||
          (e.next_release_ns == next->next_release_ns && e.binding.spec.priority > next->binding.spec.priority)) {
        next = &e;
        next_index = i;
      }
    }
    if (next == nullptr || next->next_release_ns > end_ns) {
      // Nothing periodic left before the end: advance to it so a later call continues from there.
      if (end_ns > clock_.now()) clock_.set(end_ns);
      return runPendingEvents(clock_.now());
    }
    const TimeNs release_ns = next->next_release_ns;
    clock_.set(release_ns);
    runOne(*next, next_index, release_ns);
    next->next_release_ns += next->period_ns;
    if (Status s = runPendingEvents(release_ns); !s) return s;
  }
}

std::vector<LockstepExecutor::NamedStats> LockstepExecutor::stats() const {
  std::vector<NamedStats> out;
  out.reserve(entries_.size());
  for (const Entry& e : entries_) out.push_back({e.binding.spec.name, e.stats.get()});
  return out;
}

}  // namespace aerotrack::rt
