// Spatial-temporal trajectory optimisation in a flight corridor (paper Sect. V-C). Decision
// variables: the M - 1 intermediate waypoints q and the M piece durations T of a minimum-jerk spline
// (min_jerk_spline.hpp) whose start and end states are fixed. The cost, as the paper writes it,
//   J = J_S + J_F + J_D,
//   J_S = int |p'''|^2 dt                                            (jerk energy, closed form)
//   J_F = -kappa sum_{i=1}^{M-1} sum_{j=i}^{i+1} 1^T ln(b_j - A_j q_i)  (log barrier: q_i in C_i ∩ C_{i+1})
//   J_D = rho_t sum T_i
//       + rho_v sum_i l(|(q_{i+1} - q_{i-1}) / (T_{i+1} + T_i)|^2 - v_m^2)
//       + rho_a sum_i l(|((q_{i+1} - q_i) / T_{i+1} - (q_i - q_{i-1}) / T_i) / ((T_{i+1} + T_i) / 2)|^2 - a_m^2)
// with l(x) = max(x, 0)^3 and q_0, q_M the fixed start and end positions (paper index convention:
// piece i runs from q_{i-1} to q_i in T_i). The paper's terms constrain only the waypoints, so what
// lies between them is also penalised (J_C, issue 8): at K + 1 samples of every piece,
//   rho_c l(how far p leaves its box, per face) + rho_vs l(|v|^2 - v_m^2) + rho_as l(|a|^2 - a_m^2)
//   + rho_js l(|j|^2 - j_m^2),
// and, given the person's predicted torso (issue 21), rho_cv times the camera-view penalty of each sample
// (camera_view.hpp: the body's tilt must keep the torso in the 1-DOF gimbal camera's vertical field of view).
// Durations stay positive through T = softplus(tau) = ln(1 + e^tau), a smooth change of variable; the
// vector L-BFGS sees is x = [q (column-major); tau]. Gradients of every term are analytic: with respect
// to the coefficients and the explicit T, then through the coefficient map by its adjoint (O(M)).
// Minimised by LBFGS++ (Debian liblbfgspp-dev) with a backtracking Wolfe line search; points outside
// the barrier's domain cost +inf, so the line search steps back, and the best finite point seen is kept.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string_view>

#include <Eigen/Core>

#include "aerotrack/planning/corridor.hpp"
#include "aerotrack/planning/min_jerk_spline.hpp"
#include "aerotrack/planning/polynomial_trajectory.hpp"
#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/field_table.hpp"

