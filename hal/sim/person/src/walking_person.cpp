// Walking person: path smoothing (lines + corner arcs), bounded-acceleration speed profile, and the
// kinematic gait that places the COCO-17 keypoints. Models and references: walking_person.hpp.
#include "aerotrack/hal/sim/walking_person.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

namespace aerotrack::hal::sim {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kMaxLegSpeedMps = 6.0;
constexpr double kMaxBackwardSpeedMps = 3.0;
constexpr double kMaxLegAccelMps2 = 10.0;
constexpr double kMinLegLengthM = 1e-3;
constexpr double kMinArcRadiusM = 0.05;  // Tighter corners: stop and turn on the spot.
constexpr double kStraightRad = 1e-9;    // Smaller turns at a vertex are no corner at all.
constexpr double kTinyM = 1e-12;

// Drillis & Contini segment proportions of the stature H (Winter, Fig. 4.1).
constexpr double kHipHeightH = 0.530;
constexpr double kKneeHeightH = 0.285;
constexpr double kAnkleHeightH = 0.039;
constexpr double kShoulderHeightH = 0.818;
constexpr double kShoulderWidthH = 0.259;
constexpr double kHipWidthH = 0.191;
constexpr double kUpperArmH = 0.186;
constexpr double kForearmH = 0.146;
// Head, relative to the shoulder line: eye height 0.936 H (Drillis & Contini); the nose tip about
// 2.5 cm below the eyes and 10 cm ahead of the ears; ears about level with the eyes, head breadth
// 0.088 H (15 cm), interpupillary distance 0.036 H (6.3 cm).
constexpr double kEyeHeightH = 0.936;
constexpr double kNoseHeightH = 0.922;
constexpr double kEarHeightH = 0.925;
constexpr double kNoseForwardH = 0.060;
constexpr double kEyeForwardH = 0.045;
constexpr double kEyeHalfSpacingH = 0.018;
constexpr double kEarHalfSpacingH = 0.044;
constexpr double kMaxGaitScale = 2.0;  // Cap on the amplitude scale at very high speeds.

double wrapAngle(double a_rad) {
  a_rad = std::remainder(a_rad, 2.0 * kPi);  // [-pi, pi]
  return a_rad <= -kPi ? a_rad + 2.0 * kPi : a_rad;
}

bool finite(double x) {
  return std::isfinite(x);
}

rt::Status checkRange(const char* name, double value, double lo, double hi) {
  if (!finite(value) || value < lo || value > hi) {
    return rt::Error{std::string("PersonParams.") + name + ": " + std::to_string(value) + " is outside [" +
                     std::to_string(lo) + ", " + std::to_string(hi) + "]"};
  }
  return rt::ok();
}

rt::Status validateParams(const PersonParams& p) {
  const double h = p.height_m;
  struct Check {
    const char* name;
    double value, lo, hi;
  };
  if (auto s = checkRange("height_m", h, 0.5, 2.5); !s) return s;
  const Check checks[] = {
      {"torso_m", p.torso_m, 0.2 * h, 0.4 * h},
      {"max_accel_mps2", p.max_accel_mps2, 1e-3, 10.0},
      {"corner_radius_m", p.corner_radius_m, 0.0, 10.0},
      {"max_lateral_accel_mps2", p.max_lateral_accel_mps2, 1e-3, 20.0},
      {"max_yaw_rate_radps", p.max_yaw_rate_radps, 1e-3, 20.0},
      {"max_corner_cut_m", p.max_corner_cut_m, 0.0, 10.0},
      {"max_backward_speed_mps", p.max_backward_speed_mps, 1e-3, kMaxBackwardSpeedMps},
      {"cadence_ref_hz", p.cadence_ref_hz, 0.1, 5.0},
      {"gait_ref_speed_mps", p.gait_ref_speed_mps, 0.1, kMaxLegSpeedMps},
      {"cadence_speed_exponent", p.cadence_speed_exponent, 0.0, 0.99},
      {"cadence_floor_speed_mps", p.cadence_floor_speed_mps, 0.01, p.gait_ref_speed_mps},
      {"arm_swing_ref_rad", p.arm_swing_ref_rad, 0.0, kPi / 4.0},
      {"elbow_flex_ref_rad", p.elbow_flex_ref_rad, 0.0, kPi / 4.0},
      {"swing_knee_flex_ref_rad", p.swing_knee_flex_ref_rad, 0.0, kPi / 2.0},
      {"pelvis_bob_ref_m", p.pelvis_bob_ref_m, 0.0, 0.05 * h},
  };
  for (const Check& c : checks) {
    if (auto s = checkRange(c.name, c.value, c.lo, c.hi); !s) return s;
  }
  return rt::ok();
}

rt::Status validatePath(const PersonParams& params, const std::vector<PathPoint>& path) {
  if (path.empty()) return rt::Error{"WalkingPerson: the path has no points"};
  for (std::size_t i = 0; i < path.size(); ++i) {
    const PathPoint& q = path[i];
    const std::string at = "WalkingPerson: path[" + std::to_string(i) + "]";
    if (!q.p_W_m.allFinite()) return rt::Error{at + ".p_W_m is not finite"};
    if (!finite(q.pause_s) || q.pause_s < 0.0) return rt::Error{at + ".pause_s must be >= 0"};
    if (i + 1 == path.size()) break;
    if (!finite(q.speed_mps) || q.speed_mps <= 0.0 || q.speed_mps > kMaxLegSpeedMps) {
      return rt::Error{at + ".speed_mps: " + std::to_string(q.speed_mps) + " is outside (0, 6]"};
    }
    if (q.backwards && q.speed_mps > params.max_backward_speed_mps) {
      return rt::Error{at + ".speed_mps: " + std::to_string(q.speed_mps) + " is above max_backward_speed_mps (" +
                       std::to_string(params.max_backward_speed_mps) + ") on a backward leg"};
    }
    if (!finite(q.accel_mps2) || q.accel_mps2 < 0.0 || q.accel_mps2 > kMaxLegAccelMps2) {
      return rt::Error{at + ".accel_mps2: " + std::to_string(q.accel_mps2) + " is outside [0, 10]"};
    }
    if ((path[i + 1].p_W_m - q.p_W_m).norm() < kMinLegLengthM) {
      return rt::Error{at + " and the next point are less than 1 mm apart"};
    }
  }
  return rt::ok();
}

BodyDimensions makeBody(const PersonParams& p) {
  const double h = p.height_m;
  BodyDimensions b;
  b.hip_height_m = kHipHeightH * h;
  b.shoulder_height_m = b.hip_height_m + p.torso_m;
  b.ankle_height_m = kAnkleHeightH * h;
  b.thigh_m = (kHipHeightH - kKneeHeightH) * h;
  b.shank_m = (kKneeHeightH - kAnkleHeightH) * h;
  b.upper_arm_m = kUpperArmH * h;
  b.forearm_m = kForearmH * h;
  b.shoulder_width_m = kShoulderWidthH * h;
  b.hip_width_m = kHipWidthH * h;
  b.nose_N_m = {kNoseForwardH * h, 0.0, (kNoseHeightH - kShoulderHeightH) * h};
  b.left_eye_N_m = {kEyeForwardH * h, kEyeHalfSpacingH * h, (kEyeHeightH - kShoulderHeightH) * h};
  b.left_ear_N_m = {0.0, kEarHalfSpacingH * h, (kEarHeightH - kShoulderHeightH) * h};
  return b;
}

void placeArm(const BodyDimensions& b, const Eigen::Vector3d& shoulder, double swing_rad, double elbow_flex_rad,
              Eigen::Vector3d& elbow, Eigen::Vector3d& wrist) {
  elbow = shoulder + b.upper_arm_m * Eigen::Vector3d(std::sin(swing_rad), 0.0, -std::cos(swing_rad));
  const double f = swing_rad + elbow_flex_rad;
  wrist = elbow + b.forearm_m * Eigen::Vector3d(std::sin(f), 0.0, -std::cos(f));
}

// Hip angle theta (hip-to-knee from the downward vertical, positive forward) and knee flexion kappa of
// a leg at leg phase psi in [0, 1); half_step_m is the ankle's largest distance ahead of the hip.
// Stance [0, 0.5): straight leg whose ankle moves linearly from +half_step_m to -half_step_m (no slip at
// constant speed). Swing [0.5, 1): the ankle returns to +half_step_m on a cosine while the knee flexes
// as (27/4) p (1 - p)^2 (peak at a third of the swing, zero slope at heel strike); theta solves
// l1 sin(theta) + l2 sin(theta - kappa) = x in closed form. The swing ankle is never lower than the
// stance ankle: it is closer to the hip and at least as far ahead of or behind it.
void legAngles(const BodyDimensions& b, double psi, double half_step_m, double knee_peak_rad, double& theta,
               double& kappa) {
  const double l1 = b.thigh_m, l2 = b.shank_m;
  if (psi < 0.5) {
    kappa = 0.0;
    theta = std::asin(std::clamp(half_step_m * (1.0 - 4.0 * psi) / (l1 + l2), -1.0, 1.0));
    return;
  }
  const double p = 2.0 * (psi - 0.5);
  kappa = knee_peak_rad * 6.75 * p * (1.0 - p) * (1.0 - p);
  const double x = -half_step_m * std::cos(kPi * p);
  // l1 sin(theta) + l2 sin(theta - kappa) = r sin(theta - phi)
  const double ca = l1 + l2 * std::cos(kappa), sa = l2 * std::sin(kappa);
  const double r = std::hypot(ca, sa);
  theta = std::atan2(sa, ca) + std::asin(std::clamp(x / r, -1.0, 1.0));
}

void placeLeg(const BodyDimensions& b, const Eigen::Vector3d& hip, double theta, double kappa, Eigen::Vector3d& knee,
              Eigen::Vector3d& ankle) {
  knee = hip + b.thigh_m * Eigen::Vector3d(std::sin(theta), 0.0, -std::cos(theta));
  ankle = knee + b.shank_m * Eigen::Vector3d(std::sin(theta - kappa), 0.0, -std::cos(theta - kappa));
}

double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

}  // namespace

