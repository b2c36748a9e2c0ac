// `aerotrack sim --scenario NAME|FILE [--seed N] [--speed MPS] [--camera keypoints|image] [--out DIR] [--realtime]
// [--config FILE]`:
// one closed-loop trial in the built-in simulator, on the lockstep executor (deterministic, as
// fast as the CPU allows) or at 1x on threads with --realtime. Writes DIR/summary.json and
// DIR/topdown.png. With --camera image the gimbal camera renders frames and the real detector
// (the detection task) finds the person in them. The planner (the planning task, issue 8) flies the drone from the
// estimated person; until gimbal control lands (issue 9) the gimbal is aimed from the truth (task truth_gimbal).
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <thread>

#include "commands.hpp"
#include "paths.hpp"
#include "report.hpp"
#include "run_executors.hpp"
#include "signals.hpp"
#include "sim_report.hpp"
#include "suite.hpp"
#include "system.hpp"

namespace aerotrack::app {
int simCommand(const ParsedArgs& args) {
  const std::string mode = args.valueOr("mode", "proposed");
  if (const std::string bad = badModeError(mode); !bad.empty()) return failCommand("sim", bad);
  const auto seed = parseInt("seed", args.valueOr("seed", "1"), 0, INT64_MAX);
  if (!seed) return failCommand("sim", seed.error().message);
  std::optional<double> speed;
  if (args.has("speed")) {
    const auto s = parseDouble("speed", args.values.at("speed"), 0.05, 20.0);
    if (!s) return failCommand("sim", s.error().message);
    speed = *s;
  }
  const auto overrides = configOverrides(args);
  if (!overrides) return failCommand("sim", overrides.error().message);
  auto config = loadAppConfig(args.valueOr("config", configDir() + "/sim.yaml"), *overrides);
  if (!config) return failCommand("sim", config.error().message);
  if (!config->hal.usesSim()) return failCommand("sim", config->source + ": hal: no device uses the sim backend");
  config->baseline_mode = mode == "baseline";
  if (mode == "truth_flight") System::flyFromTruth(config->tasks);
  config->record_dir = args.valueOr("record", "");
  config->mcap_path = args.valueOr("mcap", "");
  config->mcap_compression = args.valueOr("mcap-compression", "zstd");
  config->live_address = args.valueOr("live", "");
  const std::string scenario_name = args.values.at("scenario");
  auto trial = loadTrial(scenario_name, static_cast<std::uint64_t>(*seed), speed);
  if (!trial) return failCommand("sim", trial.error().message);
  if (args.has("camera")) {
    const std::string camera = args.values.at("camera");
    if (camera != "keypoints" && camera != "image")
      return failCommand("sim", "--camera: expected keypoints or image, got '" + camera + "'");
    trial->spec.gimbal_camera.mode =
        camera == "image" ? hal::sim::GimbalCameraMode::kImage : hal::sim::GimbalCameraMode::kKeypoints;
  }
  config->sim.scenario = scenario_name;
  config->sim.seed = static_cast<std::uint64_t>(*seed);
  const std::string out_dir = args.valueOr("out", "out/sim-" + trial->spec.name + "-" + std::to_string(*seed));
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) return failCommand("sim", out_dir + ": cannot create directory: " + ec.message());

  const bool realtime = args.flags.count("realtime") != 0;
  if (args.has("live") && !realtime)
    return failCommand("sim",
                       "--live: needs --realtime (a lockstep run goes faster than real time: nothing to watch live)");
  config->record_lossless = !realtime;
  rt::ManualClock sim_clock(0);
  const rt::MonotonicClock mono_clock;
  const rt::TimeNs start_ns = realtime ? mono_clock.now() : 0;
  std::atomic<bool> stop{false};
  SignalWatcher signals(stop);
  auto system = System::build(*config, &trial.value(), start_ns);
  if (!system) return failCommand("sim", system.error().message);

  RunInfo info;
  info.executor = realtime ? "realtime" : "lockstep";
  info.controller = mode == "truth_flight"
                        ? "truth_flight (flown from the truth; perception and estimation as proposed)"
                    : (*system)->planningTask() == nullptr ? "baseline_follow (truth-fed stand-in)"
                    : config->baseline_mode ? "baseline (Fast-Tracker 1.0: fixed camera, no occlusion term)"
                                            : "proposed";
  const rt::TimeNs end_ns = start_ns + rt::secondsToNs(trial->duration_s);
  const rt::Status ran = realtime ? runRealtime(**system, mono_clock, start_ns, end_ns, stop, info, "sim")
                                  : runLockstep(**system, sim_clock, end_ns, stop, info);
  if (!ran) return failCommand("sim", ran.error().message);
  info.interrupted = stop.load();
  info.map = mapSummary((*system)->mappingTask(), info.timings);
  info.perception = perceptionSummary((*system)->detectionTask());
  info.estimation = estimationSummary((*system)->targetTask(), (*system)->targetCheckTask());
  info.planning = planningSummary((*system)->planningTask());
  double supervisor_step_s = 0.0;
  for (const rt::TaskSpec& spec : config->tasks) {
    if (spec.name == "supervisor" && spec.periodic()) supervisor_step_s = 1.0 / spec.rate_hz;
  }
  info.latency = latencySummary((*system)->trajectoryServerTask());
  info.supervisor = supervisorSummary((*system)->supervisorTask(), start_ns, supervisor_step_s);