namespace aerotrack::planning {

struct TrajectoryOptimizerParams {
  double max_velocity_mps = 3.0;              ///< v_m (norm); > 0.
  double max_acceleration_mps2 = 4.0;         ///< a_m (norm); > 0.
  double max_jerk_mps3 = 30.0;                ///< j_m (norm), sampled penalty only; > 0.
  double barrier_weight = 0.01;               ///< kappa; > 0.
  double time_weight = 20.0;                  ///< rho_t, cost per second; >= 0.
  double waypoint_velocity_weight = 1e3;      ///< rho_v; >= 0.
  double waypoint_acceleration_weight = 1e3;  ///< rho_a; >= 0.
  double corridor_weight = 1e6;               ///< rho_c on samples outside their box (per m^3); >= 0.
  double corridor_margin_m = 0.0;             ///< Samples are pushed this far inside their box; >= 0.
  /// A second margin, corridor_margin_m plus this times the sample's speed (issue 21 item 5), inside its own
  /// box or a neighbouring piece's: the faster the drone, the deeper in free space, so the tracking error that
  /// grows with speed eats into this margin, not into the clearance; a narrow gap is flown slower, not
  /// closer. Seconds; >= 0 (0: none).
  double corridor_margin_per_speed_s = 0.0;
  double sample_velocity_weight = 1e3;      ///< rho_vs; >= 0.
  double sample_acceleration_weight = 1e3;  ///< rho_as; >= 0.
  double sample_jerk_weight = 1.0;          ///< rho_js; >= 0.
  /// The person in the gimbal camera's vertical field of view (camera_view.hpp, issue 21): rho_cv on every
  /// sample whose body tilt would put the person's torso (TrajectoryProblem::person_torso_W_m) outside
  /// +-(camera_half_vfov_rad - camera_view_margin_rad) of the optical axis; 0: off.
  double camera_view_weight = 0.0;
  double camera_half_vfov_rad = 0.6178;   ///< atan(240 / 337.2): 640 x 480 px at 87 deg horizontal; in (0, pi/2).
  double camera_view_margin_rad = 0.05;   ///< Kept inside the edge (the torso's keypoints, the tracking error); >= 0.
  int samples_per_piece = 12;             ///< K; >= 1.
  int max_iterations = 80;                ///< L-BFGS iterations; >= 1.
  double relative_cost_tolerance = 1e-4;  ///< Stop when the cost changed less than this over 3 iterations; > 0.
  double gradient_tolerance = 1e-5;       ///< Stop when |grad| <= this * max(1, |x|); > 0.
  int memory = 8;                         ///< L-BFGS history; >= 1.
  int max_pieces = 32;                    ///< Scratch sized for this many pieces (more allocates); >= 1.
};

/// The `optimizer:` config section: every field above but the three limits by its name, all required (the
/// limits are derived from the check's, the vehicle's: TrackingPlannerParams::optimizer_limit_fraction), with the one
/// range per field that parsing, validate() and printing share (rt/field_table.hpp; the ranges are in the .cpp).
const rt::FieldTable<TrajectoryOptimizerParams>& trajectoryOptimizerFields();
/// Every field in its range; the error names the key.
rt::Status validate(const TrajectoryOptimizerParams& params);
/// trajectoryOptimizerFields().parse; throws rt::ConfigError naming the key.
TrajectoryOptimizerParams parseTrajectoryOptimizerParams(const rt::ConfigNode& node);

/// Which cost terms evaluate() includes (bit mask; for the gradient tests).
enum CostTerm : std::uint32_t {
  kJerkEnergy = 1U << 0U,            ///< J_S
  kBarrier = 1U << 1U,               ///< J_F
  kTime = 1U << 2U,                  ///< rho_t sum T
  kWaypointVelocity = 1U << 3U,      ///< rho_v term of J_D
  kWaypointAcceleration = 1U << 4U,  ///< rho_a term of J_D
  kCorridorSamples = 1U << 5U,       ///< rho_c
  kVelocitySamples = 1U << 6U,       ///< rho_vs
  kAccelerationSamples = 1U << 7U,   ///< rho_as
  kJerkSamples = 1U << 8U,           ///< rho_js
  kCameraViewSamples = 1U << 9U,     ///< rho_cv
  kAllTerms = (1U << 10U) - 1U,
};

/// One problem: fixed boundary states, the corridor (M boxes) and the initial waypoints (M - 1, each
/// strictly inside its two boxes) and durations (M, > 0).
struct TrajectoryProblem {
  StatePva start = StatePva::Zero();  ///< Columns p, v, a at the start.
  StatePva end = StatePva::Zero();    ///< Columns p, v, a at the end.
  std::span<const CorridorBox> boxes;
  std::span<const Eigen::Vector3d> initial_waypoints_W_m;
  std::span<const double> initial_durations_s;
  /// The time weight of this problem is params.time_weight times this (the planner raises it for a fast
  /// person, issue 21); > 0.
  double time_weight_scale = 1.0;
  /// The person's torso centre (W), sampled every person_sample_dt_s from the trajectory's start, for the
  /// camera-view term (held at the last sample beyond it; linear between samples). Empty: no term. The
  /// data must outlive optimize() (and, for tests, every evaluate() after setProblem()).
  std::span<const Eigen::Vector3d> person_torso_W_m = {};
  double person_sample_dt_s = 0.0;   ///< > 0 when person_torso_W_m is not empty.
  double person_torso_half_m = 0.0;  ///< Half the shoulders-to-hips length; >= 0.
};

enum class OptimizerStatus : std::uint8_t {
  kConverged,      ///< A tolerance was met.
  kMaxIterations,  ///< Stopped by the iteration budget; the best point is used.
  kLineSearch,     ///< The line search gave up; the best point so far is used.
};
std::string_view toString(OptimizerStatus status);

struct OptimizerResult {
  OptimizerStatus status = OptimizerStatus::kConverged;
  int iterations = 0;
  int evaluations = 0;
  double initial_cost = 0.0;
  double cost = 0.0;
};

/// Not thread-safe (one per planning thread). Scratch memory is sized in create() for max_pieces and
/// reused: a warm optimize() with at most max_pieces pieces and the same piece count as the previous
/// call allocates nothing (L-BFGS resizes its history when the count changes).
class TrajectoryOptimizer {
 public:
  static rt::Expected<TrajectoryOptimizer> create(const TrajectoryOptimizerParams& params);
  TrajectoryOptimizer(TrajectoryOptimizer&&) noexcept;
  TrajectoryOptimizer& operator=(TrajectoryOptimizer&&) noexcept;
  ~TrajectoryOptimizer();

