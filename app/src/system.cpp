// Wiring: see system.hpp.
#include "system.hpp"

#include <cmath>
#include <fstream>

#include "aerotrack/gimbal_control/gimbal_control_task.hpp"
#include "aerotrack/trajectory_server/trajectory_server_task.hpp"
#include "device_tasks.hpp"
#include "paths.hpp"

namespace aerotrack::app {

std::vector<std::string> System::knownTasks() {
  return {"sim_world",       "odometry",     "gimbal_camera", "depth_camera",  "gimbal",
          "mapping",         "detection",    "target",        "target_check",  "trajectory_server",
          "baseline_follow", "truth_gimbal", "planning",      "gimbal_control"};
}

rt::Expected<std::unique_ptr<System>> System::build(const AppConfig& config, const hal::sim::ScenarioInstance* scenario,
                                                    rt::TimeNs start_ns) {
  std::unique_ptr<System> system(new System(config));
  system->start_ns_ = start_ns;
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
    config_file << "# the configuration of the recorded run (aerotrack replay reads it)\n" << toYaml(config);
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
  return system;
}

rt::Status System::addTask(const rt::TaskSpec& spec, std::size_t index) {
  const std::string where = config_.source + ": tasks[" + std::to_string(index) + "]";
  std::unique_ptr<rt::Task> task;
  if (spec.name == "sim_world" || spec.name == "baseline_follow" || spec.name == "truth_gimbal" ||
      spec.name == "target_check" || spec.name == "camera_strip") {
    if (!devices_.simulation) return rt::Error{where + ": task '" + spec.name + "' needs a sim backend in hal"};
    if (spec.name == "sim_world") {
      task = std::make_unique<SimWorldTask>(devices_.simulation);
    } else if (spec.name == "camera_strip") {
      const hal::CameraIntrinsics& k = devices_.simulation->scenario().spec.gimbal_camera.camera.intrinsics;
      const double hfov_rad = 2.0 * std::atan2(k.cx_px, k.fx_px);
      auto strip = std::make_unique<CameraStripTask>(devices_.simulation,
                                                     CameraStripSources{channels_.newest_detection, channels_.target,
                                                                        channels_.local_grid, channels_.trajectories},
                                                     /*every_s=*/4.0, hfov_rad);
      camera_strip_task_ = strip.get();
      task = std::move(strip);
    } else if (spec.name == "target_check") {
      auto check = std::make_unique<TargetTruthCheckTask>(devices_.simulation, channels_.target);
      target_check_task_ = check.get();
      task = std::move(check);
    } else {
      const bool command_vehicle = spec.name == "baseline_follow";
      task = std::make_unique<BaselineFollowTask>(devices_.simulation, *devices_.vehicle_link, *devices_.gimbal,
                                                  command_vehicle);
    }
  } else if (spec.name == "odometry") {
    task = std::make_unique<OdometryTask>(*devices_.odometry, channels_.odometry, channels_.odometry_stream,
                                          channels_.odometry_target_stream);
  } else if (spec.name == "gimbal_camera") {
    task = std::make_unique<GimbalCameraTask>(*devices_.gimbal_camera, channels_.detections, channels_.images,
                                              channels_.newest_camera_frame_ns, channels_.newest_detection);
  } else if (spec.name == "depth_camera") {
    task = std::make_unique<DepthCameraTask>(*devices_.depth_camera, channels_.depth);
  } else if (spec.name == "mapping") {
    if (!config_.mapping) return rt::Error{where + ": task 'mapping' needs a mapping: section"};
    auto mapper = mapping::Mapper::create(*config_.mapping);
    if (!mapper) return rt::Error{config_.source + ": mapping: " + mapper.error().message};
    auto mapping_task =
        std::make_unique<mapping::MappingTask>(std::move(mapper.value()), channels_.odometry_stream, channels_.depth,
                                               channels_.local_grid, channels_.octree, stats_clock_);
    mapping_task_ = mapping_task.get();
    task = std::move(mapping_task);
  } else if (spec.name == "detection") {
    if (!config_.perception) return rt::Error{where + ": task 'detection' needs a perception: section"};
    perception::DetectorParams params = *config_.perception;
    if (params.model_dir == "default") params.model_dir = modelDir();
    auto detector = perception::Detector::create(params);
    if (!detector) return rt::Error{config_.source + ": perception: " + detector.error().message};
    auto detection_task = std::make_unique<perception::DetectionTask>(std::move(detector.value()), channels_.images,
                                                                      channels_.detections, stats_clock_);
    detection_task->publishNewestTo(channels_.newest_detection);
    detection_task_ = detection_task.get();
    task = std::move(detection_task);
  } else if (spec.name == "target") {
    if (!config_.estimation) return rt::Error{where + ": task 'target' needs an estimation: section"};
    auto target =
        estimation::TargetTask::create(config_.estimation->task, channels_.detections, channels_.odometry_target_stream,
                                       channels_.gimbal_stream, channels_.target);
    if (!target) return rt::Error{config_.source + ": estimation: " + target.error().message};
    auto target_task = std::make_unique<estimation::TargetTask>(std::move(target.value()));
    target_task_ = target_task.get();
    task = std::move(target_task);
  } else if (spec.name == "gimbal") {
    task = std::make_unique<GimbalEncoderTask>(*devices_.gimbal, channels_.gimbal_state, channels_.gimbal_stream);
  } else if (spec.name == "gimbal_control") {
    if (!config_.gimbal_control || !config_.estimation)
      return rt::Error{where + ": task 'gimbal_control' needs gimbal_control: and estimation: sections"};
    const gimbal_control::GimbalController controller(*config_.gimbal_control, config_.estimation->task.extrinsics);
    auto gimbal_task = std::make_unique<gimbal_control::GimbalControlTask>(
        controller, channels_.gimbal_state, channels_.odometry, channels_.target, channels_.gimbal_search_requested,
        *devices_.gimbal);
    gimbal_task->fixCamera(config_.baseline_mode);
    task = std::move(gimbal_task);
  } else if (spec.name == "supervisor") {
    if (!config_.supervisor) return rt::Error{where + ": task 'supervisor' needs a supervisor: section"};
    const supervisor::SupervisorChannels channels{channels_.odometry,
                                                  channels_.depth,
                                                  channels_.newest_camera_frame_ns,
                                                  channels_.target,
                                                  channels_.planner_failures_in_a_row,
                                                  channels_.deadline_misses,
                                                  channels_.vehicle_link_lost,
                                                  channels_.supervisor,
                                                  channels_.gimbal_search_requested};
    auto supervisor_task =
        std::make_unique<supervisor::SupervisorTask>(*config_.supervisor, start_ns_, channels,
                                                     /*sweep_when_searching=*/!config_.baseline_mode);
    supervisor_task_ = supervisor_task.get();
    task = std::move(supervisor_task);
  } else if (spec.name == "planning") {
    if (!config_.planning) return rt::Error{where + ": task 'planning' needs a planning: section"};
    auto planner = planning::TrackingPlanner::create(*config_.planning);
    if (!planner) return rt::Error{config_.source + ": " + planner.error().message};
    const planning::PlanningChannels channels{channels_.odometry,
                                              channels_.target,
                                              channels_.local_grid,
                                              channels_.octree,
                                              channels_.trajectories,
                                              &channels_.supervisor,
                                              &channels_.planner_failures_in_a_row};
    if (config_.baseline_mode) planner->setOcclusionAware(false);
    auto planning_task = std::make_unique<planning::PlanningTask>(std::move(planner.value()), channels, stats_clock_);
    planning_task_ = planning_task.get();
    task = std::move(planning_task);
  } else if (spec.name == "trajectory_server") {
    auto server = std::make_unique<trajectory_server::TrajectoryServerTask>(
        config_.trajectory_server, channels_.trajectories, *devices_.vehicle_link, channels_.setpoints);
    server->reportLinkLossTo(channels_.vehicle_link_lost);
    if (config_.baseline_mode) {
      // The fixed camera looks where the body looks: face the person's estimate, carried to now.
      const rt::LatestSlot<estimation::TargetEstimate>& target = channels_.target;
      server->faceTowards([&target](rt::TimeNs now_ns) -> std::optional<Eigen::Vector3d> {
        const auto estimate = target.read();
        if (!estimate || !estimate->initialised || estimate->lost) return std::nullopt;
        return Eigen::Vector3d(estimate->p_WT_m + rt::nsToSeconds(now_ns - estimate->stamp_ns) * estimate->v_WT_mps);
      });
    }
    server_task_ = server.get();
    task = std::move(server);
  } else {
    std::string known;
    for (const std::string& k : knownTasks()) known += (known.empty() ? "" : ", ") + k;
    return rt::Error{where + ".name: unknown task '" + spec.name + "' (known: " + known + ")"};
  }

  rt::Doorbell* doorbell = nullptr;
  if (!spec.periodic()) {
    doorbells_.push_back(std::make_unique<rt::Doorbell>());
    doorbell = doorbells_.back().get();
    if (spec.trigger == "odometry")
      channels_.odometry.attachDoorbell(doorbell);
    else if (spec.trigger == "setpoints")
      channels_.setpoints.attachDoorbell(doorbell);
    else if (spec.trigger == "trajectories")
      channels_.trajectories.attachDoorbell(doorbell);
    else
      return rt::Error{where + ".trigger: unknown channel '" + spec.trigger +
                       "' (known: odometry, setpoints, trajectories)"};
  }
  tasks_.push_back(std::move(task));
  bindings_.push_back({spec, tasks_.back().get(), doorbell});
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
