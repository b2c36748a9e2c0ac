// The closed-loop simulator (DESIGN.md: hal/sim): one scenario instance in motion. A rigid-body
// quadrotor under a geometric tracking controller follows the setpoints arriving through the
// vehicle link, as a flight controller would; the person walks their path; the gimbal motor turns
// the camera; the sensors sample at their rates with their noise and latency:
//   - gimbal camera in keypoint mode: the person's 17 keypoints projected, occluded by obstacles,
//     noisy, sometimes missed, delivered after the detector's latency (hal::DetectionFrame); in image
//     mode: the camera pose and the person at each exposure (CameraExposure), which the camera device
//     renders into an image (hal/sim/render) on its own thread, so the stepping thread stays cheap;
//   - depth camera fixed to the body, ray cast against the obstacles (hal::DepthFrame);
//   - odometry: truth plus noise, delayed; with sensors.odometry.drift, the truth expressed in a
//     drifting, jumping odometry frame O (disturbances.hpp), which the flight controller flies too
//     (a real one fuses VIO), so the drift moves the real drone; truth, metrics, collisions, the
//     cameras and the person stay in the world frame W;
//   - wind (the scenario's wind section): a force on the vehicle the controller does not know;
//   - gimbal encoder.
// Bystanders (bystanders.hpp) walk with sim time: the depth camera sees them and the drone collides
// with them (each a vertical cylinder, kPersonBodyRadiusM); they hide the target and each other from
// the gimbal camera; in keypoint mode the camera reports every visible person (at most
// hal::kMaxPersons, the largest in the image, ordered left to right) with a noisy appearance signature.
// It also keeps the ground-truth metrics a run is judged by (metrics.hpp).
//
// Threads: step() is called from one thread (the sim_world task). The device-facing channels are
// the rt channels below, so device tasks may run on other threads (`aerotrack sim --realtime`).
// truth(), metrics() and scenario() belong to the stepping thread (or to anyone after the run).
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <random>
#include <vector>

#include "aerotrack/hal/sim/disturbances.hpp"
#include "aerotrack/hal/sim/geometric_controller.hpp"
#include "aerotrack/hal/sim/gimbal_motor.hpp"
#include "aerotrack/hal/sim/metrics.hpp"
#include "aerotrack/hal/sim/obstacle_world.hpp"
#include "aerotrack/hal/sim/quadrotor.hpp"
#include "aerotrack/hal/sim/scenario.hpp"
#include "aerotrack/hal/sim/scene_renderer.hpp"
#include "aerotrack/hal/sim/walking_person.hpp"
#include "aerotrack/rt/latest_slot.hpp"
#include "aerotrack/rt/shared_slot.hpp"
#include "aerotrack/rt/spsc_queue.hpp"

