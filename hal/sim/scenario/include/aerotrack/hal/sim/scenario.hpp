// Scenario files (config/scenarios/*.yaml, documented field by field in
// config/scenarios/README.md): the world's obstacles, listed and/or generated from a seed; the
// person and the path they walk; the drone's start and body; the sensors; how long to run; what
// counts as success. A ScenarioSpec is what the file says; instantiate() turns it and a seed into
// one concrete ScenarioInstance (generated trees and clutter, jittered obstacles, the turn side,
// the person's speed), so every trial is a pure function of (scenario, seed).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "aerotrack/hal/sim/bystanders.hpp"
#include "aerotrack/hal/sim/depth_camera.hpp"
#include "aerotrack/hal/sim/keypoint_camera.hpp"
#include "aerotrack/hal/sim/obstacle_world.hpp"
#include "aerotrack/hal/sim/person_cast.hpp"
#include "aerotrack/hal/sim/walking_person.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::sim {

/// Vertical cylinders ("trees") scattered in a region by Poisson-disc-like rejection sampling.
struct ForestGenerator {
  Eigen::Vector2d region_min_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d region_max_m = Eigen::Vector2d::Zero();
  double density_per_m2 = 0.0;  ///< Trees per square metre of the region.
  double radius_min_m = 0.15;
  double radius_max_m = 0.4;
  double height_m = 6.0;
  double min_gap_m = 0.8;         ///< Free space between two trunks.
  double path_clearance_m = 1.0;  ///< Free space between a trunk and the person's path or the drone's start.
};

/// Walls of a corridor of constant width around a polyline centreline, plus clutter (boxes
/// standing against the walls), for indoor scenarios.
struct CorridorGenerator {
  std::vector<Eigen::Vector2d> centreline_m;
  double width_m = 2.5;
  double wall_thickness_m = 0.2;
  double height_m = 3.0;
  int clutter_count = 0;             ///< Boxes placed against the walls at random.
  double clutter_depth_max_m = 0.5;  ///< How far a clutter box reaches into the corridor.
  double clutter_length_min_m = 0.4;
  double clutter_length_max_m = 1.2;
  double clutter_height_m = 1.2;
};

/// Behaviours a random walk may add to its legs (person.random_path.behaviours), drawn from their own
/// seeded stream so that a walk without them is unchanged. Each leg draws, in this order: a sprint
/// (the whole leg at sprint_speed_mps, accelerating at sprint_accel_mps2), a speed change mid-leg
/// (from a point 30-70 % along the leg, at speed_change_mps), a pause at the leg's end, and a
/// reversal at its end (the person turns on the spot and walks reversal_m back along the leg, past a
/// drone following behind, then turns again and carries on; with backwards_probability the walk back is
/// walked backwards instead, facing the way they came, towards the drone, at backwards_speed_mps).
struct PathBehaviours {
  double sprint_probability = 0.0;
  double sprint_speed_min_mps = 4.5;
  double sprint_speed_max_mps = 6.0;
  double sprint_accel_mps2 = 0.0;  ///< 0: PersonParams::max_accel_mps2.
  double speed_change_probability = 0.0;
  double speed_change_min_mps = 1.0;
  double speed_change_max_mps = 3.0;
  double pause_probability = 0.0;
  double pause_min_s = 1.0;
  double pause_max_s = 3.0;
  double reversal_probability = 0.0;
  double reversal_min_m = 2.0;  ///< At most 80 % of the leg is walked back.
  double reversal_max_m = 5.0;
  double backwards_probability = 0.0;  ///< Of a reversal's walk back.
  double backwards_speed_min_mps = 0.6;
  double backwards_speed_max_mps = 1.2;
};

/// A random walk for the person: legs of random length and turn inside a region.
struct RandomPathGenerator {
  Eigen::Vector2d region_min_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d region_max_m = Eigen::Vector2d::Zero();
  int legs = 6;
  double leg_min_m = 5.0;
  double leg_max_m = 10.0;
  double max_turn_rad = 1.6;
  double speed_min_mps = 1.0;
  double speed_max_mps = 1.5;
  std::optional<PathBehaviours> behaviours;  ///< None: the plain walk (no draws from its stream).
};