double WalkingPerson::cadenceHz(double speed_mps) const {
  if (!(speed_mps > 0.0)) return 0.0;
  if (speed_mps <= params_.cadence_floor_speed_mps) return cadence_floor_hz_;
  return cadence_gain_ * std::pow(speed_mps, params_.cadence_speed_exponent);
}

double WalkingPerson::stepLengthM(double speed_mps) const {
  return speed_mps > 0.0 ? speed_mps / cadenceHz(speed_mps) : 0.0;
}

// Integral of the cadence over speed, G(v) = int_0^v f(u) du, in closed form.
double WalkingPerson::cadenceIntegral(double speed_mps) const {
  const double v_floor = params_.cadence_floor_speed_mps;
  if (speed_mps <= v_floor) return cadence_floor_hz_ * std::max(0.0, speed_mps);
  const double e = params_.cadence_speed_exponent + 1.0;
  return cadence_floor_hz_ * v_floor + cadence_gain_ * (std::pow(speed_mps, e) - std::pow(v_floor, e)) / e;
}

// Stride cycles (two steps each) walked in tau_s from speed v0 at constant acceleration a: the
// integral of f(v(t)) / 2 dt = (G(v) - G(v0)) / (2 a).
double WalkingPerson::strideCycles(double v0_mps, double a_mps2, double tau_s) const {
  if (std::abs(a_mps2) < 1e-9) return 0.5 * cadenceHz(v0_mps) * tau_s;
  const double v = std::max(0.0, v0_mps + a_mps2 * tau_s);
  return 0.5 * (cadenceIntegral(v) - cadenceIntegral(v0_mps)) / a_mps2;
}

