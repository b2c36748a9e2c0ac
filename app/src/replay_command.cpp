// `aerotrack replay DIR [--compare] [--config FILE] [--out DIR] [--offset-s S] [--strict] [--realtime]`
// (issue 10 item 5): re-runs the modules on a recording. Every device the recording holds is served
// from it (hal/replay), the others are null; the configuration is the recorded run's own
// (DIR/config.yaml) unless --config names another; the simulator's stand-ins are left out. Lockstep
// by default: as fast as the CPU allows and deterministic, on the recording's own clock. With
// --compare, the replay is recorded too (OUT/replayed) and its outputs -- what the gimbal and the
// flight controller were told, the detections, the target estimates, the planned trajectories, and
// what the devices delivered -- are compared with the recorded ones record by record; the exit status
// is 3 if any differs.
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <system_error>

#include "aerotrack/hal/replay/manifest.hpp"
#include "commands.hpp"
#include "dataset_compare.hpp"
#include "report.hpp"
#include "run_executors.hpp"
#include "signals.hpp"
#include "system.hpp"

namespace aerotrack::app {
namespace {

constexpr int kDiffers = 3;  // the exit status when --compare finds a difference (cli.cpp's usage)

bool simulatorOnly(const std::string& task) {
  return task == "sim_world" || task == "target_check" || task == "truth_gimbal" || task == "baseline_follow" ||
         task == "camera_strip";
}

/// A folder this command wrote before (its manifest says source: replay) may be replaced; anything else
/// is refused rather than deleted.
rt::Status clearPreviousReplay(const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(dir, ec)) return rt::ok();
  const auto manifest = hal::replay::readManifest((fs::path(dir) / "manifest.yaml").string());
  if (!manifest || manifest->source != "replay")
    return rt::Error{dir + " exists and is not an earlier replay; choose another --out"};
  fs::remove_all(dir, ec);
  if (ec) return rt::Error{dir + ": cannot remove the earlier replay: " + ec.message()};
  return rt::ok();
}

}  // namespace

