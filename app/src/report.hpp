// Reports at exit: the per-task timing table for people and its JSON form for summary.json.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "aerotrack/hal/factory.hpp"
#include "aerotrack/rt/timing_stats.hpp"

namespace aerotrack::app {

struct TaskTiming {
  std::string name;
  rt::TimingSnapshot timing;
};

/// Snapshots an executor's stats() list (LockstepExecutor or RealtimeExecutor).
template <class NamedStatsList>
std::vector<TaskTiming> snapshotTimings(const NamedStatsList& stats) {
  std::vector<TaskTiming> out;
  out.reserve(stats.size());
  for (const auto& s : stats) out.push_back({s.name, s.stats->snapshot()});
  return out;
}

std::string timingTable(const std::vector<TaskTiming>& timings);
/// {name: {runs, overruns, missed_deadlines, p50_ms, p99_ms, max_ms, mean_ms}}
nlohmann::json timingJson(const std::vector<TaskTiming>& timings);
/// One line per device: "odometry (sim): ok - simulated ground truth".
std::string deviceHealthReport(const hal::Devices& devices, rt::TimeNs now_ns);

}  // namespace aerotrack::app
