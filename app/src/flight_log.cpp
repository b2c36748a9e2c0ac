// The flight log: see flight_log.hpp.
#include "flight_log.hpp"

#include <google/protobuf/arena.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cmath>

#include "flight_log_writer.hpp"
#include "foxglove_messages.hpp"
#include "system.hpp"

namespace aerotrack::app {
namespace {

google::protobuf::ArenaOptions arenaOn(std::vector<char>& block) {
  google::protobuf::ArenaOptions options;
  options.initial_block = block.data();
  options.initial_block_size = block.size();
  return options;
}

}  // namespace

FlightLogTask::FlightLogTask(const FlightLogOptions& options, const FlightLogSources& sources,
                             std::unique_ptr<FlightLogWriter> log)
    : options_(options),
      sources_(sources),
      log_(std::move(log)),
      arena_block_(kArenaBytes),
      arena_(arenaOn(arena_block_)),
      flown_path_(options.path_segment_s) {}

FlightLogTask::~FlightLogTask() = default;

rt::Expected<std::unique_ptr<FlightLogTask>> FlightLogTask::create(const FlightLogOptions& options,
                                                                   const FlightLogSources& sources) {
  auto log = FlightLogWriter::open(options.targets, sources.simulation != nullptr);
  if (!log) return log.error();
  return std::unique_ptr<FlightLogTask>(new FlightLogTask(options, sources, std::move(log.value())));
}

void FlightLogTask::step(rt::TimeNs now_ns) {
  if (!log_->active()) return;  // the log has ended; the flight goes on
  logOdometry();
  logSetpoint();
  logCamera();
  logDepth(now_ns);
  logEstimate();
  logPlanning(now_ns);
  logSim(now_ns);
  logStatus(now_ns);
  arena_.Reset();  // every message of this step is written: their storage goes back to the initial block
}

void FlightLogTask::logOdometry() {
  const auto odometry = sources_.channels.odometry.read();
  if (!odometry || odometry->stamp_ns <= last_odometry_ns_) return;
  last_odometry_ns_ = odometry->stamp_ns;
  const auto gimbal = sources_.channels.gimbal_state.read();
  const auto depth = sources_.channels.depth.read();
  auto& transforms = fresh<foxglove::FrameTransforms>();
  foxglove_log::fillTransforms(transforms, *odometry, gimbal ? gimbal->angle_rad : 0.0, sources_.extrinsics,
                               depth ? &depth->T_BC : nullptr);
  log_->write(Topic::kTf, odometry->stamp_ns, transforms);
  auto& scene = fresh<foxglove::SceneUpdate>();
  if (flown_path_.add(odometry->stamp_ns, odometry->p_WB_m, scene))
    log_->write(Topic::kPath, odometry->stamp_ns, scene);
}

void FlightLogTask::logSetpoint() {
  const auto setpoint = sources_.channels.setpoints.read();
  if (!setpoint || setpoint->stamp_ns <= last_setpoint_ns_) return;
  last_setpoint_ns_ = setpoint->stamp_ns;
  JsonLine json;
  log_->writeJson(Topic::kSetpoint, setpoint->stamp_ns, foxglove_log::setpointJson(*setpoint, json));
}

void FlightLogTask::logCamera() {
  // New values are told apart by address and time, without holding them (a held handle would pin a
  // slot of its producer's pool).
  if (const auto image = sources_.channels.images.read();
      image && (image.get() != last_image_ || image->stamp_ns != last_image_ns_)) {
    last_image_ = image.get();
    last_image_ns_ = image->stamp_ns;
    if (!image->bgr.empty() &&
        cv::imencode(".jpg", image->bgr, jpeg_, {cv::IMWRITE_JPEG_QUALITY, options_.jpeg_quality})) {
      // Kept from frame to frame and overwritten, not cleared: its data keeps its capacity.
      foxglove_log::setTime(*image_.mutable_timestamp(), image->stamp_ns);
      image_.set_frame_id("camera_optical");
      image_.mutable_data()->assign(reinterpret_cast<const char*>(jpeg_.data()), jpeg_.size());
      image_.set_format("jpeg");
      log_->write(Topic::kImage, image->stamp_ns, image_);
    }
  }
  const auto detection = sources_.channels.newest_detection.read();
  if (!detection || (detection->sequence == last_detection_sequence_ && detection->stamp_ns == last_detection_ns_) ||
      detection->stamp_ns < last_detection_ns_) {
    return;
  }
  last_detection_sequence_ = detection->sequence;
  last_detection_ns_ = detection->stamp_ns;
  // The followed person as the target task decided, when it has decided on this very frame.
  hal::DetectionFrame frame = *detection;
  if (const auto followed = sources_.channels.followed_detection.read();
      followed && followed->stamp_ns == frame.stamp_ns && followed->sequence == frame.sequence) {
    frame.target_index = followed->target_index;
  }
  auto& annotations = fresh<foxglove::ImageAnnotations>();
  foxglove_log::fillAnnotations(annotations, frame, options_.keypoint_min_score);
  log_->write(Topic::kDetections, frame.stamp_ns, annotations);
  auto& calibration = fresh<foxglove::CameraCalibration>();
  foxglove_log::fillCalibration(calibration, frame.stamp_ns, frame.intrinsics);
  log_->write(Topic::kCalibration, frame.stamp_ns, calibration);
}

void FlightLogTask::logDepth(rt::TimeNs now_ns) {
  if (now_ns < next_depth_ns_) return;
  const auto depth = sources_.channels.depth.read();
  if (!depth || depth->stamp_ns <= last_depth_ns_) return;
  last_depth_ns_ = depth->stamp_ns;
  next_depth_ns_ = now_ns + static_cast<rt::TimeNs>(1e9 / options_.depth_rate_hz);
  foxglove_log::fillDepthPoints(points_, *depth, options_.depth_step_px);
  log_->write(Topic::kDepth, depth->stamp_ns, points_);
}

void FlightLogTask::logEstimate() {
  const auto estimate = sources_.channels.target.read();
  if (!estimate || estimate->stamp_ns <= last_estimate_ns_) return;
  last_estimate_ns_ = estimate->stamp_ns;
  auto& scene = fresh<foxglove::SceneUpdate>();
  foxglove_log::fillEstimate(scene, *estimate);
  log_->write(Topic::kEstimate, estimate->stamp_ns, scene);
  if (!estimate->initialised) return;
  JsonLine json;
  log_->writeJson(Topic::kEstimateValues, estimate->stamp_ns, foxglove_log::estimateJson(*estimate, json));
}

void FlightLogTask::logPlanning(rt::TimeNs now_ns) {
  if (const auto trajectory = sources_.channels.trajectories.read();
      trajectory && trajectory->trajectory &&
      (trajectory->trajectory.get() != last_trajectory_ || trajectory->start_ns != last_trajectory_ns_)) {
    last_trajectory_ = trajectory->trajectory.get();
    last_trajectory_ns_ = trajectory->start_ns;
    auto& scene = fresh<foxglove::SceneUpdate>();
    foxglove_log::fillTrajectory(scene, now_ns, *trajectory, 40);
    log_->write(Topic::kTrajectory, now_ns, scene);
  }
  if (const auto plan = sources_.channels.plan_snapshots.read(); plan && plan->stamp_ns > last_plan_ns_) {
    last_plan_ns_ = plan->stamp_ns;
    auto& scene = fresh<foxglove::SceneUpdate>();
    foxglove_log::fillPlan(scene, *plan);
    log_->write(Topic::kPlan, plan->stamp_ns, scene);
    JsonLine json;
    log_->writeJson(Topic::kPlanValues, plan->stamp_ns, foxglove_log::planCycleJson(*plan, json));
  }
  if (now_ns >= next_map_ns_) {
    if (const auto grid = sources_.channels.local_grid.read(); grid) {
      next_map_ns_ = now_ns + static_cast<rt::TimeNs>(1e9 / options_.map_rate_hz);
      auto& scene = fresh<foxglove::SceneUpdate>();
      foxglove_log::fillOccupied(scene, now_ns, *grid);
      log_->write(Topic::kMap, now_ns, scene);
    }
  }
  // On every transition, and once a second (a plot, or a viewer joining late, sees the mode all along).
  if (const auto state = sources_.channels.supervisor.read();
      state && (state->transitions != last_transitions_ || now_ns >= next_supervisor_ns_)) {
    last_transitions_ = state->transitions;
    next_supervisor_ns_ = now_ns + rt::secondsToNs(1.0);
    JsonLine json;
    log_->writeJson(Topic::kSupervisor, now_ns, foxglove_log::supervisorJson(*state, json));
  }
}

void FlightLogTask::logSim(rt::TimeNs now_ns) {
  if (!sources_.simulation) return;
  if (!obstacles_written_) {
    obstacles_written_ = true;
    auto& scene = fresh<foxglove::SceneUpdate>();
    foxglove_log::fillObstacles(scene, now_ns, sources_.simulation->obstacles());
    log_->write(Topic::kObstacles, now_ns, scene);
  }
  if (now_ns < next_truth_ns_) return;
  const auto truth = sources_.simulation->truthOut().read();
  if (!truth) return;
  next_truth_ns_ = now_ns + static_cast<rt::TimeNs>(1e9 / options_.truth_rate_hz);
  auto& scene = fresh<foxglove::SceneUpdate>();
  foxglove_log::fillTruth(scene, *truth);
  log_->write(Topic::kTruth, truth->stamp_ns, scene);
  const auto estimate = sources_.channels.target.read();
  const bool live = estimate && estimate->initialised && !estimate->lost;
  JsonLine json;
  log_->writeJson(Topic::kTruthValues, truth->stamp_ns,
                  foxglove_log::truthJson(*truth, live ? &*estimate : nullptr, json));
}

void FlightLogTask::logStatus(rt::TimeNs now_ns) {
  if (now_ns < next_status_ns_) return;
  next_status_ns_ = now_ns + rt::secondsToNs(1.0);
  if (!timings_.empty()) {
    nlohmann::json tasks = nlohmann::json::object();
    for (const rt::TaskSet::NamedStats& t : timings_) {
      const rt::TimingSnapshot s = t.stats->snapshot();
      tasks[t.name] = {{"runs", s.runs},      {"overruns", s.overruns}, {"missed_deadlines", s.missed_deadlines},
                       {"p50_ms", s.p50_ms},  {"p99_ms", s.p99_ms},     {"max_ms", s.max_ms},
                       {"mean_ms", s.mean_ms}};
    }
    log_->writeJson(Topic::kTiming, now_ns, tasks.dump());
  }
  if (sources_.devices != nullptr) {
    const hal::Devices& d = *sources_.devices;
    nlohmann::json devices = nlohmann::json::object();
    const std::pair<const char*, const hal::Device*> all[] = {{"gimbal_camera", d.gimbal_camera.get()},
                                                              {"depth_camera", d.depth_camera.get()},
                                                              {"gimbal", d.gimbal.get()},
                                                              {"odometry", d.odometry.get()},
                                                              {"vehicle_link", d.vehicle_link.get()}};
    for (const auto& [name, device] : all) {
      if (device == nullptr) continue;
      const hal::DeviceHealth h = device->health(now_ns);
      devices[name] = {{"backend", std::string(device->backend())},
                       {"state", std::string(hal::toString(h.state))},
                       {"detail", h.detail}};
    }
    log_->writeJson(Topic::kHealth, now_ns, devices.dump());
  }
}

rt::Status FlightLogTask::finish() {
  if (log_->active()) {
    auto& scene = fresh<foxglove::SceneUpdate>();
    if (flown_path_.flush(scene)) log_->write(Topic::kPath, flown_path_.lastStampNs(), scene);
  }
  return log_->close();
}

std::string FlightLogTask::summary() const {
  return log_->summary();
}

}  // namespace aerotrack::app