int replayCommand(const ParsedArgs& args) {
  namespace fs = std::filesystem;
  const std::string dir = *args.positional;
  auto manifest = hal::replay::readManifest((fs::path(dir) / "manifest.yaml").string());
  if (!manifest) return failCommand("replay", manifest.error().message);
  const std::string config_path = args.valueOr("config", (fs::path(dir) / "config.yaml").string());
  const auto overrides = configOverrides(args);
  if (!overrides) return failCommand("replay", overrides.error().message);
  auto config = loadAppConfig(config_path, *overrides);
  if (!config) return failCommand("replay", config.error().message);
  const std::string mode = args.valueOr("mode", "proposed");
  if (mode != "proposed" && mode != "baseline")
    return failCommand("replay", "--mode: expected proposed or baseline, got '" + mode + "'");
  config->baseline_mode = mode == "baseline";
  double offset_s = 0.0;
  if (args.has("offset-s")) {
    const auto o = parseDouble("offset-s", args.values.at("offset-s"), 0.0, 1e7);
    if (!o) return failCommand("replay", o.error().message);
    offset_s = *o;
  }

  // Every recorded device from the recording; what it lacks is absent.
  const auto from = [&manifest](std::initializer_list<const char*> streams) -> std::string {
    for (const char* s : streams)
      if (manifest->stream(s) != nullptr) return "replay";
    return "null";
  };
  hal::HalConfig& hal = config->hal;
  hal.gimbal_camera = from({"gimbal_camera", "detections"});
  hal.depth_camera = from({"depth_camera"});
  hal.gimbal = from({"gimbal"});
  hal.odometry = from({"odometry"});
  hal.vehicle_link = "replay";  // keeps the setpoints for comparison
  hal.replay.dir = dir;
  hal.replay.offset_s = offset_s;
  hal.replay.loop = false;
  hal.replay.start_at_first_use = args.flags.count("realtime") != 0;
  hal.replay.bad_rows =
      args.flags.count("strict") != 0 ? hal::replay::BadRowPolicy::kStrict : hal::replay::BadRowPolicy::kSkip;
  std::vector<rt::TaskSpec> tasks;
  std::string left_out;
  for (const rt::TaskSpec& spec : config->tasks) {
    if (simulatorOnly(spec.name)) {
      left_out += (left_out.empty() ? "" : ", ") + spec.name;
      continue;
    }
    tasks.push_back(spec);
  }
  config->tasks = std::move(tasks);

  const bool compare = args.flags.count("compare") != 0;
  const std::string out_dir = args.valueOr("out", "out/replay-" + fs::path(dir).filename().string());
  const bool realtime = args.flags.count("realtime") != 0;
  if (compare && args.has("record"))
    return failCommand("replay", "--record: --compare records the replay itself (OUT/replayed)");
  if (compare) {
    config->record_dir = (fs::path(out_dir) / "replayed").string();
    if (rt::Status s = clearPreviousReplay(config->record_dir); !s) return failCommand("replay", s.error().message);
  } else {
    config->record_dir = args.valueOr("record", "");
  }
  config->record_lossless = !realtime;
  config->mcap_path = args.valueOr("mcap", "");
  config->mcap_compression = args.valueOr("mcap-compression", "zstd");

  const rt::MonotonicClock mono_clock;
  rt::ManualClock replay_clock(manifest->start_ns);  // lockstep: on the recording's own clock
  const rt::TimeNs start_ns = realtime ? mono_clock.now() : manifest->start_ns;
  std::atomic<bool> stop{false};
  SignalWatcher signals(stop);
  auto system = System::build(*config, nullptr, start_ns);
  if (!system) return failCommand("replay", system.error().message);
  // The run ends with the recording: its last record of any stream, shown at start + (end - first).
  if (!(*system)->devices().recording) return failCommand("replay", dir + ": no device replays the recording");
  const hal::replay::ReplayTimeline& t = (*system)->devices().recording->timeline();
  // As long as the recorded run, if its manifest says; else (a kill -9, an import) one longest task
  // period after the last record, so that every task is released after it was shown.
  rt::DurationNs longest_period_ns = 0;
  for (const rt::TaskSpec& spec : config->tasks)
    if (spec.periodic()) longest_period_ns = std::max(longest_period_ns, rt::periodFromRateHz(spec.rate_hz));
  // A manifest's end_ns is trusted only up to a second past the last record: beyond, the run
  // would replay nothing for as long (an hour, or 9e18 ns) and write what it saw of it.
  const rt::TimeNs data_end_ns = t.endNs() + longest_period_ns;
  rt::TimeNs recording_end_ns = manifest->end_ns ? *manifest->end_ns : data_end_ns;
  bool recording_cut_short = !manifest->end_ns;
  if (recording_end_ns > data_end_ns + std::max<rt::DurationNs>(longest_period_ns, rt::secondsToNs(1.0))) {
    recording_cut_short = true;
    std::printf("replay: the manifest's end_ns lies %.1f s past the last record; replaying to the last record\n",
                rt::nsToSeconds(recording_end_ns - t.endNs()));
    recording_end_ns = data_end_ns;
  }
  const rt::DurationNs duration_ns = recording_end_ns - t.firstNs();
  // Real time: the devices' replay starts when the tasks first ask (start_at_first_use), just below.
  const rt::TimeNs end_ns = (realtime ? mono_clock.now() : start_ns) + duration_ns;
  if (!left_out.empty()) std::printf("replay: left out the simulator's tasks: %s\n", left_out.c_str());

  RunInfo info;
  info.executor = realtime ? "realtime" : "lockstep";
  const rt::Status ran = realtime ? runRealtime(**system, mono_clock, start_ns, end_ns, stop, info, "replay")
                                  : runLockstep(**system, replay_clock, end_ns, stop, info);
  if (!ran) return failCommand("replay", ran.error().message);
  std::printf("replay %s (%s, recorded by %s): %.1f s of recording in %.2f s wall (%s)\n", dir.c_str(),
              manifest->source.c_str(), manifest->software_version.c_str(), info.sim_time_s, info.wall_time_s,
              info.executor.c_str());
  std::fputs(timingTable(info.timings).c_str(), stdout);
  if (const perception::DetectionTask* detection = (*system)->detectionTask();
      detection != nullptr && detection->framesDetected() + detection->failures() > 0) {
    std::printf("detector: %llu frames, the followed person locked on in %llu, %llu failures\n",
                static_cast<unsigned long long>(detection->framesDetected()),
                static_cast<unsigned long long>(detection->framesWithTarget()),
                static_cast<unsigned long long>(detection->failures()));
  }
  std::fputs(deviceHealthReport((*system)->devices(), end_ns - 1).c_str(), stdout);
  auto recorded = (*system)->finishRecording(realtime ? mono_clock.now() : replay_clock.now());
  if (const std::string logged = (*system)->finishFlightLog(); !logged.empty()) std::printf("%s\n", logged.c_str());
  if (!recorded) return failCommand("replay", recorded.error().message);
  if (!recorded->empty()) std::printf("%s\n", recorded->c_str());
  if (stop.load()) return signals.stoppedStatus();
  if (!compare) return 0;
  // An imported video has no delivery times to compare with: only what the modules produced is.
  auto comparison =
      compareDatasets(dir, config->record_dir, /*inputs=*/manifest->source != "import", recording_cut_short);
  if (!comparison) return failCommand("replay", comparison.error().message);
  std::printf("compare with the recording:\n%s", formatComparison(*comparison).c_str());
  if (comparison->empty()) return failCommand("replay", dir + ": nothing to compare (no outputs recorded)");
  for (const StreamComparison& c : *comparison) {
    if (!c.same()) {
      std::printf("replay differs from the recording (first: %s)\n", c.first_difference.c_str());
      return kDiffers;
    }
  }
  std::printf("replay identical to the recording\n");
  return 0;
}

}  // namespace aerotrack::app