std::array<Eigen::Vector3d, kNumKeypoints> WalkingPerson::bodyKeypoints(double speed_mps, double stride_cycles) const {
  const BodyDimensions& b = body_;
  const double leg_m = b.thigh_m + b.shank_m;
  const double step_m = stepLengthM(std::max(0.0, speed_mps));
  const double k = std::min(kMaxGaitScale, step_m / step_length_ref_m_);  // amplitude scale, 0 at rest
  const double half_step_m = std::min(0.95 * leg_m, 0.5 * step_m);
  const double knee_peak_rad = k * params_.swing_knee_flex_ref_rad;
  const double psi_l = stride_cycles - std::floor(stride_cycles);
  const double psi_r = psi_l < 0.5 ? psi_l + 0.5 : psi_l - 0.5;
  double theta_l = 0.0, kappa_l = 0.0, theta_r = 0.0, kappa_r = 0.0;
  legAngles(b, psi_l, half_step_m, knee_peak_rad, theta_l, kappa_l);
  legAngles(b, psi_r, half_step_m, knee_peak_rad, theta_r, kappa_r);

  // The pelvis drops by the bob, but never so far that the straight stance leg would push its ankle
  // below the standing ankle height (beyond that the stance heel rises).
  const double theta_stance = psi_l < 0.5 ? theta_l : theta_r;
  const double bob_m = k * params_.pelvis_bob_ref_m * 0.5 * (1.0 + std::cos(4.0 * kPi * psi_l));
  const double pelvis_z = b.hip_height_m - std::min(bob_m, leg_m * (1.0 - std::cos(theta_stance)));
  const double shoulder_z = pelvis_z + params_.torso_m;
  const double hy = 0.5 * b.hip_width_m;
  const double sy = 0.5 * b.shoulder_width_m;

  std::array<Eigen::Vector3d, kNumKeypoints> kp;
  using K = CocoKeypoint;
  kp[index(K::kLeftHip)] = {0.0, hy, pelvis_z};
  kp[index(K::kRightHip)] = {0.0, -hy, pelvis_z};
  kp[index(K::kLeftShoulder)] = {0.0, sy, shoulder_z};
  kp[index(K::kRightShoulder)] = {0.0, -sy, shoulder_z};
  const Eigen::Vector3d neck(0.0, 0.0, shoulder_z);
  const auto mirror = [](const Eigen::Vector3d& q) { return Eigen::Vector3d(q.x(), -q.y(), q.z()); };
  kp[index(K::kNose)] = neck + b.nose_N_m;
  kp[index(K::kLeftEye)] = neck + b.left_eye_N_m;
  kp[index(K::kRightEye)] = neck + mirror(b.left_eye_N_m);
  kp[index(K::kLeftEar)] = neck + b.left_ear_N_m;
  kp[index(K::kRightEar)] = neck + mirror(b.left_ear_N_m);
  placeLeg(b, kp[index(K::kLeftHip)], theta_l, kappa_l, kp[index(K::kLeftKnee)], kp[index(K::kLeftAnkle)]);
  placeLeg(b, kp[index(K::kRightHip)], theta_r, kappa_r, kp[index(K::kRightKnee)], kp[index(K::kRightAnkle)]);

  // Each arm swings against the leg on its side: forward while that foot is behind.
  const double swing_l = -k * params_.arm_swing_ref_rad * std::cos(2.0 * kPi * psi_l);
  const double flex = k * params_.elbow_flex_ref_rad;
  placeArm(b, kp[index(K::kLeftShoulder)], swing_l, flex, kp[index(K::kLeftElbow)], kp[index(K::kLeftWrist)]);
  placeArm(b, kp[index(K::kRightShoulder)], -swing_l, flex, kp[index(K::kRightElbow)], kp[index(K::kRightWrist)]);
  return kp;
}

