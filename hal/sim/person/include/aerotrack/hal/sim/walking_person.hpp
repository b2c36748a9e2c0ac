// The simulated person the drone follows: a walker on a polyline path with COCO-17 body keypoints.
// The path is smoothed into lines and circular corner arcs and timed by a speed profile with bounded
// acceleration (trapezoidal: the largest v(s) with |d(v^2)/ds| <= 2a under the leg and corner speed
// limits). The body follows Drillis & Contini's anthropometric proportions of the stature H (Winter,
// "Biomechanics and Motor Control of Human Movement", Fig. 4.1), with the torso stretched so that the
// upright neck-to-mid-hip length -- the "upper body length" of Fast-Tracker 2.0 Sect. IV -- equals
// PersonParams::torso_m. The gait is kinematic: cadence rises with speed as f = f_ref (v / v_ref)^0.58,
// i.e. step length proportional to v^0.42 (Grieve 1968, as used by Kuo 2001, J. Biomech. Eng. 123:264);
// the straight stance leg carries its ankle backwards under the hip at walking speed (no slip), the
// swing leg swings forward with a flexed knee, arms swing opposite to the legs, and the pelvis drops in
// double support (a capped compass gait, with heel rise where the cap applies).
#pragma once

#include <array>
#include <numbers>
#include <vector>

#include <Eigen/Core>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::sim {

/// Body and motion parameters of the walker. Validated by WalkingPerson::create.
struct PersonParams {
  double height_m = 1.75;  ///< Stature H, [0.5, 2.5] m.
  /// Upright 3D distance from the neck (mid-shoulders) to the mid-hips, the localizer's feature.
  /// Drillis & Contini give (0.818 - 0.530) H = 0.504 m for H = 1.75 m; allowed [0.2 H, 0.4 H].
  double torso_m = 0.50;
  double max_accel_mps2 = 1.5;  ///< |dv/dt| bound for speed changes, starts and stops (0, 10].
  /// A corner is walked as a circular arc of this radius, smaller where the legs are short or the
  /// arc would pass farther than this from the corner point; below 5 cm (and for a reversal) the
  /// person stops at the corner and turns on the spot. 0: stop and turn at every corner.
  double corner_radius_m = 0.5;
  double max_lateral_accel_mps2 = 2.0;           ///< On corner arcs v^2 / r stays below this.
  double max_yaw_rate_radps = std::numbers::pi;  ///< On arcs v / r stays below this; turning on the spot.
  /// Runner's corners: a person who runs does not slow to walking pace at every corner but widens it.
  /// When set, a corner between legs of speeds v1, v2 is an arc of radius max(corner_radius_m,
  /// min(v1, v2)^2 / max_lateral_accel_mps2) -- the radius at which the slower leg's speed needs just
  /// the allowed lateral acceleration -- still limited by half the legs and by max_corner_cut_m.
  bool wide_corners = false;
  /// How far a corner arc may pass from the corner point (the arc's midpoint to the vertex): the
  /// larger of this and corner_radius_m, [0, 10] m. Keeps a widened corner off the obstacles the path
  /// was cleared of.
  double max_corner_cut_m = 0.0;
  /// Legs walked backwards (PathPoint::backwards) are limited to this speed, (0, 3] m/s: people walk
  /// backwards slower than forwards (preferred ~0.6-1 m/s against 1.4 m/s forwards); 2 m/s is a brisk
  /// backward jog.
  double max_backward_speed_mps = 2.0;
  // Gait. Cadence f(v) = cadence_ref_hz * (v / gait_ref_speed_mps)^cadence_speed_exponent steps/s
  // (Grieve 1968: step length ~ v^0.42), constant below cadence_floor_speed_mps (steps shorten in
  // proportion to speed there, so the gait fades in and out smoothly); step length v / f. At 1.4 m/s
  // and H = 1.75 m: 1.8 steps/s, 0.78 m steps, legs (hip to ankle) swinging about +-25 deg.
  // The amplitudes below are at gait_ref_speed_mps and scale with step length.
  double cadence_ref_hz = 1.8;  ///< Steps per second at gait_ref_speed_mps (~108 steps/min).
  double gait_ref_speed_mps = 1.4;
  double cadence_speed_exponent = 0.58;                              ///< [0, 1).
  double cadence_floor_speed_mps = 0.3;                              ///< (0, gait_ref_speed_mps].
  double arm_swing_ref_rad = 20.0 * std::numbers::pi / 180.0;        ///< Shoulder swing amplitude, each way.
  double elbow_flex_ref_rad = 20.0 * std::numbers::pi / 180.0;       ///< Elbow flexion while walking.
  double swing_knee_flex_ref_rad = 50.0 * std::numbers::pi / 180.0;  ///< Peak, early in swing.
  /// Peak-to-peak vertical pelvis motion, lowest in double support (about 4-5 cm in adults; a straight
  /// compass gait would give 8.6 cm, so the stance heel rises instead).
  double pelvis_bob_ref_m = 0.04;
};

