// What a simulated run leaves behind (issue 3, docs/command-line.md "sim outputs"): summary.json with the
// verdict and the ground-truth metrics, and topdown.png (obstacles, the person's path, the
// drone's path coloured by whether the person was visible, loss events marked).
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "aerotrack/estimation/target_task.hpp"
#include "aerotrack/hal/sim/simulation.hpp"
#include "aerotrack/mapping/mapping_task.hpp"
#include "aerotrack/perception/detection_task.hpp"
#include "aerotrack/planning/planning_task.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/supervisor/supervisor_task.hpp"
#include "aerotrack/trajectory_server/trajectory_server_task.hpp"
#include "report.hpp"

namespace aerotrack::app {

struct RunInfo {
  std::string executor;    ///< "lockstep" or "realtime"
  std::string controller;  ///< what flew the drone, e.g. "baseline_follow"
  double sim_time_s = 0.0;
  double wall_time_s = 0.0;
  bool interrupted = false;
  std::string trace_hash;  ///< lockstep only
  std::vector<TaskTiming> timings;
  nlohmann::json map;         ///< mapSummary()
  nlohmann::json perception;  ///< perceptionSummary()
  nlohmann::json estimation;  ///< estimationSummary()
  nlohmann::json planning;    ///< planningSummary()
  nlohmann::json supervisor;  ///< supervisorSummary()
  nlohmann::json latency;     ///< latencySummary()
};

/// End-to-end latency, image capture to the first setpoint of the trajectory planned from it (null
/// without a trajectory server task). Simulated time in lockstep; wall time on threads.
nlohmann::json latencySummary(const trajectory_server::TrajectoryServerTask* task);

class TargetTruthCheckTask;
/// The estimation section of summary.json (null if the run had no target task).
nlohmann::json estimationSummary(const estimation::TargetTask* task, const TargetTruthCheckTask* check);

/// The planning section of summary.json (null if the run had no planning task): cycles by outcome,
/// the replanning cycle's time (prediction + search + corridor + optimisation + check) and counters.
nlohmann::json planningSummary(const planning::PlanningTask* task);

/// The supervisor section of summary.json (null without a supervisor task): the final mode and reason,
/// every transition (time since start, mode, reason) and the seconds spent in each mode.
nlohmann::json supervisorSummary(const supervisor::SupervisorTask* task, rt::TimeNs start_ns, double step_s);

/// The perception section of summary.json (null if the run had no detection task).
nlohmann::json perceptionSummary(const perception::DetectionTask* task);

/// The map section of summary.json (null if the run had no mapping task).
nlohmann::json mapSummary(const mapping::MappingTask* task, const std::vector<TaskTiming>& timings);

nlohmann::json simSummary(const hal::sim::Simulation& sim, const RunInfo& run);

/// Draws the top view of the run; error if the file cannot be written.
rt::Status drawTopdown(const hal::sim::Simulation& sim, const std::string& png_path);

/// Loads a scenario (name in config/scenarios/ or a file) and instantiates one trial.
rt::Expected<hal::sim::ScenarioInstance> loadTrial(const std::string& name_or_file, std::uint64_t seed,
                                                   std::optional<double> speed_override_mps);

}  // namespace aerotrack::app