rt::Expected<WalkingPerson> WalkingPerson::create(const PersonParams& params, std::vector<PathPoint> path) {
  if (auto s = validateParams(params); !s) return s.error();
  if (auto s = validatePath(params, path); !s) return s.error();

  WalkingPerson w;
  w.params_ = params;
  w.body_ = makeBody(params);
  w.cadence_gain_ = params.cadence_ref_hz / std::pow(params.gait_ref_speed_mps, params.cadence_speed_exponent);
  w.cadence_floor_hz_ = w.cadence_gain_ * std::pow(params.cadence_floor_speed_mps, params.cadence_speed_exponent);
  w.step_length_ref_m_ = params.gait_ref_speed_mps / params.cadence_ref_hz;
  w.start_W_m_ = path.front().p_W_m;

  const std::size_t n = path.size();
  if (n == 1) return w;  // Stands at the only point, facing +x.

  // Legs.
  const std::size_t legs = n - 1;
  std::vector<Eigen::Vector2d> dir(legs);
  std::vector<double> len(legs);
  for (std::size_t i = 0; i < legs; ++i) {
    const Eigen::Vector2d d = path[i + 1].p_W_m - path[i].p_W_m;
    len[i] = d.norm();
    dir[i] = d / len[i];
  }
  // Facing along each leg's direction, or against it on a backward leg; each leg's acceleration bound.
  const auto facing_offset = [&](std::size_t leg) { return path[leg].backwards ? kPi : 0.0; };
  std::vector<double> leg_accel(legs);
  for (std::size_t i = 0; i < legs; ++i)
    leg_accel[i] = path[i].accel_mps2 > 0.0 ? path[i].accel_mps2 : params.max_accel_mps2;
  w.start_heading_rad_ = std::atan2(dir[0].y(), dir[0].x()) + facing_offset(0);

  // Corners at the interior vertices: none (straight on), an arc, or a stop (turn on the spot).
  enum class Corner { kNone, kArc, kStop };
  std::vector<Corner> corner(n, Corner::kNone);
  std::vector<double> turn(n, 0.0), radius(n, 0.0), tangent(n, 0.0);
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const Eigen::Vector2d& a = dir[i - 1];
    const Eigen::Vector2d& c = dir[i];
    const double delta = std::atan2(a.x() * c.y() - a.y() * c.x(), a.dot(c));  // (-pi, pi]
    turn[i] = delta;
    const double abs_delta = std::abs(delta);
    if (path[i].pause_s > 0.0 || path[i - 1].backwards != path[i].backwards) {
      corner[i] = Corner::kStop;
      continue;
    }
    if (abs_delta < kStraightRad) continue;
    if (abs_delta > kPi - 1e-6) {
      corner[i] = Corner::kStop;
      continue;
    }
    const double budget = std::min(i == 1 ? len[0] : 0.5 * len[i - 1], i + 2 == n ? len[i] : 0.5 * len[i]);
    const double half = 0.5 * abs_delta;
    // A runner widens the corner so that the slower leg's speed needs no more than the allowed
    // lateral acceleration (wide_corners); a walker keeps corner_radius_m.
    const double v_legs_mps = std::min(path[i - 1].speed_mps, path[i].speed_mps);
    const double r_want =
        params.wide_corners ? std::max(params.corner_radius_m, v_legs_mps * v_legs_mps / params.max_lateral_accel_mps2)
                            : params.corner_radius_m;
    const double cut_m = std::max(params.corner_radius_m, params.max_corner_cut_m);
    // Arc midpoint to corner distance: r (1 / cos(half) - 1) <= cut_m.
    double r = std::min({r_want, budget / std::tan(half), cut_m / (1.0 / std::cos(half) - 1.0)});
    if (!(r >= kMinArcRadiusM)) {
      corner[i] = Corner::kStop;
      continue;
    }
    corner[i] = Corner::kArc;
    radius[i] = r;
    tangent[i] = r * std::tan(half);
  }

  // Geometry pieces, their speed limits, and where the person must stop (run boundaries).
  std::vector<double> limit;                  // per piece, m/s
  std::vector<double> accel;                  // per piece, m/s^2
  std::vector<std::size_t> run_end_pieces;    // a run ends after this many pieces
  std::vector<std::size_t> run_end_vertices;  // at this path vertex
  std::vector<double> run_end_s;              // at this arc length
  double s = 0.0;
  const auto add_piece = [&](Piece piece, double v_limit, double a_limit) {
    if (piece.length_m <= kTinyM) return;
    piece.s0_m = s;
    s += piece.length_m;
    w.pieces_.push_back(piece);
    limit.push_back(v_limit);
    accel.push_back(a_limit);
  };
  for (std::size_t i = 0; i < legs; ++i) {
    Piece line;
    line.p0_W_m = path[i].p_W_m + dir[i] * tangent[i];
    line.dir_W = dir[i];
    line.heading0_rad = std::atan2(dir[i].y(), dir[i].x());
    line.length_m = std::max(0.0, len[i] - tangent[i] - tangent[i + 1]);
    line.backwards = path[i].backwards;
    add_piece(line, path[i].speed_mps, leg_accel[i]);
    const std::size_t v = i + 1;
    if (corner[v] == Corner::kArc) {
      Piece arc;
      arc.is_arc = true;
      arc.radius_m = radius[v];
      arc.turn_sign = turn[v] > 0.0 ? 1.0 : -1.0;
      arc.heading0_rad = line.heading0_rad;
      arc.backwards = line.backwards;  // an arc joins legs of the same facing (else: a stop)
      const Eigen::Vector2d start = path[v].p_W_m - dir[i] * tangent[v];
      arc.centre_W_m = start + arc.turn_sign * radius[v] * Eigen::Vector2d(-dir[i].y(), dir[i].x());
      arc.length_m = radius[v] * std::abs(turn[v]);
      const double v_corner =
          std::min(std::sqrt(params.max_lateral_accel_mps2 * radius[v]), params.max_yaw_rate_radps * radius[v]);
      add_piece(arc, std::min({path[i].speed_mps, path[v].speed_mps, v_corner}), std::min(leg_accel[i], leg_accel[v]));
    }
    if (v + 1 == n || corner[v] == Corner::kStop) {
      run_end_pieces.push_back(w.pieces_.size());
      run_end_vertices.push_back(v);
      run_end_s.push_back(s);
    }
  }
  w.length_m_ = s;
  w.piece_s0_m_.reserve(w.pieces_.size());
  for (const Piece& p : w.pieces_) w.piece_s0_m_.push_back(p.s0_m);

  // Timeline: optional start pause, then runs (each from rest to rest) separated by stop dwells.
  double t = 0.0;
  double stride = 0.0;
  const auto add_phase = [&](Phase ph) {
    ph.t0_s = t;
    ph.stride0_cycles = stride;
    // Backward legs play the gait in reverse.
    if (!ph.dwell) stride += (ph.backwards ? -1.0 : 1.0) * w.strideCycles(ph.v0_mps, ph.a_mps2, ph.duration_s);
    t += ph.duration_s;
    w.phases_.push_back(ph);
  };
  if (path[0].pause_s > 0.0) {
    Phase ph;
    ph.dwell = true;
    ph.duration_s = path[0].pause_s;
    ph.heading0_rad = w.start_heading_rad_;
    add_phase(ph);
  }
  std::size_t first = 0;
  for (std::size_t r = 0; r < run_end_pieces.size(); ++r) {
    const std::size_t last = run_end_pieces[r];
    const std::size_t m = last - first;
    // Squared speed at the piece boundaries: min of the adjacent limits, then the largest values
    // reachable with |d(v^2)/ds| <= 2a from rest at both ends (forward and backward passes).
    std::vector<double> u(m + 1, 0.0);
    for (std::size_t k = 1; k < m; ++k) {
      u[k] = std::min(limit[first + k - 1], limit[first + k]);
      u[k] *= u[k];
    }
    for (std::size_t k = 1; k <= m; ++k)
      u[k] = std::min(u[k], u[k - 1] + 2.0 * accel[first + k - 1] * w.pieces_[first + k - 1].length_m);
    for (std::size_t k = m; k-- > 0;)
      u[k] = std::min(u[k], u[k + 1] + 2.0 * accel[first + k] * w.pieces_[first + k].length_m);
    for (std::size_t k = 0; k < m; ++k) {
      const Piece& piece = w.pieces_[first + k];
      const double a = accel[first + k];
      const double lim2 = limit[first + k] * limit[first + k];
      const double len_k = piece.length_m;
      const double u0 = u[k], u1 = u[k + 1];
      // Up to three constant-acceleration parts: (distance, v^2 at its end).
      double x_acc = std::max(0.0, (lim2 - u0) / (2.0 * a));
      double x_dec = std::max(0.0, (lim2 - u1) / (2.0 * a));
      double peak = lim2;
      if (x_acc + x_dec > len_k) {
        x_acc = std::clamp((u1 - u0 + 2.0 * a * len_k) / (4.0 * a), 0.0, len_k);
        x_dec = len_k - x_acc;
        peak = u0 + 2.0 * a * x_acc;
      }
      const std::pair<double, double> parts[3] = {{x_acc, peak}, {len_k - x_acc - x_dec, peak}, {x_dec, u1}};
      double s_part = piece.s0_m;
      double u_start = u0;
      for (const auto& [dist, u_end] : parts) {
        if (dist <= kTinyM) continue;
        const double v0 = std::sqrt(std::max(0.0, u_start));
        const double v1 = std::sqrt(std::max(0.0, u_end));
        if (v0 + v1 <= 0.0) continue;
        Phase ph;
        ph.s0_m = s_part;
        ph.v0_mps = v0;
        ph.duration_s = 2.0 * dist / (v0 + v1);
        ph.a_mps2 = (v1 - v0) / ph.duration_s;
        ph.backwards = piece.backwards;
        add_phase(ph);
        s_part += dist;
        u_start = u_end;
      }
    }
    first = last;
    // Stop at an interior vertex: turn on the spot, then pause.
    const std::size_t vtx = run_end_vertices[r];
    if (vtx + 1 < n) {
      Phase ph;
      ph.dwell = true;
      ph.s0_m = run_end_s[r];
      ph.heading0_rad = std::atan2(dir[vtx - 1].y(), dir[vtx - 1].x()) + facing_offset(vtx - 1);
      // The facing turns by the path's turn, plus half a turn where backward walking starts or ends.
      double facing_turn = turn[vtx];
      if (path[vtx - 1].backwards != path[vtx].backwards) facing_turn = wrapAngle(facing_turn + kPi);
      ph.turn_rad = std::abs(facing_turn) > kPi - 1e-6 ? kPi : facing_turn;  // reversals turn left
      ph.turn_s = std::abs(ph.turn_rad) / params.max_yaw_rate_radps;
      ph.duration_s = ph.turn_s + path[vtx].pause_s;
      if (ph.duration_s > 0.0) add_phase(ph);
    }
  }
  w.duration_s_ = t;
  w.phase_t0_s_.reserve(w.phases_.size());
  for (const Phase& ph : w.phases_) w.phase_t0_s_.push_back(ph.t0_s);
  return w;
}

