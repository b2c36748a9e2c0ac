// Tasks that connect devices to channels (the capture side of the HAL), the simulation's physics
// step, and the simulator's truth-fed baseline_follow stand-in. Thin by design.
#pragma once

#include <cmath>
#include <memory>

#include <algorithm>

#include "aerotrack/estimation/target_estimator.hpp"
#include "aerotrack/hal/depth_view.hpp"
#include "aerotrack/hal/devices.hpp"
#include "aerotrack/hal/sim/baseline_follower.hpp"
#include "aerotrack/hal/sim/simulation.hpp"
#include "aerotrack/perception/keypoint_lock_on.hpp"
#include "aerotrack/rt/latest_slot.hpp"
#include "aerotrack/rt/shared_slot.hpp"
#include "aerotrack/rt/spsc_queue.hpp"
#include "aerotrack/rt/task.hpp"

namespace aerotrack::app {

/// Polls the odometry device and publishes each new sample (by stamp): the newest on the
/// odometry channel, every one on the streams that feed the pose histories of the mapper and of
/// the target task (one consumer each).
class OdometryTask final : public rt::Task {
 public:
  OdometryTask(hal::Odometry& device, rt::LatestSlot<hal::OdometrySample>& out,
               rt::SpscQueue<hal::OdometrySample>& mapping_stream, rt::SpscQueue<hal::OdometrySample>& target_stream)
      : device_(device), out_(out), mapping_stream_(mapping_stream), target_stream_(target_stream) {}
  void step(rt::TimeNs now_ns) override {
    const auto sample = device_.read(now_ns);
    if (!sample || sample->stamp_ns <= last_stamp_ns_) return;
    last_stamp_ns_ = sample->stamp_ns;
    out_.write(*sample);
    mapping_stream_.try_push(*sample);
    target_stream_.try_push(*sample);
  }

 private:
  hal::Odometry& device_;
  rt::LatestSlot<hal::OdometrySample>& out_;
  rt::SpscQueue<hal::OdometrySample>& mapping_stream_;
  rt::SpscQueue<hal::OdometrySample>& target_stream_;
  rt::TimeNs last_stamp_ns_ = -1;
};

/// Publishes the gimbal camera's output: images on the images channel (for the detection task),
/// or, from a keypoint-mode camera (the simulator's), its detection results straight onto the
/// detections stream.
class GimbalCameraTask final : public rt::Task {
 public:
  GimbalCameraTask(hal::GimbalCamera& device, rt::SpscQueue<hal::DetectionFrame>& detections,
                   rt::SharedSlot<hal::ImageFrame>& images, std::atomic<rt::TimeNs>& newest_frame_ns,
                   rt::LatestSlot<hal::DetectionFrame>& newest_detection, const perception::KeypointLockOn& lock_on)
      : device_(device),
        detections_(detections),
        images_(images),
        newest_frame_ns_(newest_frame_ns),
        newest_detection_(newest_detection),
        lock_on_(lock_on) {}
  void step(rt::TimeNs now_ns) override {
    if (auto image = device_.grab(now_ns)) {
      newest_frame_ns_.store(image->stamp_ns, std::memory_order_relaxed);
      images_.write(std::move(image));
    }
    while (auto frame = device_.grabDetections(now_ns)) {
      // A device that detects (the simulator's keypoint mode) reports everyone it sees; which one is
      // followed is chosen here, as the image pipeline's detector chooses it (keypoint_lock_on.hpp).
      lock_on_.apply(*frame);
      newest_frame_ns_.store(frame->stamp_ns, std::memory_order_relaxed);
      newest_detection_.write(*frame);
      detections_.try_push(*frame);
    }
  }