/// One corner of the path. Defaults let `PathPoint{{x, y}, speed}` be written.
struct PathPoint {
  Eigen::Vector2d p_W_m = Eigen::Vector2d::Zero();  ///< On the ground, world frame.
  double speed_mps = 1.4;  ///< Walking speed on the leg that starts here, (0, 6]; ignored at the last point.
  double pause_s = 0.0;    ///< Stand still here this long (first point: before walking; last: ignored).
  /// The leg that starts here is walked backwards: facing opposite to the direction of motion (heading
  /// = motion heading + pi), the gait played in reverse (backward walking is close to time-reversed
  /// forward walking: Grasso, Bianchi & Lacquaniti 1998, J. Neurophysiol. 80:1868), at most
  /// PersonParams::max_backward_speed_mps. Where the facing changes between legs the person stops and
  /// turns on the spot.
  bool backwards = false;
  /// |dv/dt| bound on the leg that starts here, (0, 10] m/s^2; 0: PersonParams::max_accel_mps2. A
  /// sprint start accelerates harder than a walker.
  double accel_mps2 = 0.0;
};

/// Segment lengths and head geometry, derived once from PersonParams (metres).
struct BodyDimensions {
  double hip_height_m = 0.0;       ///< Hip joints above the ground, standing (0.530 H).
  double shoulder_height_m = 0.0;  ///< hip_height_m + torso_m.
  double ankle_height_m = 0.0;     ///< 0.039 H.
  double thigh_m = 0.0;            ///< Hip to knee (0.245 H).
  double shank_m = 0.0;            ///< Knee to ankle (0.246 H).
  double upper_arm_m = 0.0;        ///< Shoulder to elbow (0.186 H).
  double forearm_m = 0.0;          ///< Elbow to wrist (0.146 H).
  double shoulder_width_m = 0.0;   ///< Between the shoulder keypoints (0.259 H).
  double hip_width_m = 0.0;        ///< Between the hip keypoints (0.191 H).
  /// Head keypoints relative to the neck (mid-shoulders) in the body frame (x forward, y left,
  /// z up); the right-side points mirror the left ones (y negated).
  Eigen::Vector3d nose_N_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d left_eye_N_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d left_ear_N_m = Eigen::Vector3d::Zero();
};

/// The person at one instant.
struct PersonState {
  double t_s = 0.0;
  Eigen::Vector3d p_W_m = Eigen::Vector3d::Zero();    ///< Ground point under the pelvis (z = 0).
  Eigen::Vector3d v_W_mps = Eigen::Vector3d::Zero();  ///< Of p_W_m (horizontal).
  double speed_mps = 0.0;                             ///< |v_W_mps|, also when walking backwards.
  /// Facing direction, from world +x towards +y, in (-pi, pi]; opposite to v_W_mps on backward legs.
  double heading_rad = 0.0;
  /// COCO-17 order (hal::CocoKeypoint); "left" is the person's left.
  std::array<Eigen::Vector3d, kNumKeypoints> keypoints_W_m{};
};