/// Per-seed variation of a scenario.
struct Randomization {
  double obstacle_jitter_m = 0.0;      ///< Listed obstacles move by up to this in x and y.
  bool mirror_y = false;               ///< Odd seeds mirror the world about y = 0 (the turn side).
  double speed_jitter_fraction = 0.0;  ///< The person's speeds scale by U(1 - f, 1 + f).
};

struct DroneSpec {
  Eigen::Vector3d start_m = Eigen::Vector3d::Zero();
  /// If set, the start's x, y (and yaw) are this far behind the person's start, facing along the
  /// first leg; start_m then gives only the height. For generated paths.
  std::optional<double> start_behind_person_m;
  double start_yaw_rad = 0.0;
  double radius_m = 0.25;  ///< Collision sphere (paper: 300 x 300 mm frame).
  double mass_kg = 1.0;
  double thrust_to_weight = 2.5;
};

/// What the simulated gimbal camera delivers: the detector's output (keypoints, the default) or
/// rendered images (hal/sim/render) for a real detector to run on.
enum class GimbalCameraMode { kKeypoints, kImage };

struct GimbalCameraSpec {
  GimbalCameraMode mode = GimbalCameraMode::kKeypoints;
  double rate_hz = 30.0;
  double latency_s = 0.040;  ///< Capture to detection result (the paper's detector time).
  Eigen::Vector3d mount_B_m = Eigen::Vector3d(0.08, 0.0, -0.06);  ///< Gimbal axis in the body frame.
  KeypointCameraParams camera;  ///< Intrinsics for both modes; the rest for keypoint mode.
  /// Image mode: the people drawn (the target and the bystanders wear them), and which is the target.
  PersonCastSpec cast = defaultCast();
  std::size_t target_person = 0;  ///< Index into cast.people.
};

struct DepthCameraSpec {
  double rate_hz = 15.0;
  Eigen::Vector3d mount_B_m = Eigen::Vector3d(0.12, 0.0, 0.0);  ///< Fixed, looking along body x.
  DepthCameraParams camera;
};

/// A relocalisation jump of the odometry frame: at t_s the odometry's report of the drone's
/// position steps by dp_m and its heading by dyaw_rad (the frame turns about the drone).
struct OdometryJump {
  double t_s = 0.0;  ///< Seconds since the simulation's start.
  Eigen::Vector3d dp_m = Eigen::Vector3d::Zero();
  double dyaw_rad = 0.0;
};

/// Visual-inertial odometry drift (sensors.odometry.drift): the odometry frame O moves away from
/// the world W as a random walk in position and yaw whose variance grows with the distance flown
/// (and optionally with time), plus jumps (hal/sim/disturbances.hpp has the model). All zero by
/// default: O = W, the odometry is the truth plus white noise.
struct OdometryDriftSpec {
  double position_m_per_sqrt_m = 0.0;  ///< x and y: std of the walk after 1 m flown.
  double z_m_per_sqrt_m = 0.0;         ///< z: std after 1 m flown.
  double yaw_rad_per_sqrt_m = 0.0;     ///< yaw: std after 1 m flown.
  double position_m_per_sqrt_s = 0.0;  ///< x, y and z: std after 1 s (drift while hovering).
  double yaw_rad_per_sqrt_s = 0.0;
  std::vector<OdometryJump> jumps;      ///< At given times.
  double random_jumps_per_min = 0.0;    ///< Poisson rate of seeded jumps.
  double random_jump_position_m = 0.0;  ///< Their size: horizontal, in a random direction.
  double random_jump_yaw_rad = 0.0;     ///< Their heading step, of random sign.
  bool enabled() const {
    return position_m_per_sqrt_m > 0.0 || z_m_per_sqrt_m > 0.0 || yaw_rad_per_sqrt_m > 0.0 ||
           position_m_per_sqrt_s > 0.0 || yaw_rad_per_sqrt_s > 0.0 || !jumps.empty() || random_jumps_per_min > 0.0;
  }
};

struct OdometrySpec {
  double rate_hz = 100.0;
  double latency_s = 0.010;
  double position_noise_m = 0.02;
  double velocity_noise_mps = 0.05;
  double yaw_noise_rad = 0.01;
  OdometryDriftSpec drift;
};