 private:
  hal::GimbalCamera& device_;
  rt::SpscQueue<hal::DetectionFrame>& detections_;
  rt::SharedSlot<hal::ImageFrame>& images_;
  std::atomic<rt::TimeNs>& newest_frame_ns_;  ///< camera health, for the supervisor
  rt::LatestSlot<hal::DetectionFrame>& newest_detection_;
  perception::KeypointLockOn lock_on_;
};

/// Publishes each new depth frame on the depth channel -- unless it is blank (hal::isBlankDepth: fewer than 0.5 %
/// of its pixels hold a range) after the camera has once shown data, while its view holds ground it would range. A
/// camera that goes on delivering frames of zeros is as blind as one delivering none, and the supervisor's depth
/// failsafe must see it so (issue 23's fault matrix: with them published, the drone flew on a map no longer
/// updated). Before the first frame with data they are published: on the ground in an open field everything is
/// nearer than the minimum range or beyond the maximum, and take-off must not wait for data it cannot have. A
/// view of the sky -- the nose pitched up braking, at the newest odometry's attitude and height
/// (hal::viewHoldsGroundWithin) -- returns zeros from a working camera too, and those are published
/// (hal/depth_view.hpp: the supervisor held a drone braking at the world's edge).
class DepthCameraTask final : public rt::Task {
 public:
  /// A working depth camera ranges the ground nearer than this: the reach the mapper is configured to trust
  /// (mapping.max_range_m, 6 m in config/sim.yaml and config/drone.yaml; the D435 driver itself reads to 8 m).
  static constexpr double kGroundReachM = 6.0;
  DepthCameraTask(hal::DepthCamera& device, rt::SharedSlot<hal::DepthFrame>& out,
                  const rt::LatestSlot<hal::OdometrySample>& odometry)
      : device_(device), out_(out), odometry_(odometry) {}
  void step(rt::TimeNs now_ns) override {
    auto frame = device_.grab(now_ns);
    if (!frame) return;
    if (hal::isBlankDepth(*frame)) {
      ++blank_frames_;
      if (seen_data_ && viewHoldsGround(*frame)) return;
    } else {
      seen_data_ = true;
    }
    out_.write(std::move(frame));
  }
  std::uint64_t blankFrames() const { return blank_frames_; }

 private:
  /// Whether the view at the newest odometry holds ground in reach; unknown attitude (no odometry yet): as if it
  /// did -- a silent camera is not given the benefit of the doubt.
  bool viewHoldsGround(const hal::DepthFrame& frame) const {
    const auto pose = odometry_.read();
    if (!pose) return true;
    Eigen::Isometry3d T_WB = Eigen::Isometry3d::Identity();
    T_WB.linear() = pose->q_WB.toRotationMatrix();
    T_WB.translation() = pose->p_WB_m;
    return hal::viewHoldsGroundWithin(T_WB * frame.T_BC, frame.intrinsics, kGroundReachM);
  }

  hal::DepthCamera& device_;
  rt::SharedSlot<hal::DepthFrame>& out_;
  const rt::LatestSlot<hal::OdometrySample>& odometry_;
  std::uint64_t blank_frames_ = 0;
  bool seen_data_ = false;
};

/// Publishes the gimbal encoder's newest reading, and every new one (by stamp) on the stream that
/// feeds the target task's angle history.
class GimbalEncoderTask final : public rt::Task {
 public:
  GimbalEncoderTask(hal::Gimbal& device, rt::LatestSlot<hal::GimbalState>& out, rt::SpscQueue<hal::GimbalState>& stream)
      : device_(device), out_(out), stream_(stream) {}
  void step(rt::TimeNs now_ns) override {
    const auto state = device_.read(now_ns);
    if (!state) return;
    out_.write(*state);
    if (state->stamp_ns > last_stamp_ns_) {
      last_stamp_ns_ = state->stamp_ns;
      stream_.try_push(*state);
    }
  }

 private:
  hal::Gimbal& device_;
  rt::LatestSlot<hal::GimbalState>& out_;
  rt::SpscQueue<hal::GimbalState>& stream_;
  rt::TimeNs last_stamp_ns_ = -1;
};

/// Advances the simulation to the executor's time (the physics of sim backends).
class SimWorldTask final : public rt::Task {
 public:
  SimWorldTask(std::shared_ptr<hal::sim::Simulation> sim, const rt::LatestSlot<hal::DetectionFrame>& newest_detection,
               const rt::LatestSlot<hal::DetectionFrame>& followed_detection)
      : sim_(std::move(sim)), newest_detection_(newest_detection), followed_detection_(followed_detection) {}
  void step(rt::TimeNs now_ns) override {
    // Whom the pipeline follows, for the identity metrics (the followed detection is matched to the
    // truth by the simulator): each frame once. The person the estimator was given where a target task
    // runs (it may choose another than the lock-on, issue 22), else the detector output's choice.
    auto frame = followed_detection_.read();
    if (frame) {
      uses_followed_ = true;
    } else if (!uses_followed_) {
      frame = newest_detection_.read();
    }
    if (frame && frame->sequence != last_sequence_) {
      last_sequence_ = frame->sequence;
      sim_->recordFollowed(*frame);
    }
    sim_->step(now_ns);
  }