namespace aerotrack::hal::sim {

using rt::DurationNs;

/// A window of simulated time [begin_s, end_s) (seconds since the simulation's start) in which a fault
/// is injected; begin_s < 0: never.
struct FaultWindow {
  double begin_s = -1.0;
  double end_s = -1.0;
  bool active(double t_s) const { return begin_s >= 0.0 && t_s >= begin_s && t_s < end_s; }
};

/// Faults the sim devices inject (issue 9: the supervisor's failsafes and relocation are tested with them).
struct SimFaults {
  FaultWindow camera_stop;      ///< The gimbal camera delivers no frames.
  FaultWindow person_occluded;  ///< Frames arrive, but the person is in none (a forced occlusion), depth frames too.
  FaultWindow odometry_freeze;  ///< Odometry repeats the last sample from before the window.
  FaultWindow depth_stop;       ///< The depth camera delivers no frames.
  // The wider fault matrix (issue 23; docs/modules/closed-loop.md, "Fault matrix"):
  FaultWindow gimbal_stuck;       ///< The gimbal motor ignores commands: it stays where it is.
  FaultWindow gimbal_silent;      ///< The gimbal motor reports nothing (its state stops arriving).
  FaultWindow vehicle_link_lost;  ///< Setpoints no longer reach the flight controller.
  FaultWindow camera_late;        ///< Frames (detector output, or rendered images) arrive 0.5 s after their exposure.
  FaultWindow detector_garbage;   ///< Keypoint mode: every reported person has random keypoints.
  FaultWindow depth_zero;         ///< The depth camera delivers frames of zeros (no data in any pixel).
};

/// How late camera_late delivers a frame, and how long the simulated flight controller waits for a
/// setpoint before it holds position on its own (PX4's offboard-loss failsafe, COM_OF_LOSS_T, 1 s).
inline constexpr double kCameraLateS = 0.5;
inline constexpr double kOffboardLossS = 1.0;

struct SimulationOptions {
  SimFaults faults;               ///< Injected device faults (none by default).
  double physics_step_s = 0.002;  ///< Controller and dynamics step (500 Hz, like a flight controller's attitude loop).
  bool render_depth = true;       ///< Off: no depth frames (tests and runs that need no mapping).
  double metrics_rate_hz = 50.0;
};

/// Ground truth at one instant.
struct SimTruth {
  TimeNs stamp_ns = 0;
  QuadrotorState drone;
  PersonState person;
  double gimbal_angle_rad = 0.0;
  Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();  ///< Gimbal camera (OpenCV axes).
};

/// Most bystanders an image-mode exposure carries (the nearest to the camera).
inline constexpr std::size_t kMaxExposureBystanders = 16;

/// One image-mode exposure of the gimbal camera: what its renderer needs, at the exposure time.
struct CameraExposure {
  TimeNs stamp_ns = 0;         ///< Exposure time.
  std::uint64_t sequence = 0;  ///< Frame counter (shared with keypoint mode's).
  Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();
  PersonState person;
  /// The bystanders nearest the camera (ids as Simulation::personStateAt's, 1..N), at most
  /// kMaxExposureBystanders.
  std::size_t bystander_count = 0;
  std::array<std::size_t, kMaxExposureBystanders> bystander_ids{};
  std::array<PersonState, kMaxExposureBystanders> bystanders{};
};

/// The truth other threads may read (through Simulation::truthOut()): small and fixed-size.
struct TruthSnapshot {
  TimeNs stamp_ns = 0;
  Eigen::Vector3d drone_p_W_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d drone_v_W_mps = Eigen::Vector3d::Zero();
  double drone_yaw_rad = 0.0;
  Eigen::Vector3d person_p_W_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d person_v_W_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d camera_p_W_m = Eigen::Vector3d::Zero();
  double gimbal_angle_rad = 0.0;
  bool person_walking = false;  ///< The person's start delay has passed.
  /// The odometry frame's pose in the world, T_OW (disturbances.hpp; identity without drift): the
  /// setpoints and the odometry are in O, p_O = R_z(odom_yaw_OW_rad) p_W + odom_t_OW_m.
  Eigen::Vector3d odom_t_OW_m = Eigen::Vector3d::Zero();
  double odom_yaw_OW_rad = 0.0;
};

}  // namespace aerotrack::hal::sim

static_assert(std::is_standard_layout_v<aerotrack::hal::sim::TruthSnapshot>);
template <>
struct aerotrack::rt::IsBitwiseCopyable<aerotrack::hal::sim::TruthSnapshot> : std::true_type {};

namespace aerotrack::hal::sim {

class Simulation {
 public:
  static rt::Expected<std::unique_ptr<Simulation>> create(const ScenarioInstance& scenario,
                                                          const SimulationOptions& options, TimeNs start_ns);

  /// Advances everything to now_ns in physics steps, sampling sensors when due. One thread.
  void step(TimeNs now_ns);

  // Device-facing channels (thread-safe; see the header paragraph).
  rt::LatestSlot<Setpoint>& setpointInbox() { return setpoint_in_; }
  rt::LatestSlot<GimbalCommand>& gimbalInbox() { return gimbal_in_; }
  const rt::LatestSlot<OdometrySample>& odometryOut() const { return odometry_out_; }
  const rt::LatestSlot<GimbalState>& gimbalOut() const { return gimbal_out_; }
  rt::SpscQueue<DetectionFrame>& detectionsOut() { return detections_out_; }
  const rt::SharedSlot<DepthFrame>& depthOut() const { return depth_out_; }
  const rt::LatestSlot<TruthSnapshot>& truthOut() const { return truth_out_; }
  /// Image mode only (otherwise never written): exposures for the camera device to render, oldest
  /// dropped when 4 wait. One consumer.
  rt::SpscQueue<CameraExposure>& exposuresOut() { return exposures_out_; }
  /// Image mode: the renderer (its sprite loaded by create()); null in keypoint mode. Immutable, so
  /// any thread may use it, with obstacles() (also immutable after create()).
  const SceneRenderer* renderer() const { return renderer_ ? &*renderer_ : nullptr; }