/// Wind (the optional top-level `wind:` section): a mean plus gusts, each axis a first-order
/// Gauss-Markov process (hal/sim/disturbances.hpp). The air-relative velocity drives the vehicle's
/// linear rotor drag and an optional quadratic body drag.
struct WindSpec {
  Eigen::Vector3d mean_W_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d gust_sigma_mps = Eigen::Vector3d::Zero();               ///< Stationary std per axis.
  Eigen::Vector3d gust_time_constant_s = Eigen::Vector3d::Constant(1.0);  ///< Correlation time per axis.
  double body_cd_area_m2 = 0.0;      ///< Drag coefficient times frontal area (0: no quadratic drag).
  double air_density_kgpm3 = 1.225;  ///< ISA sea level.
};

struct GimbalSpec {
  double max_rate_radps = 6.0;
  double time_constant_s = 0.05;           ///< First-order lag of the motor's speed loop.
  double encoder_resolution_rad = 9.6e-5;  ///< 2 pi / 65536, a 16-bit absolute encoder.
  double angle_gain_per_s = 8.0;           ///< Angle mode: rate = gain * error, limited.
};

struct SuccessSpec {
  double tracking_distance_m = 2.5;    ///< The desired distance to the person.
  double final_distance_factor = 2.0;  ///< At the end, within factor * tracking distance.
  /// The paper's verdict (followed_all_the_way, metrics.hpp): the longest loss of sight allowed, and
  /// the longest time farther than max_distance_m. 3 s: the example; a person walking at
  /// 1.5 m/s covers 4.5 m in it, more than the tracking distance.
  double max_loss_s = 3.0;
  /// 0: final_distance_factor * tracking_distance_m (5 m by default), so the paper's verdict asks of
  /// the whole run (excursions up to max_loss_s forgiven) what ours asks of its end.
  double max_distance_m = 0.0;
};

struct ScenarioSpec {
  std::string name;
  std::string source;
  double end_margin_s = 5.0;  ///< Run this long after the person stops.
  double max_duration_s = 120.0;
  /// Optional `supervisor:` section: the scenario's override of the config's supervisor.search_timeout_s (how
  /// long the drone searches after a relocation; issue 21 item 3). Nothing: the config's.
  std::optional<double> search_timeout_s;
  Eigen::Vector3d bounds_min_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d bounds_max_m = Eigen::Vector3d::Zero();
  std::vector<Box> boxes;
  std::vector<Cylinder> cylinders;
  std::optional<ForestGenerator> forest;
  std::optional<CorridorGenerator> corridor;
  PersonParams person;
  double person_start_delay_s = 3.0;  ///< The person starts walking after this (take-off time).
  std::vector<PathPoint> path;        ///< Empty when random_path generates it.
  std::optional<RandomPathGenerator> random_path;
  Randomization randomize;
  DroneSpec drone;
  GimbalCameraSpec gimbal_camera;
  DepthCameraSpec depth_camera;
  OdometrySpec odometry;
  GimbalSpec gimbal;
  std::optional<WindSpec> wind;  ///< None: still air (the vehicle's own drag only).
  SuccessSpec success;
  BystandersSpec bystanders;  ///< The other people (bystanders.hpp); none by default.
};

/// One concrete trial of a scenario.
struct ScenarioInstance {
  ScenarioSpec spec;  ///< With path and obstacles replaced by the concrete ones.
  std::uint64_t seed = 0;
  bool mirrored = false;
  double speed_scale = 1.0;
  double duration_s = 0.0;  ///< Person's start delay + walk + end margin, capped.
  /// The bystanders (spec.bystanders resolved for this seed) and the target's appearance.
  BystandersInstance bystanders;
};

rt::Expected<ScenarioSpec> loadScenarioSpec(const std::string& path);
rt::Expected<ScenarioSpec> parseScenarioSpec(const std::string& yaml_text, const std::string& source_name);

/// Resolves generators and randomisation for one seed. speed_override_mps, if set, replaces
/// every forward leg's speed before jitter (`aerotrack bench --speed`); backward legs keep theirs,
/// and after jitter every backward leg is capped at person.max_backward_speed_mps. Error if a generator cannot
/// place what it was asked to (e.g. the path leaves the region).
rt::Expected<ScenarioInstance> instantiate(const ScenarioSpec& spec, std::uint64_t seed,
                                           std::optional<double> speed_override_mps = std::nullopt);

}  // namespace aerotrack::hal::sim
