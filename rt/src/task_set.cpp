// TaskSet: see task_set.hpp.
#include "aerotrack/rt/task_set.hpp"

namespace aerotrack::rt {

Status TaskSet::add(const TaskBinding& binding) {
  const TaskSpec& spec = binding.spec;
  if (Status s = validate(spec); !s) return s;
  if (binding.task == nullptr) return Error{"task '" + spec.name + "' has no implementation"};
  if (spec.triggered() && binding.doorbell == nullptr)
    return Error{"event task '" + spec.name + "' has no doorbell for trigger '" + spec.trigger + "'"};
  for (const Entry& e : entries_)
    if (e.binding.spec.name == spec.name) return Error{"task '" + spec.name + "' added twice"};
  Entry entry;
  entry.binding = binding;
  entry.period_ns = spec.periodic() ? periodFromRateHz(spec.rate_hz) : 0;
  entry.min_period_ns = millisecondsToNs(spec.min_period_ms);
  entry.stats = std::make_unique<TimingStats>(millisecondsToNs(spec.budget_ms));
  entries_.push_back(std::move(entry));
  return ok();
}

Expected<std::size_t> TaskSet::stallIndex(const std::string& name, TimeNs from_ns, TimeNs until_ns,
                                          DurationNs run_ns) const {
  std::size_t index = 0;
  while (index < entries_.size() && entries_[index].binding.spec.name != name) ++index;
  if (index == entries_.size()) {
    std::string names;
    for (const Entry& e : entries_) {
      if (!names.empty()) names += ", ";
      names += e.binding.spec.name;
    }
    return Error{"stall: no task named '" + name + "' (tasks: " + names + ")"};
  }
  if (run_ns <= 0 || until_ns <= from_ns)
    return Error{"stall: task '" + name + "' needs a window that ends after it begins and a positive run time"};
  return index;
}

std::vector<TaskSet::NamedStats> TaskSet::stats() const {
  std::vector<NamedStats> out;
  out.reserve(entries_.size());
  for (const Entry& e : entries_) out.push_back({e.binding.spec.name, e.stats.get()});
  return out;
}

}  // namespace aerotrack::rt