/// A person walking a polyline path once, then standing at its end. Immutable after create();
/// const methods are thread-safe.
class WalkingPerson {
 public:
  /// Validates the parameters and the path (at least one point, finite values, consecutive points at
  /// least 1 mm apart, leg speeds in (0, 6] m/s, backward legs' speeds at most
  /// params.max_backward_speed_mps, leg accelerations 0 or in (0, 10] m/s^2, pauses >= 0) and precomputes the
  /// arc-length parameterisation and the timed speed profile. Allocates; O(n).
  static rt::Expected<WalkingPerson> create(const PersonParams& params, std::vector<PathPoint> path);

  /// The person at time t_s (seconds since the start of the walk). Before 0: standing at the start,
  /// facing the first leg; after durationS(): standing at the end, facing along the last leg. A
  /// one-point path stands there facing +x. O(log n), allocation-free.
  PersonState state(double t_s) const;

  /// Time at which the person reaches the end of the path and stops, seconds.
  double durationS() const { return duration_s_; }
  /// Length of the smoothed path (lines and corner arcs), metres.
  double lengthM() const { return length_m_; }
  const PersonParams& params() const { return params_; }
  const BodyDimensions& body() const { return body_; }

  /// Body-frame keypoints (origin: ground under the pelvis; x forward, y left, z up) for walking at
  /// speed_mps with stride phase stride_cycles (cycles; the left foot touches down at integers).
  /// speed 0: standing upright, arms down. Allocation-free.
  std::array<Eigen::Vector3d, kNumKeypoints> bodyKeypoints(double speed_mps, double stride_cycles) const;

  /// Steps per second at speed_mps (0 at rest).
  double cadenceHz(double speed_mps) const;
  /// Step length at speed_mps, metres (0 at rest).
  double stepLengthM(double speed_mps) const;

 private:
  struct Piece {  ///< A line or a circular arc of the smoothed path.
    double s0_m = 0.0;
    double length_m = 0.0;
    bool is_arc = false;
    Eigen::Vector2d p0_W_m = Eigen::Vector2d::Zero();      ///< Line: start.
    Eigen::Vector2d dir_W = Eigen::Vector2d::UnitX();      ///< Line: unit direction.
    Eigen::Vector2d centre_W_m = Eigen::Vector2d::Zero();  ///< Arc: centre.
    double radius_m = 0.0;                                 ///< Arc: radius.
    double turn_sign = 0.0;                                ///< Arc: +1 left turn, -1 right turn.
    double heading0_rad = 0.0;                             ///< Tangent heading at the start.
    bool backwards = false;                                ///< Walked facing against the motion.
  };
  struct Phase {  ///< A time interval of constant acceleration along the path, or standing still.
    double t0_s = 0.0;
    double duration_s = 0.0;
    double s0_m = 0.0;
    double v0_mps = 0.0;
    double a_mps2 = 0.0;
    double stride0_cycles = 0.0;  ///< Gait phase at t0_s.
    bool dwell = false;           ///< Standing at s0_m; heading turns by turn_rad over turn_s first.
    double heading0_rad = 0.0;
    double turn_rad = 0.0;
    double turn_s = 0.0;
    bool backwards = false;  ///< Moving: the gait runs in reverse (stride phase decreases).
  };

  WalkingPerson() = default;

  double strideCycles(double v0_mps, double a_mps2, double tau_s) const;
  double cadenceIntegral(double speed_mps) const;

  PersonParams params_;
  BodyDimensions body_;
  Eigen::Vector2d start_W_m_ = Eigen::Vector2d::Zero();
  double start_heading_rad_ = 0.0;
  double cadence_gain_ = 0.0;  ///< f = gain * v^beta above the floor speed.
  double cadence_floor_hz_ = 0.0;
  double step_length_ref_m_ = 0.0;
  std::vector<Piece> pieces_;
  std::vector<double> piece_s0_m_;  ///< pieces_[i].s0_m, for the binary search.
  std::vector<Phase> phases_;
  std::vector<double> phase_t0_s_;  ///< phases_[i].t0_s, for the binary search.
  double duration_s_ = 0.0;
  double length_m_ = 0.0;
};

}  // namespace aerotrack::hal::sim
