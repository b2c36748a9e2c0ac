// Wiring: see system.hpp.
#include "system.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <string_view>

#include "aerotrack/gimbal_control/gimbal_control_task.hpp"
#include "aerotrack/trajectory_server/trajectory_server_task.hpp"
#include "device_tasks.hpp"
#include "flight_log.hpp"
#include "paths.hpp"

namespace aerotrack::app {

rt::Expected<std::unique_ptr<System>> System::build(const AppConfig& config, const hal::sim::ScenarioInstance* scenario,
                                                    rt::TimeNs start_ns) {
  std::unique_ptr<System> system(new System(config));
  system->start_ns_ = start_ns;
  selectLocalization(system->config_,
                     scenario != nullptr && scenario->spec.gimbal_camera.mode == hal::sim::GimbalCameraMode::kImage);
  hal::sim::SimulationOptions sim_options;
  sim_options.physics_step_s = config.sim.physics_step_s;
  sim_options.render_depth = config.sim.render_depth;
  sim_options.faults = config.sim.faults;
  auto devices = hal::makeDevices(config.hal, scenario, sim_options, start_ns);
  if (!devices) return rt::Error{config.source + ": " + devices.error().message};
  system->devices_ = std::move(devices.value());
  if (!config.record_dir.empty()) {
    hal::replay::RecorderOptions options;
    options.dir = config.record_dir;
    options.software_version = "aerotrack (" + config.source + ")";
    options.source = config.hal.usesSim() ? "sim" : config.hal.usesReplay() ? "replay" : "real";
    options.lossless = config.record_lossless;
    auto recorder = hal::replay::DatasetRecorder::start(options, start_ns);
    if (!recorder) return recorder.error();
    system->recorder_ = std::move(recorder.value());
    // The effective configuration, so that `aerotrack replay` re-runs the modules as they ran.
    const std::string config_path = config.record_dir + "/config.yaml";
    std::ofstream config_file(config_path);
    config_file << "# the configuration of the recorded run (aerotrack replay reads it)\n" << toYaml(system->config_);
    config_file.close();
    if (!config_file) return rt::Error{"record: " + config_path + ": write failed"};
    hal::Devices& d = system->devices_;
    hal::replay::DatasetRecorder& r = *system->recorder_;
    d.odometry = std::make_unique<hal::replay::RecordingOdometry>(std::move(d.odometry), r);
    d.gimbal_camera = std::make_unique<hal::replay::RecordingGimbalCamera>(std::move(d.gimbal_camera), r);
    d.depth_camera = std::make_unique<hal::replay::RecordingDepthCamera>(std::move(d.depth_camera), r);
    d.gimbal = std::make_unique<hal::replay::RecordingGimbal>(std::move(d.gimbal), r);
    d.vehicle_link = std::make_unique<hal::replay::RecordingVehicleLink>(std::move(d.vehicle_link), r);
  }

  bool has_world_task = false;
  for (std::size_t i = 0; i < config.tasks.size(); ++i) {
    if (const rt::Status s = system->addTask(config.tasks[i], i); !s) return s.error();
    has_world_task = has_world_task || config.tasks[i].name == "sim_world";
  }
  if (system->devices_.simulation && !has_world_task)
    return rt::Error{config.source +
                     ": tasks: sim backends are configured but no 'sim_world' task steps the simulation"};
  if (system->recorder_) {
    // The modules' outputs beside the devices' streams: a background task, after every table row.
    auto outputs = OutputRecorderTask::create(config.record_dir, system->channels_.newest_detection,
                                              system->channels_.target, system->channels_.trajectories);
    if (!outputs) return outputs.error();
    system->output_recorder_ = outputs->get();
    system->tasks_.push_back(std::move(outputs.value()));
    rt::TaskSpec spec;
    spec.name = "record_outputs";
    spec.rate_hz = kOutputRecordRateHz;
    spec.budget_ms = 2.0;
    system->bindings_.push_back({spec, system->tasks_.back().get(), nullptr});
  }
  if (!config.mcap_path.empty() || !config.live_address.empty()) {
    if (rt::Status s = system->addFlightLog(); !s) return s.error();
  }
  return system;
}

System::~System() = default;

rt::Status System::addFlightLog() {
  FlightLogOptions options;
  options.targets.mcap_path = config_.mcap_path;
  auto compression = hal::replay::parseMcapCompression(config_.mcap_compression);
  if (!compression) return rt::Error{"--mcap-compression: " + compression.error().message};
  options.targets.mcap.compression = *compression;
  options.targets.live.address = config_.live_address;
  const estimation::GimbalCameraExtrinsics* extrinsics =
      config_.estimation ? &config_.estimation->task.extrinsics : nullptr;
  auto log = FlightLogTask::create(options, FlightLogSources{channels_, extrinsics, devices_.simulation, &devices_});
  if (!log) return rt::Error{(log.error().message.rfind("--live", 0) == 0 ? "" : "--mcap: ") + log.error().message};
  flight_log_ = log->get();
  tasks_.push_back(std::move(log.value()));
  rt::TaskSpec spec;
  spec.name = "flight_log";
  spec.rate_hz = kOutputRecordRateHz;  // as fast as the target task publishes (see kOutputRecordRateHz)
  spec.budget_ms = 50.0;               // a full chunk's compression (zstd level 1, 1 MB) takes 5-15 ms of one step
  spec.observer = true;
  bindings_.push_back({spec, tasks_.back().get(), nullptr});
  return rt::ok();
}

void System::watchTimings(std::vector<rt::TaskSet::NamedStats> timings) {
  if (flight_log_ != nullptr) flight_log_->watchTimings(std::move(timings));
}

std::string System::finishFlightLog() {
  if (flight_log_ == nullptr) return std::string();
  (void)flight_log_->finish();  // an early stop is in the summary
  return flight_log_->summary();
}

namespace {

template <class T>
System::TaskResult made(std::unique_ptr<T> task) {
  return System::TaskResult(std::unique_ptr<rt::Task>(std::move(task)));
}

}  // namespace

// The registry: one row per task name the table may use. A row says whether the task needs the
// simulator (sim-only tasks are refused on real or replayed devices) and how it is built from the
// devices, the channels and the config sections. knownTasks() and addTask() both read it, so a task
// cannot be buildable and missing from the list (or listed and unbuildable).
std::span<const System::TaskKind> System::taskKinds() {
  static const TaskKind kKinds[] = {
      {"sim_world", true,
       [](System& s, const std::string& /*where*/) {
         return made(std::make_unique<SimWorldTask>(s.devices_.simulation, s.channels_.newest_detection,
                                                    s.channels_.followed_detection));
       }},
      {"odometry", false,
       [](System& s, const std::string& /*where*/) {
         return made(std::make_unique<OdometryTask>(*s.devices_.odometry, s.channels_.odometry,
                                                    s.channels_.odometry_stream, s.channels_.odometry_target_stream));
       }},
      {"gimbal_camera", false,
       [](System& s, const std::string& /*where*/) {
         Channels& c = s.channels_;
         // The lock-on of detection-delivering cameras uses the image pipeline's tracker settings.
         const perception::DetectorParams detector = s.config_.perception.value_or(perception::DetectorParams{});
         return made(std::make_unique<GimbalCameraTask>(*s.devices_.gimbal_camera, c.detections, c.images,
                                                        c.newest_camera_frame_ns, c.newest_detection,
                                                        perception::KeypointLockOn(detector.tracker, detector.torso)));
       }},
      {"depth_camera", false,
       [](System& s, const std::string& /*where*/) {
         return made(
             std::make_unique<DepthCameraTask>(*s.devices_.depth_camera, s.channels_.depth, s.channels_.odometry));
       }},
      {"gimbal", false,
       [](System& s, const std::string& /*where*/) {
         return made(std::make_unique<GimbalEncoderTask>(*s.devices_.gimbal, s.channels_.gimbal_state,
                                                         s.channels_.gimbal_stream));
       }},
      {"mapping", false, &System::makeMappingTask},
      {"detection", false, &System::makeDetectionTask},
      {"target", false, &System::makeTargetTask},
      {"target_check", true,
       [](System& s, const std::string& /*where*/) {
         auto check = std::make_unique<TargetTruthCheckTask>(s.devices_.simulation, s.channels_.target);
         s.target_check_task_ = check.get();
         return made(std::move(check));
       }},
      {"trajectory_server", false, &System::makeTrajectoryServerTask},
      // The paper's baseline (the body faces the person, the camera fixed), and a perception-free check of the
      // loop that only points the gimbal at the true person.
      {"baseline_follow", true, [](System& s, const std::string& /*where*/) { return makeSimFollower(s, true); }},
      {"truth_gimbal", true, [](System& s, const std::string& /*where*/) { return makeSimFollower(s, false); }},
      {"planning", false, &System::makePlanningTask},
      {"gimbal_control", false, &System::makeGimbalControlTask},
      {"supervisor", false, &System::makeSupervisorTask},
      {"camera_strip", true, &System::makeCameraStripTask},
  };
  return kKinds;
}

std::vector<std::string> System::knownTasks() {
  std::vector<std::string> names;
  for (const TaskKind& kind : taskKinds()) names.emplace_back(kind.name);
  return names;
}

void System::flyFromTruth(std::vector<rt::TaskSpec>& tasks) {
  static constexpr std::array<std::string_view, 7> kFlight = {
      "planning", "gimbal_control", "supervisor", "trajectory_server", "mapping", "camera_strip", "baseline_follow"};
  std::erase_if(tasks, [](const rt::TaskSpec& spec) { return std::ranges::find(kFlight, spec.name) != kFlight.end(); });
  // At the trajectory server's rate and priority: it stands in for the setpoint stream.
  rt::TaskSpec follow;
  follow.name = "baseline_follow";
  follow.rate_hz = 100.0;
  follow.budget_ms = 0.5;
  follow.priority = 80;
  tasks.push_back(follow);
}

System::TaskResult System::makeSimFollower(System& s, bool command_vehicle) {
  return made(std::make_unique<BaselineFollowTask>(s.devices_.simulation, *s.devices_.vehicle_link, *s.devices_.gimbal,
                                                   command_vehicle));
}

System::TaskResult System::makeCameraStripTask(System& s, const std::string& /*where*/) {
  const hal::CameraIntrinsics& k = s.devices_.simulation->scenario().spec.gimbal_camera.camera.intrinsics;
  const double hfov_rad = 2.0 * std::atan2(k.cx_px, k.fx_px);
  const Channels& c = s.channels_;
  auto strip = std::make_unique<CameraStripTask>(
      s.devices_.simulation, CameraStripSources{c.newest_detection, c.target, c.local_grid, c.trajectories, &c.images},
      /*every_s=*/4.0, hfov_rad);
  s.camera_strip_task_ = strip.get();
  return made(std::move(strip));
}

System::TaskResult System::makeMappingTask(System& s, const std::string& where) {
  if (!s.config_.mapping) return rt::Error{where + ": task 'mapping' needs a mapping: section"};
  auto mapper = mapping::Mapper::create(*s.config_.mapping);
  if (!mapper) return rt::Error{s.config_.source + ": mapping: " + mapper.error().message};
  Channels& c = s.channels_;
  auto task = std::make_unique<mapping::MappingTask>(std::move(mapper.value()), c.odometry_stream, c.depth,
                                                     c.local_grid, c.octree, s.stats_clock_);
  // The followed person, where the newest estimate puts them at the frame's capture time, is not an obstacle.
  const mapping::TargetExclusionParams exclusion = s.config_.mapping->exclude_target;
  if (exclusion.enabled) {
    task->excludeBodyFrom([&target = c.target, exclusion](rt::TimeNs stamp_ns) -> std::optional<mapping::ExcludedBody> {
      const std::optional<estimation::TargetEstimate> estimate = target.read();
      if (!estimate || !estimate->initialised || estimate->lost) return std::nullopt;  // lost: where is unknown
      // Carried to the capture time along its velocity, at most a second either way (the estimate may be older).
      const double dt_s = std::clamp(rt::nsToSeconds(stamp_ns - estimate->stamp_ns), -1.0, 1.0);
      return mapping::bodyAround(estimate->p_WT_m + dt_s * estimate->v_WT_mps,
                                 estimate->covariance.topLeftCorner<2, 2>(), exclusion);
    });
  }
  s.mapping_task_ = task.get();
  return made(std::move(task));
}

System::TaskResult System::makeDetectionTask(System& s, const std::string& where) {
  if (!s.config_.perception) return rt::Error{where + ": task 'detection' needs a perception: section"};
  perception::DetectorParams params = *s.config_.perception;
  if (params.model_dir == "default") params.model_dir = modelDir();
  auto detector = perception::Detector::create(params);
  if (!detector) return rt::Error{s.config_.source + ": perception: " + detector.error().message};
  auto task = std::make_unique<perception::DetectionTask>(std::move(detector.value()), s.channels_.images,
                                                          s.channels_.detections, s.stats_clock_);
  task->publishNewestTo(s.channels_.newest_detection);
  if (params.follow_estimator) task->judgedBy(s.channels_.followed_detection);
  s.detection_task_ = task.get();
  return made(std::move(task));
}

System::TaskResult System::makeTargetTask(System& s, const std::string& where) {
  if (!s.config_.estimation) return rt::Error{where + ": task 'target' needs an estimation: section"};
  Channels& c = s.channels_;
  auto target = estimation::TargetTask::create(s.config_.estimation->task, c.detections, c.odometry_target_stream,
                                               c.gimbal_stream, c.target);
  if (!target) return rt::Error{s.config_.source + ": estimation: " + target.error().message};
  auto task = std::make_unique<estimation::TargetTask>(std::move(target.value()));
  task->publishFollowedTo(c.followed_detection);
  task->rangeFrom(c.depth);
  s.target_task_ = task.get();
  return made(std::move(task));
}

System::TaskResult System::makeGimbalControlTask(System& s, const std::string& where) {
  if (!s.config_.gimbal_control || !s.config_.estimation)
    return rt::Error{where + ": task 'gimbal_control' needs gimbal_control: and estimation: sections"};
  const gimbal_control::GimbalController controller(*s.config_.gimbal_control, s.config_.estimation->task.extrinsics);
  Channels& c = s.channels_;
  auto task = std::make_unique<gimbal_control::GimbalControlTask>(controller, c.gimbal_state, c.odometry, c.target,
                                                                  c.gimbal_search_requested, *s.devices_.gimbal);
  task->fixCamera(s.config_.baseline_mode);
  return made(std::move(task));
}

System::TaskResult System::makeSupervisorTask(System& s, const std::string& where) {
  if (!s.config_.supervisor) return rt::Error{where + ": task 'supervisor' needs a supervisor: section"};
  Channels& c = s.channels_;
  const supervisor::SupervisorChannels channels{c.odometry,
                                                c.depth,
                                                c.newest_camera_frame_ns,
                                                c.gimbal_state,
                                                c.target,
                                                c.planner_failures_in_a_row,
                                                c.deadline_misses,
                                                c.vehicle_link_lost,
                                                c.supervisor,
                                                c.gimbal_search_requested};
  supervisor::SupervisorParams params = *s.config_.supervisor;
  // A simulated scenario may set how long to search after a relocation (its `supervisor:` section).
  // The baseline (Fast-Tracker 1.0) has no search after its relocation: it stays the paper's comparison.
  if (s.config_.baseline_mode) params.search_timeout_s = 0.0;
  if (s.devices_.simulation && !s.config_.baseline_mode) {
    if (const auto search_s = s.devices_.simulation->scenario().spec.search_timeout_s)
      params.search_timeout_s = *search_s;
  }
  auto task = std::make_unique<supervisor::SupervisorTask>(params, s.start_ns_, channels,
                                                           /*sweep_when_searching=*/!s.config_.baseline_mode);
  s.supervisor_task_ = task.get();
  return made(std::move(task));
}

System::TaskResult System::makePlanningTask(System& s, const std::string& where) {
  if (!s.config_.planning) return rt::Error{where + ": task 'planning' needs a planning: section"};
  auto planner = planning::TrackingPlanner::create(*s.config_.planning);
  if (!planner) return rt::Error{s.config_.source + ": " + planner.error().message};
  Channels& c = s.channels_;
  const planning::PlanningChannels channels{
      c.odometry,
      c.target,
      c.local_grid,
      c.octree,
      c.trajectories,
      &c.supervisor,
      &c.planner_failures_in_a_row,
      &c.refused_trajectory_start_ns,
      s.config_.mcap_path.empty() && s.config_.live_address.empty() ? nullptr : &c.plan_snapshots};
  if (s.config_.baseline_mode) planner->setOcclusionAware(false);
  auto task = std::make_unique<planning::PlanningTask>(std::move(planner.value()), channels, s.stats_clock_);
  s.planning_task_ = task.get();
  return made(std::move(task));
}

System::TaskResult System::makeTrajectoryServerTask(System& s, const std::string& /*where*/) {
  Channels& c = s.channels_;
  auto server = std::make_unique<trajectory_server::TrajectoryServerTask>(s.config_.trajectory_server, c.trajectories,
                                                                          *s.devices_.vehicle_link, c.setpoints);
  server->reportLinkLossTo(c.vehicle_link_lost);
  server->reportLateRefusalsTo(c.refused_trajectory_start_ns);
  if (s.config_.baseline_mode) {
    // The fixed camera looks where the body looks: face the person's estimate, carried to now.
    const rt::LatestSlot<estimation::TargetEstimate>& target = c.target;
    server->faceTowards([&target](rt::TimeNs now_ns) -> std::optional<Eigen::Vector3d> {
      const auto estimate = target.read();
      if (!estimate || !estimate->initialised || estimate->lost) return std::nullopt;
      return Eigen::Vector3d(estimate->p_WT_m + rt::nsToSeconds(now_ns - estimate->stamp_ns) * estimate->v_WT_mps);
    });
  }
  s.server_task_ = server.get();
  return made(std::move(server));
}

rt::Status System::addTask(const rt::TaskSpec& spec, std::size_t index) {
  const std::string where = config_.source + ": tasks[" + std::to_string(index) + "]";
  const std::span<const TaskKind> kinds = taskKinds();
  const auto kind = std::find_if(kinds.begin(), kinds.end(), [&](const TaskKind& k) { return spec.name == k.name; });
  if (kind == kinds.end()) {
    std::string known;
    for (const std::string& k : knownTasks()) known += (known.empty() ? "" : ", ") + k;
    return rt::Error{where + ".name: unknown task '" + spec.name + "' (known: " + known + ")"};
  }
  if (kind->needs_sim && !devices_.simulation)
    return rt::Error{where + ": task '" + spec.name + "' needs a sim backend in hal"};
  TaskResult made_task = kind->make(*this, where);
  if (!made_task) return made_task.error();
  std::unique_ptr<rt::Task> task = std::move(made_task.value());

  rt::Doorbell* doorbell = nullptr;
  if (spec.triggered()) {
    doorbells_.push_back(std::make_unique<rt::Doorbell>());
    doorbell = doorbells_.back().get();
    if (const rt::Status s = attachTrigger(spec.trigger, doorbell); !s)
      return rt::Error{where + ".trigger: " + s.error().message};
    triggered_by_.emplace_back(spec.trigger, spec.name);
  }
  tasks_.push_back(std::move(task));
  bindings_.push_back({spec, tasks_.back().get(), doorbell});
  return rt::ok();
}

rt::Status System::attachTrigger(const std::string& channel, rt::Doorbell* doorbell) {
  // Each channel has one doorbell: one task may be triggered by it.
  for (const auto& [name, task] : triggered_by_)
    if (name == channel)
      return rt::Error{
          std::string("channel '").append(channel).append("' already triggers task '").append(task).append("'")};
  Channels& c = channels_;
  if (channel == "odometry")
    c.odometry.attachDoorbell(doorbell);
  else if (channel == "setpoints")
    c.setpoints.attachDoorbell(doorbell);
  else if (channel == "trajectories")
    c.trajectories.attachDoorbell(doorbell);
  else if (channel == "detections")
    c.detections.attachDoorbell(doorbell);
  else if (channel == "images")
    c.images.attachDoorbell(doorbell);
  else if (channel == "target")
    c.target.attachDoorbell(doorbell);
  else if (channel == "depth")
    c.depth.attachDoorbell(doorbell);
  else if (channel == "gimbal_state")
    c.gimbal_state.attachDoorbell(doorbell);
  else if (channel == "local_grid")
    c.local_grid.attachDoorbell(doorbell);
  else
    return rt::Error{"unknown channel '" + channel + "' (known: " + kTriggerChannels + ")"};
  return rt::ok();
}

rt::Expected<std::string> System::finishRecording(rt::TimeNs end_ns) {
  if (!recorder_) return std::string();
  const rt::Status devices = recorder_->stop(end_ns);
  const rt::Status outputs = output_recorder_ != nullptr ? output_recorder_->finish() : rt::ok();
  if (!devices) return devices.error();
  if (!outputs) return outputs.error();
  std::string line = "recorded " + recorder_->dir() + ": " + recorder_->summary();
  if (output_recorder_ != nullptr) {
    line += ", detector outputs " + std::to_string(output_recorder_->detectionsWritten()) + ", estimates " +
            std::to_string(output_recorder_->estimatesWritten()) + ", trajectories " +
            std::to_string(output_recorder_->trajectoriesWritten());
  }
  return line + " records; " + std::to_string(recorder_->droppedTotal()) + " dropped (disk too slow)";
}

}  // namespace aerotrack::app