 private:
  std::shared_ptr<hal::sim::Simulation> sim_;
  const rt::LatestSlot<hal::DetectionFrame>& newest_detection_;
  const rt::LatestSlot<hal::DetectionFrame>& followed_detection_;
  bool uses_followed_ = false;
  std::uint64_t last_sequence_ = 0;
};

/// The simulator's truth-fed stand-in for planner and gimbal control (see baseline_follower.hpp):
/// reads ground truth, commands the vehicle and the gimbal through their devices. With
/// command_vehicle false it points only the gimbal (task `truth_gimbal`: the planner flies, and the
/// gimbal is aimed from the truth until gimbal control lands, issue 9).
class BaselineFollowTask final : public rt::Task {
 public:
  BaselineFollowTask(std::shared_ptr<hal::sim::Simulation> sim, hal::VehicleLink& vehicle, hal::Gimbal& gimbal,
                     bool command_vehicle = true)
      : sim_(std::move(sim)),
        follower_(hal::sim::BaselineFollowerParams{}, sim_->scenario().spec.drone.start_m,
                  sim_->scenario().spec.drone.start_yaw_rad),
        vehicle_(vehicle),
        gimbal_(gimbal),
        command_vehicle_(command_vehicle) {}
  void step(rt::TimeNs now_ns) override {
    const auto truth = sim_->truthOut().read();
    if (!truth) return;
    const hal::sim::FollowCommand command = follower_.update(*truth, now_ns);
    // The flight controller flies the odometry frame (issue 20: it drifts from the world).
    if (command_vehicle_)
      vehicle_.send(hal::sim::inOdometryFrame(hal::sim::OdometryFrameError{truth->odom_t_OW_m, truth->odom_yaw_OW_rad},
                                              command.setpoint));
    gimbal_.command(command.gimbal);
  }

 private:
  std::shared_ptr<hal::sim::Simulation> sim_;
  hal::sim::BaselineFollower follower_;
  hal::VehicleLink& vehicle_;
  hal::Gimbal& gimbal_;
  bool command_vehicle_;
};

/// Simulator only: compares the target estimate with where the person really is, at every step
/// while the person walks and the estimate is live (horizontal errors; the estimate is carried to
/// the step's time by its own velocity). The numbers go into summary.json ("estimation").
class TargetTruthCheckTask final : public rt::Task {
 public:
  TargetTruthCheckTask(std::shared_ptr<hal::sim::Simulation> sim,
                       const rt::LatestSlot<estimation::TargetEstimate>& estimate)
      : sim_(std::move(sim)), estimate_(estimate) {}
  void step(rt::TimeNs now_ns) override {
    const auto truth = sim_->truthOut().read();
    if (!truth || !truth->person_walking) return;
    ++steps_;
    const auto estimate = estimate_.read();
    if (!estimate || !estimate->initialised || estimate->lost) return;
    ++live_steps_;
    const double ahead_s = rt::nsToSeconds(now_ns - estimate->stamp_ns);
    const Eigen::Vector2d p_m = (estimate->p_WT_m + ahead_s * estimate->v_WT_mps).head<2>();
    // The estimate lives in the odometry frame (identity without drift, issue 20): so does the truth here.
    const hal::sim::OdometryFrameError T_OW{truth->odom_t_OW_m, truth->odom_yaw_OW_rad};
    const double position_error_m = (p_m - T_OW.toOdometry(truth->person_p_W_m).head<2>()).norm();
    const double velocity_error_mps = (estimate->v_WT_mps - T_OW.rotationOW() * truth->person_v_W_mps).head<2>().norm();
    position_error_sum_m_ += position_error_m;
    velocity_error_sum_mps_ += velocity_error_mps;
    position_error_max_m_ = std::max(position_error_max_m_, position_error_m);
  }
  std::uint64_t steps() const { return steps_; }
  std::uint64_t liveSteps() const { return live_steps_; }
  double positionErrorMeanM() const {
    return live_steps_ ? position_error_sum_m_ / static_cast<double>(live_steps_) : 0.0;
  }
  double positionErrorMaxM() const { return position_error_max_m_; }
  double velocityErrorMeanMps() const {
    return live_steps_ ? velocity_error_sum_mps_ / static_cast<double>(live_steps_) : 0.0;
  }

 private:
  std::shared_ptr<hal::sim::Simulation> sim_;
  const rt::LatestSlot<estimation::TargetEstimate>& estimate_;
  std::uint64_t steps_ = 0, live_steps_ = 0;
  double position_error_sum_m_ = 0.0, velocity_error_sum_mps_ = 0.0, position_error_max_m_ = 0.0;
};

}  // namespace aerotrack::app