  // The stepping thread's view.
  const SimTruth& truth() const { return truth_; }
  const SimMetrics& metrics() const { return metrics_; }
  /// How often the simulated flight controller's offboard-loss failsafe made it hold (kOffboardLossS).
  std::uint64_t offboardLosses() const { return offboard_losses_; }
  const ScenarioInstance& scenario() const { return scenario_; }
  const ObstacleWorld& obstacles() const { return obstacles_; }
  const WalkingPerson& person() const { return person_; }
  double personStartS() const { return scenario_.spec.person_start_delay_s; }
  TimeNs startNs() const { return start_ns_; }
  const SimulationOptions& options() const { return options_; }
  /// Seconds since the simulation's start at now_ns (for the fault windows).
  double secondsSinceStart(TimeNs now_ns) const { return rt::nsToSeconds(now_ns - start_ns_); }
  /// Camera pose for a body pose and gimbal angle (OpenCV axes: z along the gimbal's x).
  Eigen::Isometry3d cameraPose(const QuadrotorState& drone, double gimbal_angle_rad) const;
  /// The person's state at sim time t_ns (standing at the start before their delay).
  PersonState personAt(TimeNs t_ns) const;
  /// Everyone in the world: 0 is the target, 1..N the bystanders (scenario().bystanders.people[id - 1]).
  std::size_t personCount() const { return 1 + bystanders_.size(); }
  /// Person id's true state at sim time t_ns (standing at their start before their delay). Pure;
  /// the stepping thread's (or anyone's after create(): the people are immutable).
  PersonState personStateAt(std::size_t id, TimeNs t_ns) const;
  /// Person id's true appearance signature (what the camera's noisy signatures scatter around).
  const AppearanceSignature& personAppearance(std::size_t id) const;
  /// Notes whom the autonomy stack follows: the detector output frame (its followed person,
  /// target_index) is matched to the true people at its exposure -- the person in the image whose
  /// keypoints project nearest the detection's (keypointMatchError: mean pixel distance over the
  /// reported keypoints, left and right allowed exchanged, within half their projected torso
  /// length) -- and the identity metrics record it (0: the target, k: bystander k, -1: nobody followed, or a detection
  /// that matches no one). Stepping thread; frames older than the last 64 exposures are ignored.
  void recordFollowed(const DetectionFrame& frame);
  /// The true person a detection (image pixels of the exposure `sequence`) belongs to, as above;
  /// -1 if none or the exposure is forgotten.
  /// `keep_id` (>= 0): the person matched before, kept while the detection still fits them within the threshold
  /// even if another fits better -- CLEAR MOT's rule for keeping a correspondence (Bernardin and Stiefelhagen 2008,
  /// Sect. 2.1.2): a detection of two overlapping people fits both, and the nearer by a few pixels is noise.
  int matchDetection(std::uint64_t sequence, const PersonDetection& detection, int keep_id = -1) const;

  /// Whether the person's torso is in the gimbal camera's view and line of sight, and if not why
  /// (out of the image is reported first: then the obstacles do not matter). The line of sight is
  /// blocked by the obstacles and by the bystanders where they stand at the stepping thread's
  /// current time.
  Sight personSight(const Eigen::Isometry3d& T_WC, const PersonState& person) const;
  /// The odometry frame's pose in the world now, T_OW (identity without sensors.odometry.drift).
  OdometryFrameError odometryFrameError() const { return drift_ ? drift_->error() : OdometryFrameError{}; }
  /// The drone's position error in the odometry frame now (p_O - p_W), m.
  Eigen::Vector3d odometryPositionErrorM() const {
    return odometryFrameError().toOdometry(quad_.state().p_W_m) - quad_.state().p_W_m;
  }
  /// The wind at the drone now, W (zero without a wind section).
  Eigen::Vector3d windW() const { return wind_ ? wind_->velocityW() : Eigen::Vector3d::Zero(); }