  const TrajectoryOptimizerParams& params() const { return params_; }

  /// Minimises J and writes the spline into `out`. Errors: inconsistent sizes, a non-finite input, a
  /// duration not positive, an initial waypoint not strictly inside both of its boxes.
  rt::Expected<OptimizerResult> optimize(const TrajectoryProblem& problem, PolynomialTrajectory& out);

  // --- For tests and benchmarks. ---
  /// Loads a problem without optimising (same checks as optimize()); initialVariables() is then x0.
  rt::Status setProblem(const TrajectoryProblem& problem);
  const Eigen::VectorXd& initialVariables() const { return x0_; }
  /// J(x) restricted to `terms`, and its gradient (same size as x). +inf outside the barrier's domain.
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& gradient, std::uint32_t terms = kAllTerms);
  /// The spline of the last evaluate().
  const MinJerkSpline& spline() const { return spline_; }

  /// T = softplus(tau) and its inverse.
  static double durationFromTau(double tau);
  static double tauFromDuration(double duration_s);

 private:
  struct Solver;
  explicit TrajectoryOptimizer(const TrajectoryOptimizerParams& params);
  void addWaypointTerms(std::uint32_t terms, double& cost);
  /// The speed-dependent corridor margin of one sample of `piece` (see the .cpp); true when active.
  bool addSpeedMarginTerm(Eigen::Index piece, const Eigen::Vector3d& p, const Eigen::Vector3d& v, double& cost,
                          Eigen::Vector3d& gp, Eigen::Vector3d& gv) const;
  void addSampleTerms(std::uint32_t terms, double& cost);
  /// The person's torso centre at time s_s after the start, and its velocity (linear interpolation).
  void personAt(double s_s, Eigen::Vector3d& p_W_m, Eigen::Vector3d& v_W_mps) const;

  TrajectoryOptimizerParams params_;
  std::unique_ptr<Solver> solver_;
  MinJerkSpline spline_;
  Eigen::Index pieces_ = 0;
  StatePva start_ = StatePva::Zero();
  StatePva end_ = StatePva::Zero();
  std::vector<CorridorBox> boxes_;
  std::span<const Eigen::Vector3d> person_torso_W_m_;  // the problem's (camera-view term)
  double person_sample_dt_s_ = 0.0;
  double person_torso_half_m_ = 0.0;
  Eigen::VectorXd later_time_grad_;  // per piece: d cost / d (the piece's start time), through the person
  Eigen::VectorXd x0_;
  Eigen::Matrix3Xd q_;       // waypoints of the current x
  Eigen::VectorXd t_;        // durations of the current x
  Eigen::Matrix3Xd grad_q_;  // dJ/dq
  Eigen::VectorXd grad_t_;   // dJ/dT
  RowMatrixX3d grad_c_;      // dJ/dc
  Eigen::VectorXd best_x_;   // best finite point seen during optimize()
  Eigen::VectorXd scratch_grad_;
  double best_cost_ = 0.0;
  double time_weight_ = 0.0;
  int evaluations_ = 0;
};

}  // namespace aerotrack::planning
