// `aerotrack sim --scenario NAME|FILE [--seed N] [--out DIR] [--realtime] [--config FILE]`.
//
// Foundation version: the scenario's drone flies a minimum-jerk tour of waypoints through the
// trajectory server and the simulated flight controller, on the lockstep executor (or at 1x on
// threads with --realtime), and the run is summarised in DIR/summary.json. The person, obstacles,
// sensors and planner replace the tour as later issues land (README, "Status").
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <thread>

#include "aerotrack/rt/lockstep_executor.hpp"
#include "aerotrack/rt/realtime_executor.hpp"
#include "aerotrack/trajectory_server/min_jerk_tour.hpp"
#include "commands.hpp"
#include "paths.hpp"
#include "report.hpp"
#include "scenario.hpp"
#include "signals.hpp"
#include "system.hpp"

namespace aerotrack::app {
namespace {

int fail(const std::string& message) {
  std::fprintf(stderr, "aerotrack sim: %s\n", message.c_str());
  return 1;
}

struct RunOutcome {
  std::vector<TaskTiming> timings;
  double sim_time_s = 0.0;
  double wall_time_s = 0.0;
  std::uint64_t trace_hash = 0;  // lockstep only
  bool interrupted = false;
};

rt::Status addAll(const System& system, auto& executor) {
  for (const rt::TaskBinding& b : system.bindings())
    if (rt::Status s = executor.add(b); !s) return s;
  return rt::ok();
}

rt::Expected<RunOutcome> runLockstep(System& system, rt::ManualClock& clock, rt::TimeNs end_ns,
                                     const std::atomic<bool>& stop) {
  const rt::MonotonicClock wall;
  rt::LockstepExecutor executor(clock, wall);
  if (rt::Status s = addAll(system, executor); !s) return s.error();
  const rt::TimeNs wall_start = wall.now();
  if (rt::Status s = executor.runUntil(end_ns, &stop); !s) return s.error();
  RunOutcome out;
  out.wall_time_s = rt::nsToSeconds(wall.now() - wall_start);
  out.sim_time_s = rt::nsToSeconds(clock.now());
  out.timings = snapshotTimings(executor.stats());
  out.trace_hash = executor.traceHash();
  out.interrupted = stop.load();
  return out;
}

rt::Expected<RunOutcome> runRealtime(System& system, const rt::MonotonicClock& clock, rt::TimeNs start_ns,
                                     rt::TimeNs end_ns, const std::atomic<bool>& stop) {
  rt::RealtimeExecutor executor(clock, system.config().realtime);
  if (rt::Status s = addAll(system, executor); !s) return s.error();
  const auto warnings = executor.start();
  if (!warnings) return warnings.error();
  for (const std::string& w : *warnings) std::fprintf(stderr, "aerotrack sim: warning: %s\n", w.c_str());
  while (!stop.load() && clock.now() < end_ns) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  executor.requestStop();
  executor.join();
  RunOutcome out;
  out.sim_time_s = rt::nsToSeconds(clock.now() - start_ns);
  out.wall_time_s = out.sim_time_s;
  out.timings = snapshotTimings(executor.stats());
  out.interrupted = stop.load();
  return out;
}

}  // namespace

int simCommand(const ParsedArgs& args) {
  if (args.has("mode"))
    return std::fprintf(stderr, "aerotrack sim: --mode is not available yet: planner modes arrive with issue 9\n"), 2;
  const auto seed = parseInt("seed", args.valueOr("seed", "1"), 0, INT64_MAX);
  if (!seed) return fail(seed.error().message);
  const auto scenario = loadScenario(resolveScenario(args.values.at("scenario")));
  if (!scenario) return fail(scenario.error().message);
  auto config = loadAppConfig(args.valueOr("config", configDir() + "/sim.yaml"));
  if (!config) return fail(config.error().message);
  if (!config->hal.usesSim()) return fail(config->source + ": hal: no device uses the sim backend");
  config->sim.start_p_W_m = scenario->drone_start_m;
  config->sim.start_yaw_rad = scenario->drone_start_yaw_rad;
  config->trajectory_server.initial_yaw_rad = scenario->drone_start_yaw_rad;
  const std::string out_dir = args.valueOr("out", "out/sim-" + scenario->name + "-" + std::to_string(*seed));

  const bool realtime = args.flags.count("realtime") != 0;
  rt::ManualClock sim_clock(0);
  const rt::MonotonicClock mono_clock;
  const rt::TimeNs start_ns = realtime ? mono_clock.now() : 0;

  std::atomic<bool> stop{false};
  SignalWatcher signals(stop);
  auto system = System::build(*config, start_ns);
  if (!system) return fail(system.error().message);

  // The tour starts at the drone's start position; the vehicle's limits cap the scenario's.
  std::vector<Eigen::Vector3d> waypoints{scenario->drone_start_m};
  waypoints.insert(waypoints.end(), scenario->tour_waypoints_m.begin(), scenario->tour_waypoints_m.end());
  auto tour = trajectory_server::MinJerkTour::create(
      waypoints, std::min(scenario->tour_max_speed_mps, config->vehicle.max_speed_mps),
      std::min(scenario->tour_max_accel_mps2, config->vehicle.max_accel_mps2));
  if (!tour) return fail(scenario->source + ": tour: " + tour.error().message);
  const auto tour_handle = std::make_shared<const trajectory_server::MinJerkTour>(std::move(tour.value()));
  (*system)->channels().trajectories.write(std::make_shared<const trajectory_server::TimedTrajectory>(
      trajectory_server::TimedTrajectory{tour_handle, start_ns + rt::secondsToNs(scenario->tour_start_delay_s)}));

  const rt::TimeNs end_ns = start_ns + rt::secondsToNs(scenario->duration_s);
  auto outcome = realtime ? runRealtime(**system, mono_clock, start_ns, end_ns, stop)
                          : runLockstep(**system, sim_clock, end_ns, stop);
  if (!outcome) return fail(outcome.error().message);

  const hal::sim::PointMassWorld& world = *(*system)->devices().world;
  const hal::sim::PointMassTruth truth = world.truth();
  const double final_error_m = (truth.p_W_m - waypoints.back()).norm();
  const double rtf = outcome->wall_time_s > 0.0 ? outcome->sim_time_s / outcome->wall_time_s : 0.0;
  nlohmann::json summary = {
      {"scenario", scenario->name},
      {"seed", *seed},
      {"executor", realtime ? "realtime" : "lockstep"},
      {"interrupted", outcome->interrupted},
      {"sim_time_s", outcome->sim_time_s},
      {"wall_time_s", outcome->wall_time_s},
      {"realtime_factor", rtf},
      {"tour_duration_s", tour_handle->durationS()},
      {"setpoints_received", world.setpointsReceived()},
      {"tracking_error_mean_m", world.trackingStats().meanErrorM()},
      {"tracking_error_max_m", world.trackingStats().max_error_m},
      {"final_position_error_m", final_error_m},
      {"tasks", timingJson(outcome->timings)},
  };
  if (!realtime) {
    char hash[32];
    std::snprintf(hash, sizeof(hash), "%016llx", static_cast<unsigned long long>(outcome->trace_hash));
    summary["trace_hash"] = hash;
  }

  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) return fail(out_dir + ": cannot create directory: " + ec.message());
  const std::string summary_path = out_dir + "/summary.json";
  std::ofstream file(summary_path);
  file << summary.dump(2) << "\n";
  file.close();
  if (!file) return fail(summary_path + ": write failed");

  std::printf("scenario %s, seed %lld, %s: %.1f s simulated in %.3f s wall (%.0fx real time)\n", scenario->name.c_str(),
              static_cast<long long>(*seed), realtime ? "realtime" : "lockstep", outcome->sim_time_s,
              outcome->wall_time_s, rtf);
  std::printf("setpoint tracking error: mean %.3f m, max %.3f m; final distance to the last waypoint %.3f m\n",
              world.trackingStats().meanErrorM(), world.trackingStats().max_error_m, final_error_m);
  std::fputs(timingTable(outcome->timings).c_str(), stdout);
  std::printf("summary: %s\n", summary_path.c_str());
  return outcome->interrupted ? 130 : 0;
}

}  // namespace aerotrack::app