PersonState WalkingPerson::state(double t_s) const {
  PersonState out;
  out.t_s = t_s;
  Eigen::Vector2d p = start_W_m_;
  double heading = start_heading_rad_;  // facing
  double motion_heading = heading;      // direction of travel (speed 0 where it differs from the path's)
  double speed = 0.0;
  double stride = 0.0;
  if (!phases_.empty()) {
    const double t = std::clamp(t_s, 0.0, duration_s_);
    const auto it = std::upper_bound(phase_t0_s_.begin(), phase_t0_s_.end(), t);
    const std::size_t i = it == phase_t0_s_.begin() ? 0 : static_cast<std::size_t>(it - phase_t0_s_.begin()) - 1;
    const Phase& ph = phases_[i];
    const double tau = std::clamp(t - ph.t0_s, 0.0, ph.duration_s);
    double s = ph.s0_m;
    stride = ph.stride0_cycles;
    if (!ph.dwell) {
      speed = std::max(0.0, ph.v0_mps + ph.a_mps2 * tau);
      s += ph.v0_mps * tau + 0.5 * ph.a_mps2 * tau * tau;
      stride += (ph.backwards ? -1.0 : 1.0) * strideCycles(ph.v0_mps, ph.a_mps2, tau);
    }
    s = std::clamp(s, 0.0, length_m_);
    const auto pit = std::upper_bound(piece_s0_m_.begin(), piece_s0_m_.end(), s);
    const std::size_t j = pit == piece_s0_m_.begin() ? 0 : static_cast<std::size_t>(pit - piece_s0_m_.begin()) - 1;
    const Piece& piece = pieces_[j];
    const double sigma = std::clamp(s - piece.s0_m, 0.0, piece.length_m);
    if (piece.is_arc) {
      const double ang = piece.turn_sign * sigma / piece.radius_m;
      heading = piece.heading0_rad + ang;
      const double radial = heading - piece.turn_sign * 0.5 * kPi;  // centre -> point
      p = piece.centre_W_m + piece.radius_m * Eigen::Vector2d(std::cos(radial), std::sin(radial));
    } else {
      heading = piece.heading0_rad;
      p = piece.p0_W_m + sigma * piece.dir_W;
    }
    motion_heading = heading;
    if (ph.dwell) {
      heading = ph.heading0_rad + ph.turn_rad * (ph.turn_s > 0.0 ? smoothstep(tau / ph.turn_s) : 0.0);
    } else if (ph.backwards) {
      heading += kPi;
    }
  }
  heading = wrapAngle(heading);
  const double c = std::cos(heading), sn = std::sin(heading);
  out.p_W_m = {p.x(), p.y(), 0.0};
  out.speed_mps = speed;
  motion_heading = wrapAngle(motion_heading);  // == heading (same bits) unless walking backwards
  out.v_W_mps = {speed * std::cos(motion_heading), speed * std::sin(motion_heading), 0.0};
  out.heading_rad = heading;
  const std::array<Eigen::Vector3d, kNumKeypoints> kp = bodyKeypoints(speed, stride);
  for (std::size_t k = 0; k < kNumKeypoints; ++k) {
    const Eigen::Vector3d& q = kp[k];
    out.keypoints_W_m[k] = {p.x() + c * q.x() - sn * q.y(), p.y() + sn * q.x() + c * q.y(), q.z()};
  }
  return out;
}

}  // namespace aerotrack::hal::sim
