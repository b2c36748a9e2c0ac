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
#include "aerotrack/hal/sim/person_sprite.hpp"
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
  KeypointCameraParams camera;     ///< Intrinsics for both modes; the rest for keypoint mode.
  PersonSpriteSpec person_sprite;  ///< Image mode: the photo the person is cut out of.
};

struct DepthCameraSpec {
  double rate_hz = 15.0;
  Eigen::Vector3d mount_B_m = Eigen::Vector3d(0.12, 0.0, 0.0);  ///< Fixed, looking along body x.
  DepthCameraParams camera;
};

struct OdometrySpec {
  double rate_hz = 100.0;
  double latency_s = 0.010;
  double position_noise_m = 0.02;
  double velocity_noise_mps = 0.05;
  double yaw_noise_rad = 0.01;
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
};

struct ScenarioSpec {
  std::string name;
  std::string source;
  double end_margin_s = 5.0;  ///< Run this long after the person stops.
  double max_duration_s = 120.0;
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
/// every leg's speed before jitter (`aerotrack bench --speed`). Error if a generator cannot
/// place what it was asked to (e.g. the path leaves the region).
rt::Expected<ScenarioInstance> instantiate(const ScenarioSpec& spec, std::uint64_t seed,
                                           std::optional<double> speed_override_mps = std::nullopt);

}  // namespace aerotrack::hal::sim
