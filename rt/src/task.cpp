// Validation of task-table rows.
#include "aerotrack/rt/task.hpp"

#include <cmath>
#include <set>

namespace aerotrack::rt {

Status validate(const TaskSpec& spec) {
  const std::string where = "task '" + spec.name + "': ";
  if (spec.name.empty()) return Error{"task with an empty name"};
  if (!std::isfinite(spec.rate_hz) || spec.rate_hz < 0.0 || spec.rate_hz > 100000.0)
    return Error{where + "rate_hz must be in [0, 100000]"};
  if (!spec.periodic() && !spec.triggered())
    return Error{where + "needs a rate_hz (periodic), a trigger (event) or both (event, periodic fallback)"};
  if (!std::isfinite(spec.min_period_ms) || spec.min_period_ms < 0.0 || spec.min_period_ms > 10000.0)
    return Error{where + "min_period_ms must be in [0, 10000]"};
  if (spec.min_period_ms > 0.0 && !spec.triggered())
    return Error{where + "min_period_ms (a rate cap) needs a trigger: a periodic task runs at its rate"};
  if (spec.periodic() && spec.min_period_ms * 1e-3 * spec.rate_hz > 1.0)
    return Error{where + "min_period_ms must be at most the fallback period (1 / rate_hz)"};
  if (!std::isfinite(spec.budget_ms) || spec.budget_ms <= 0.0 || spec.budget_ms > 10000.0)
    return Error{where + "budget_ms must be in (0, 10000]"};
  if (spec.priority < 0 || spec.priority > 99) return Error{where + "priority must be in [0, 99]"};
  if (spec.cpu < -1 || spec.cpu > 1023) return Error{where + "cpu must be -1 (any) or in [0, 1023]"};
  if (!std::isfinite(spec.latency_ms) || spec.latency_ms < 0.0 || spec.latency_ms > spec.budget_ms)
    return Error{where + "latency_ms must be in [0, budget_ms]"};
  if (spec.periodic() && spec.latency_ms * 1e-3 * spec.rate_hz > 1.0)
    return Error{where + "latency_ms must be at most the period"};
  return ok();
}

Status validate(const std::vector<TaskSpec>& table) {
  std::set<std::string> names;
  for (const TaskSpec& spec : table) {
    if (Status s = validate(spec); !s) return s;
    if (!names.insert(spec.name).second) return Error{"task '" + spec.name + "' appears twice in the table"};
  }
  return ok();
}

}  // namespace aerotrack::rt