  const hal::sim::Simulation& sim = *(*system)->devices().simulation;
  nlohmann::json summary = simSummary(sim, info);
  // The config values this trial ran with beyond its file (a sweep's point: bench --set).
  summary["set"] = nlohmann::json::object();
  for (const rt::ConfigOverride& o : *overrides) summary["set"][o.key] = o.value;
  const std::string summary_path = out_dir + "/summary.json";
  // Written aside and renamed: a trial killed while writing leaves no half summary to be merged.
  std::ofstream file(summary_path + ".tmp", std::ios::trunc);
  file << summary.dump(2) << "\n";
  file.close();
  std::error_code renamed;
  if (file) std::filesystem::rename(summary_path + ".tmp", summary_path, renamed);
  if (!file || renamed) return failCommand("sim", summary_path + ": write failed");
  const std::string topdown_path = out_dir + "/topdown.png";
  if (const rt::Status s = drawTopdown(sim, topdown_path); !s) return failCommand("sim", s.error().message);
  std::string strip_path;
  if (const CameraStripTask* strip = (*system)->cameraStripTask(); strip != nullptr && strip->panels() > 0) {
    strip_path = out_dir + "/camera_strip.png";
    if (const rt::Status s = strip->write(strip_path); !s) return failCommand("sim", s.error().message);
  }

  const hal::sim::SimMetrics& m = sim.metrics();
  std::printf("%s seed %lld (%s): %s%s\n", trial->spec.name.c_str(), static_cast<long long>(*seed),
              info.executor.c_str(), m.success() ? "success" : "FAILURE: ", m.failureReason().c_str());
  std::printf(
      "  %.1f s simulated in %.2f s wall (%.0fx real time); person visible %.0f%% of the time, longest loss %.1f s\n",
      info.sim_time_s, info.wall_time_s, summary["realtime_factor"].get<double>(), 100.0 * m.visibleRatio(),
      m.longestLossS());
  std::printf("  distance to the person: mean %.2f m, max %.2f m, final %.2f m; min clearance %.2f m, collisions %d\n",
              m.distanceMeanM(), m.distanceMaxM(), m.finalDistanceM(), m.minClearanceM(), m.collisions());
  if (const supervisor::SupervisorTask* sup = (*system)->supervisorTask()) {
    std::printf("  supervisor: %zu transitions, ends in %s (%s)\n", sup->transitionCount(),
                std::string(supervisor::toString(sup->state().mode)).c_str(),
                std::string(supervisor::toString(sup->state().reason)).c_str());
  }
  if (info.latency.is_object() && info.latency["samples"].get<std::uint64_t>() > 0) {
    std::printf("  end-to-end latency, image capture to first setpoint: %.0f ms median, %.0f ms p99\n",
                info.latency["capture_to_setpoint_ms_p50"].get<double>(),
                info.latency["capture_to_setpoint_ms_p99"].get<double>());
  }
  if (const planning::PlanningTask* planner = (*system)->planningTask()) {
    const rt::TimingSnapshot cycle = planner->cycleStats().snapshot();
    std::printf("  planning: %llu cycles, %llu planned, %llu stops; cycle %.2f ms median, %.2f ms p99\n",
                static_cast<unsigned long long>(planner->cycles()),
                static_cast<unsigned long long>(planner->count(planning::PlanStatus::kPlanned)),
                static_cast<unsigned long long>(planner->count(planning::PlanStatus::kStopped)), cycle.p50_ms,
                cycle.p99_ms);
  }
  std::fputs(timingTable(info.timings).c_str(), stdout);
  if (auto recorded = (*system)->finishRecording(realtime ? mono_clock.now() : sim_clock.now()); !recorded) {
    std::fprintf(stderr, "aerotrack sim: %s\n", recorded.error().message.c_str());
  } else if (!recorded->empty()) {
    std::printf("%s\n", recorded->c_str());
  }
  if (const std::string logged = (*system)->finishFlightLog(); !logged.empty()) std::printf("%s\n", logged.c_str());
  std::printf("results: %s, %s%s%s\n", summary_path.c_str(), topdown_path.c_str(), strip_path.empty() ? "" : ", ",
              strip_path.c_str());
  return info.interrupted ? signals.stoppedStatus() : 0;
}

}  // namespace aerotrack::app