 private:
  struct DetectionMatch {
    int nearest = -1;  ///< The person the detection fits best, or -1.
    int kept = -1;     ///< keep_id if the detection fits them, else nearest.
  };
  /// matchDetection's both answers from one pass over the people.
  DetectionMatch match(std::uint64_t sequence, const PersonDetection& detection, int keep_id) const;
  Simulation(const ScenarioInstance& scenario, const SimulationOptions& options, ObstacleWorld obstacles,
             WalkingPerson person, Quadrotor quad, GeometricController controller, TimeNs start_ns);
  void physicsStep(double dt_s);
  void sampleDueSensors();
  void captureCamera();
  void captureDepth();
  void sampleOdometry();
  void releaseDetections();
  void publishTruth();
  /// bodies_ (every person, the followed one first) at t_ns (no work if already there).
  void refreshBodies(TimeNs t_ns);
  /// The static obstacles and the people's bodies except person skip_id's leave the segment clear.
  bool sightClear(const Eigen::Vector3d& a_W_m, const Eigen::Vector3d& b_W_m, std::size_t skip_id) const;
  /// Keypoint mode with bystanders: everyone observed, the largest kMaxPersons reported.
  void observeCrowd(const Eigen::Isometry3d& T_WC, DetectionFrame& frame);
  int target_slot_ = -1;  ///< The target's slot in the frame being captured (-1: not reported).

  ScenarioInstance scenario_;
  SimulationOptions options_;
  ObstacleWorld obstacles_;
  WalkingPerson person_;
  Quadrotor quad_;
  GeometricController controller_;
  GimbalMotor gimbal_;
  TimeNs start_ns_;
  TimeNs now_ns_;
  DurationNs physics_step_ns_;
  std::mt19937_64 camera_rng_, depth_rng_, odometry_rng_;
  std::optional<OdometryDrift> drift_;  ///< Only with sensors.odometry.drift (own rng streams).
  std::optional<WindField> wind_;       ///< Only with a wind section (own rng stream).
  // Bystanders: their walkers (and start delays, s since the start); their bodies (bystander i is
  // body i + 1; body 0 is the target's, an occluder of bystanders but not an obstacle, as before)
  // at bodies_ns_; keypoint noise of bystanders and every person's appearance noise, each from
  // its own stream so that runs without bystanders keep the target's detections bit for bit.
  std::vector<WalkingPerson> bystanders_;
  std::vector<double> bystander_delay_s_;
  std::vector<Cylinder> bodies_;
  TimeNs bodies_ns_ = -1;
  std::size_t sight_skip_id_ = 0;  ///< The person whose keypoints observe() is checking.
  struct Candidate {
    PersonDetection detection;
    std::size_t id = 0;
    double area_px2 = 0.0;
  };
  std::vector<Candidate> candidates_;
  std::mt19937_64 crowd_rng_, appearance_rng_;

  Setpoint active_setpoint_;
  std::uint64_t setpoint_version_ = 0;
  bool offboard_hold_ = false;  ///< The flight controller holds: no setpoint for kOffboardLossS.
  std::uint64_t offboard_losses_ = 0;
  GimbalCommand active_gimbal_command_;
  std::uint64_t gimbal_version_ = 0;

  // Sensor schedules.
  TimeNs next_camera_ns_, next_depth_ns_, next_odometry_ns_, next_metrics_ns_;
  DurationNs camera_period_ns_, depth_period_ns_, odometry_period_ns_, metrics_period_ns_;
  std::uint64_t camera_sequence_ = 0, depth_sequence_ = 0;
  // The camera's recent exposures, for matching the pipeline's followed detection to the truth.
  struct Exposure {
    std::uint64_t sequence = 0;
    TimeNs stamp_ns = 0;
    Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();
  };
  std::array<Exposure, 64> exposures_{};
  // Detections waiting for their latency to pass (a small fixed ring).
  std::array<DetectionFrame, 16> pending_{};
  std::size_t pending_head_ = 0, pending_count_ = 0;
  // Odometry delay line.
  std::array<OdometrySample, 256> odometry_delay_{};
  std::size_t odometry_head_ = 0, odometry_count_ = 0;

  SimTruth truth_;
  SimMetrics metrics_;

  rt::LatestSlot<Setpoint> setpoint_in_;
  rt::LatestSlot<GimbalCommand> gimbal_in_;
  rt::LatestSlot<OdometrySample> odometry_out_;
  rt::LatestSlot<GimbalState> gimbal_out_;
  rt::SpscQueue<DetectionFrame> detections_out_{8, rt::OverflowPolicy::kDropOldest};
  rt::SharedSlot<DepthFrame> depth_out_;
  rt::LatestSlot<TruthSnapshot> truth_out_;
  rt::SpscQueue<CameraExposure> exposures_out_{4, rt::OverflowPolicy::kDropOldest};
  std::optional<SceneRenderer> renderer_;
};

}  // namespace aerotrack::hal::sim
