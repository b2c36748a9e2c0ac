// Spatial-temporal trajectory optimisation: see trajectory_optimizer.hpp.
#include "aerotrack/planning/trajectory_optimizer.hpp"

#include <LBFGS.h>

#include "aerotrack/planning/camera_view.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>
#include <string>

namespace aerotrack::planning {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kMaxRestarts = 8;

// l(x) = max(x, 0)^3 and its derivative.
double penalty(double x) {
  return x > 0.0 ? x * x * x : 0.0;
}
double penaltyDerivative(double x) {
  return x > 0.0 ? 3.0 * x * x : 0.0;
}

// Adds rho l(|w|^2 - limit^2) to cost; returns dcost/dw.
Eigen::Vector3d addNormPenalty(const Eigen::Vector3d& w, double limit, double rho, double& cost) {
  const double x = w.squaredNorm() - limit * limit;
  if (x <= 0.0) return Eigen::Vector3d::Zero();
  cost += rho * penalty(x);
  return rho * penaltyDerivative(x) * 2.0 * w;
}

// Weak Wolfe line search by bisection and expansion (Lewis and Overton, "Nonsmooth optimization via
// quasi-Newton methods", Math. Prog. 2013), plugged into LBFGS++ as its LineSearch policy. Unlike
// LBFGS++'s backtracking, it brackets the step: a trial point outside the barrier's domain (cost +inf)
// or above the Armijo line shrinks the bracket from above, one that is too flat (curvature condition
// unmet) from below, so it never oscillates between the two. The accepted step satisfies weak Wolfe,
// which keeps s^T y > 0 for the L-BFGS update.
template <typename Scalar>
class LineSearchLewisOverton {
 public:
  using Vector = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;

  template <typename Objective>
  // NOLINTNEXTLINE(readability-identifier-naming): the name is LBFGS++'s interface
  static void LineSearch(Objective& f, Scalar& fx, Vector& x, Vector& grad, Scalar& step, const Vector& drt,
                         const Vector& xp, const LBFGSpp::LBFGSParam<Scalar>& param) {
    const Scalar fx_init = fx;
    const Scalar dg_init = grad.dot(drt);
    if (!(dg_init < 0)) throw std::logic_error("not a descent direction");
    Scalar lo = 0;
    Scalar hi = std::numeric_limits<Scalar>::infinity();
    for (int iter = 0; iter < param.max_linesearch; ++iter) {
      x.noalias() = xp + step * drt;
      fx = f(x, grad);
      if (!(fx <= fx_init + param.ftol * step * dg_init)) {
        hi = step;  // too long (or +inf / NaN)
      } else if (grad.dot(drt) < param.wolfe * dg_init) {
        lo = step;  // too short
      } else {
        return;
      }
      step = std::isinf(hi) ? 2 * step : (lo + hi) / 2;
      if (step < param.min_step) break;
    }
    throw std::runtime_error("line search failed");
  }
};

}  // namespace

struct TrajectoryOptimizer::Solver {
  LBFGSpp::LBFGSParam<double> param;
  std::unique_ptr<LBFGSpp::LBFGSSolver<double, LineSearchLewisOverton>> lbfgs;
  Eigen::VectorXd x;
};

std::string_view toString(OptimizerStatus status) {
  switch (status) {
    case OptimizerStatus::kConverged:
      return "converged";
    case OptimizerStatus::kMaxIterations:
      return "max_iterations";
    case OptimizerStatus::kLineSearch:
      return "line_search";
  }
  return "unknown";
}

const rt::FieldTable<TrajectoryOptimizerParams>& trajectoryOptimizerFields() {
  using P = TrajectoryOptimizerParams;
  using rt::Range;
  static const rt::FieldTable<P> kTable({
      rt::number("barrier_weight", &P::barrier_weight, Range::closed(1e-9, 1e6)),
      rt::number("time_weight", &P::time_weight, Range::closed(0.0, 1e6)),
      rt::number("waypoint_velocity_weight", &P::waypoint_velocity_weight, Range::closed(0.0, 1e9)),
      rt::number("waypoint_acceleration_weight", &P::waypoint_acceleration_weight, Range::closed(0.0, 1e9)),
      rt::number("corridor_weight", &P::corridor_weight, Range::closed(0.0, 1e12)),
      rt::number("corridor_margin_m", &P::corridor_margin_m, Range::closed(0.0, 1.0)),
      rt::number("corridor_margin_per_speed_s", &P::corridor_margin_per_speed_s, Range::closed(0.0, 1.0)),
      rt::number("sample_velocity_weight", &P::sample_velocity_weight, Range::closed(0.0, 1e9)),
      rt::number("sample_acceleration_weight", &P::sample_acceleration_weight, Range::closed(0.0, 1e9)),
      rt::number("sample_jerk_weight", &P::sample_jerk_weight, Range::closed(0.0, 1e9)),
      rt::number("camera_view_weight", &P::camera_view_weight, Range::closed(0.0, 1e12)),
      rt::number("camera_half_vfov_rad", &P::camera_half_vfov_rad, Range::open(0.0, 1.5707)),
      rt::number("camera_view_margin_rad", &P::camera_view_margin_rad, Range::closed(0.0, 1.0)),
      rt::integer("samples_per_piece", &P::samples_per_piece, 1, 256),
      rt::integer("max_iterations", &P::max_iterations, 1, 100'000),
      rt::number("relative_cost_tolerance", &P::relative_cost_tolerance, Range::closed(1e-12, 1.0)),
      rt::number("gradient_tolerance", &P::gradient_tolerance, Range::closed(1e-12, 1.0)),
      rt::integer("memory", &P::memory, 1, 64),
      rt::integer("max_pieces", &P::max_pieces, 1, 100'000),
  });
  return kTable;
}

rt::Status validate(const TrajectoryOptimizerParams& params) {
  return trajectoryOptimizerFields().validate(params);
}

TrajectoryOptimizerParams parseTrajectoryOptimizerParams(const rt::ConfigNode& node) {
  return trajectoryOptimizerFields().parse(node);
}

double TrajectoryOptimizer::durationFromTau(double tau) {
  // softplus, written to stay accurate for large |tau|
  return tau > 0.0 ? tau + std::log1p(std::exp(-tau)) : std::log1p(std::exp(tau));
}

double TrajectoryOptimizer::tauFromDuration(double duration_s) {
  // inverse softplus: ln(e^T - 1) = T + ln(1 - e^-T)
  return duration_s + std::log(-std::expm1(-duration_s));
}

TrajectoryOptimizer::TrajectoryOptimizer(const TrajectoryOptimizerParams& params)
    : params_(params), solver_(std::make_unique<Solver>()) {
  solver_->param.m = params.memory;
  solver_->param.epsilon = params.gradient_tolerance;
  solver_->param.epsilon_rel = params.gradient_tolerance;
  solver_->param.past = 3;
  solver_->param.delta = params.relative_cost_tolerance;
  solver_->param.max_iterations = params.max_iterations;
  solver_->param.max_linesearch = 40;
  solver_->param.linesearch = LBFGSpp::LBFGS_LINESEARCH_BACKTRACKING_WOLFE;
  solver_->lbfgs = std::make_unique<LBFGSpp::LBFGSSolver<double, LineSearchLewisOverton>>(solver_->param);
  const int m = params.max_pieces;
  boxes_.reserve(static_cast<std::size_t>(m));
  spline_.reset(StatePva::Zero(), StatePva::Zero(), m);
  const int n = 4 * m - 3;
  x0_.resize(n);
  best_x_.resize(n);
  scratch_grad_.resize(n);
  solver_->x.resize(n);
  q_.resize(3, m - 1);
  t_.resize(m);
  grad_q_.resize(3, m - 1);
  grad_t_.resize(m);
  grad_c_.resize(Eigen::Index{6} * m, 3);
  later_time_grad_.resize(m);
}

TrajectoryOptimizer::TrajectoryOptimizer(TrajectoryOptimizer&&) noexcept = default;
TrajectoryOptimizer& TrajectoryOptimizer::operator=(TrajectoryOptimizer&&) noexcept = default;
TrajectoryOptimizer::~TrajectoryOptimizer() = default;

rt::Expected<TrajectoryOptimizer> TrajectoryOptimizer::create(const TrajectoryOptimizerParams& params) {
  if (const rt::Status s = validate(params); !s) return rt::Error{"trajectory optimizer: " + s.error().message};
  // The limits are not config keys (the planner derives them from the check's, issue 21): checked here.
  if (!(params.max_velocity_mps > 0.0) || !(params.max_acceleration_mps2 > 0.0) || !(params.max_jerk_mps3 > 0.0))
    return rt::Error{"trajectory optimizer: the velocity, acceleration and jerk limits must be > 0"};
  if (params.camera_view_weight > 0.0 && !(params.camera_view_margin_rad < params.camera_half_vfov_rad))
    return rt::Error{"trajectory optimizer: camera_view_margin_rad must be below camera_half_vfov_rad"};
  return TrajectoryOptimizer(params);
}

rt::Status TrajectoryOptimizer::setProblem(const TrajectoryProblem& problem) {
  const auto m = static_cast<Eigen::Index>(problem.boxes.size());
  if (m < 1) return rt::Error{"trajectory optimizer: no corridor boxes"};
  if (static_cast<int>(problem.initial_durations_s.size()) != m ||
      static_cast<int>(problem.initial_waypoints_W_m.size()) != m - 1)
    return rt::Error{"trajectory optimizer: " + std::to_string(m) + " boxes need " + std::to_string(m - 1) +
                     " waypoints and " + std::to_string(m) + " durations"};
  if (!(problem.time_weight_scale > 0.0) || !std::isfinite(problem.time_weight_scale))
    return rt::Error{"trajectory optimizer: the time weight's scale must be finite and > 0"};
  if (!problem.start.allFinite() || !problem.end.allFinite())
    return rt::Error{"trajectory optimizer: non-finite boundary state"};
  if (!problem.person_torso_W_m.empty()) {
    if (!(problem.person_sample_dt_s > 0.0) || !std::isfinite(problem.person_sample_dt_s) ||
        !(problem.person_torso_half_m >= 0.0) || !std::isfinite(problem.person_torso_half_m))
      return rt::Error{
          "trajectory optimizer: the person's samples need a finite step > 0 and a torso half length >= 0"};
    for (const Eigen::Vector3d& p : problem.person_torso_W_m) {
      if (!p.allFinite()) return rt::Error{"trajectory optimizer: a non-finite person sample"};
    }
  }
  for (const double t : problem.initial_durations_s) {
    if (!std::isfinite(t) || t <= 0.0) return rt::Error{"trajectory optimizer: a duration is not positive"};
  }
  for (Eigen::Index i = 0; i + 1 < m; ++i) {
    const Eigen::Vector3d& q = problem.initial_waypoints_W_m[static_cast<std::size_t>(i)];
    const CorridorBox& a = problem.boxes[static_cast<std::size_t>(i)];
    const CorridorBox& b = problem.boxes[static_cast<std::size_t>(i) + 1];
    const bool inside = q.allFinite() && (q.array() > a.lo_W_m.array()).all() && (q.array() < a.hi_W_m.array()).all() &&
                        (q.array() > b.lo_W_m.array()).all() && (q.array() < b.hi_W_m.array()).all();
    if (!inside)
      return rt::Error{"trajectory optimizer: waypoint " + std::to_string(i) +
                       " is not strictly inside the intersection of its two boxes"};
  }
  pieces_ = m;
  start_ = problem.start;
  end_ = problem.end;
  time_weight_ = params_.time_weight * problem.time_weight_scale;
  boxes_.assign(problem.boxes.begin(), problem.boxes.end());
  person_torso_W_m_ = problem.person_torso_W_m;
  person_sample_dt_s_ = problem.person_sample_dt_s;
  person_torso_half_m_ = problem.person_torso_half_m;
  spline_.reset(start_, end_, static_cast<int>(m));
  const Eigen::Index n = 4 * m - 3;
  x0_.resize(n);
  for (Eigen::Index i = 0; i + 1 < m; ++i)
    x0_.segment<3>(3 * i) = problem.initial_waypoints_W_m[static_cast<std::size_t>(i)];
  for (Eigen::Index i = 0; i < m; ++i)
    x0_(3 * (m - 1) + i) = tauFromDuration(problem.initial_durations_s[static_cast<std::size_t>(i)]);
  q_.resize(3, m - 1);
  t_.resize(m);
  grad_q_.resize(3, m - 1);
  grad_t_.resize(m);
  grad_c_.resize(6 * m, 3);
  later_time_grad_.resize(m);
  return rt::ok();
}

double TrajectoryOptimizer::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& gradient, std::uint32_t terms) {
  const Eigen::Index m = pieces_;
  ++evaluations_;
  gradient.setZero(x.size());
  for (Eigen::Index i = 0; i + 1 < m; ++i) q_.col(i) = x.segment<3>(3 * i);
  for (Eigen::Index i = 0; i < m; ++i) t_(i) = durationFromTau(x(3 * (m - 1) + i));
  if (!x.allFinite() || !spline_.generate(q_, t_)) return kInf;

  double cost = 0.0;
  grad_c_.setZero();
  grad_t_.setZero();
  grad_q_.setZero();
  if ((terms & kJerkEnergy) != 0U) {
    cost += spline_.jerkEnergy();
    spline_.addJerkEnergyGradient(grad_c_, grad_t_);
  }
  if ((terms & kTime) != 0U) {
    cost += time_weight_ * t_.sum();
    grad_t_.array() += time_weight_;
  }
  addSampleTerms(terms, cost);
  // grad_q_ collects the direct waypoint terms after the chain rule has written the mapped ones.
  spline_.propagateGradient(grad_c_, grad_t_, grad_q_);
  addWaypointTerms(terms, cost);
  if (!std::isfinite(cost)) return kInf;

  for (Eigen::Index i = 0; i + 1 < m; ++i) gradient.segment<3>(3 * i) = grad_q_.col(i);
  for (Eigen::Index i = 0; i < m; ++i) {
    const double tau = x(3 * (m - 1) + i);
    const double dT_dtau = 1.0 / (1.0 + std::exp(-tau));  // softplus' = logistic
    gradient(3 * (m - 1) + i) = grad_t_(i) * dT_dtau;
  }
  return cost;
}

void TrajectoryOptimizer::addWaypointTerms(std::uint32_t terms, double& cost) {
  const Eigen::Index m = pieces_;
  // Q(k), k = 0..M: the fixed start, the waypoints, the fixed end (the paper's q_{w_0} .. q_{w_M}).
  auto point = [&](Eigen::Index k) -> Eigen::Vector3d {
    if (k == 0) return start_.col(0);
    if (k == m) return end_.col(0);
    return q_.col(k - 1);
  };
  auto addPointGrad = [&](Eigen::Index k, const Eigen::Vector3d& g) {
    if (k > 0 && k < m) grad_q_.col(k - 1) += g;
  };
  if ((terms & kBarrier) != 0U) {
    const double kappa = params_.barrier_weight;
    for (Eigen::Index i = 0; i + 1 < m; ++i) {
      const Eigen::Vector3d q = q_.col(i);
      for (Eigen::Index j = i; j <= i + 1; ++j) {
        const CorridorBox& box = boxes_[static_cast<std::size_t>(j)];
        const Eigen::Array3d to_hi = (box.hi_W_m - q).array();
        const Eigen::Array3d to_lo = (q - box.lo_W_m).array();
        if ((to_hi <= 0.0).any() || (to_lo <= 0.0).any()) {
          cost = kInf;
          return;
        }
        // sum of six logs as the log of their product (one log instead of six; each factor is a
        // distance of metres, so the product cannot overflow)
        cost -= kappa * std::log(to_hi.prod() * to_lo.prod());
        // d/dq [-ln(hi - q) - ln(q - lo)] = 1/(hi - q) - 1/(q - lo)
        grad_q_.col(i) += (kappa * (to_hi.inverse() - to_lo.inverse())).matrix();
      }
    }
  }
  for (Eigen::Index k = 1; k < m; ++k) {
    const double t_in = t_(k - 1);  // piece into Q(k): the paper's T_i
    const double t_out = t_(k);     // piece out of Q(k): T_{i+1}
    const double sum = t_in + t_out;
    if ((terms & kWaypointVelocity) != 0U && params_.waypoint_velocity_weight > 0.0) {
      const Eigen::Vector3d u = point(k + 1) - point(k - 1);
      const Eigen::Vector3d v = u / sum;
      const Eigen::Vector3d g = addNormPenalty(v, params_.max_velocity_mps, params_.waypoint_velocity_weight, cost);
      addPointGrad(k + 1, g / sum);
      addPointGrad(k - 1, -g / sum);
      const double dT = g.dot(-v / sum);
      grad_t_(k - 1) += dT;
      grad_t_(k) += dT;
    }
    if ((terms & kWaypointAcceleration) != 0U && params_.waypoint_acceleration_weight > 0.0) {
      const Eigen::Vector3d d1 = point(k + 1) - point(k);
      const Eigen::Vector3d d0 = point(k) - point(k - 1);
      const double scale = 2.0 / sum;
      const Eigen::Vector3d a = scale * (d1 / t_out - d0 / t_in);
      const Eigen::Vector3d g =
          addNormPenalty(a, params_.max_acceleration_mps2, params_.waypoint_acceleration_weight, cost);
      addPointGrad(k + 1, g * (scale / t_out));
      addPointGrad(k, g * (-scale / t_out - scale / t_in));
      addPointGrad(k - 1, g * (scale / t_in));
      grad_t_(k) += g.dot(-scale * d1 / (t_out * t_out) - a / sum);
      grad_t_(k - 1) += g.dot(scale * d0 / (t_in * t_in) - a / sum);
    }
  }
}

// The speed-dependent margin (issue 21 item 5): the sample should lie corridor_margin_m + corridor_margin_per_speed_s
// * |v| inside a box -- its own piece's or a neighbour's, whichever it is deepest in (every box is free space,
// so depth in any of them is clearance; against its own box alone, every junction, where the path leaves one
// box for the next, would count as a wall and the drone would slow down at each). The penalty is that box's
// l(.) sum; each violated face also pushes on v along v / |v| (d|v|/dv), so the optimiser may slow down as well
// as move. True when active.
bool TrajectoryOptimizer::addSpeedMarginTerm(Eigen::Index piece, const Eigen::Vector3d& p, const Eigen::Vector3d& v,
                                             double& cost, Eigen::Vector3d& gp, Eigen::Vector3d& gv) const {
  const double speed = v.norm();
  const double margin_m = params_.corridor_margin_m + params_.corridor_margin_per_speed_s * speed;
  double best_penalty = kInf;
  Eigen::Vector3d best_gp = Eigen::Vector3d::Zero();
  double best_push = 0.0;
  for (Eigen::Index b = std::max<Eigen::Index>(0, piece - 1); b <= std::min(pieces_ - 1, piece + 1); ++b) {
    const CorridorBox& box = boxes_[static_cast<std::size_t>(b)];
    double box_penalty = 0.0;
    double push = 0.0;
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (int axis = 0; axis < 3; ++axis) {
      const double above = p(axis) - box.hi_W_m(axis) + margin_m;
      const double below = box.lo_W_m(axis) - p(axis) + margin_m;
      if (above > 0.0) {  // both faces of a box narrower than twice the margin may count
        box_penalty += penalty(above);
        g(axis) += penaltyDerivative(above);
        push += penaltyDerivative(above);
      }
      if (below > 0.0) {
        box_penalty += penalty(below);
        g(axis) -= penaltyDerivative(below);
        push += penaltyDerivative(below);
      }
    }
    if (box_penalty < best_penalty) {
      best_penalty = box_penalty;
      best_gp = g;
      best_push = push;
    }
  }
  if (!(best_penalty > 0.0)) return false;
  const double w = params_.corridor_weight;
  cost += w * best_penalty;
  gp += w * best_gp;
  if (speed > 0.0) gv += (w * best_push * params_.corridor_margin_per_speed_s / speed) * v;
  return true;
}

void TrajectoryOptimizer::addSampleTerms(std::uint32_t terms, double& cost) {
  const bool corridor = (terms & kCorridorSamples) != 0U && params_.corridor_weight > 0.0;
  const bool velocity = (terms & kVelocitySamples) != 0U && params_.sample_velocity_weight > 0.0;
  const bool acceleration = (terms & kAccelerationSamples) != 0U && params_.sample_acceleration_weight > 0.0;
  const bool jerk = (terms & kJerkSamples) != 0U && params_.sample_jerk_weight > 0.0;
  const bool view =
      (terms & kCameraViewSamples) != 0U && params_.camera_view_weight > 0.0 && !person_torso_W_m_.empty();
  if (!corridor && !velocity && !acceleration && !jerk && !view) return;
  const double view_sin_limit = std::sin(params_.camera_half_vfov_rad - params_.camera_view_margin_rad);
  later_time_grad_.head(pieces_).setZero();
  double piece_start_s = 0.0;  // the camera-view term's person is at absolute time piece_start_s + t
  const int k_samples = params_.samples_per_piece;
  const double v_limit2 = params_.max_velocity_mps * params_.max_velocity_mps;
  const double a_limit2 = params_.max_acceleration_mps2 * params_.max_acceleration_mps2;
  const double j_limit2 = params_.max_jerk_mps3 * params_.max_jerk_mps3;
  const double margin_per_speed = params_.corridor_margin_per_speed_s;
  const RowMatrixX3d& coeffs = spline_.coefficients();
  for (Eigen::Index i = 0; i < pieces_; ++i) {
    // Coefficient rows c0..c5 of piece i (x, y, z each).
    const Eigen::Vector3d c0 = coeffs.row(6 * i).transpose();
    const Eigen::Vector3d c1 = coeffs.row(6 * i + 1).transpose();
    const Eigen::Vector3d c2 = coeffs.row(6 * i + 2).transpose();
    const Eigen::Vector3d c3 = coeffs.row(6 * i + 3).transpose();
    const Eigen::Vector3d c4 = coeffs.row(6 * i + 4).transpose();
    const Eigen::Vector3d c5 = coeffs.row(6 * i + 5).transpose();
    // Scaled coefficients of the derivatives, once per piece.
    const Eigen::Vector3d v2 = 2.0 * c2, v3 = 3.0 * c3, v4 = 4.0 * c4, v5 = 5.0 * c5;
    const Eigen::Vector3d a3 = 6.0 * c3, a4 = 12.0 * c4, a5 = 20.0 * c5;
    const Eigen::Vector3d j4 = 24.0 * c4, j5 = 60.0 * c5;
    const CorridorBox& box = boxes_[static_cast<std::size_t>(i)];
    const Eigen::Array3d lo = box.lo_W_m.array() + params_.corridor_margin_m;
    const Eigen::Array3d hi = box.hi_W_m.array() - params_.corridor_margin_m;
    // Piece i's first sample is piece i-1's last (continuity): each junction is counted once.
    for (int j = (i == 0 ? 0 : 1); j <= k_samples; ++j) {
      const double fraction = static_cast<double>(j) / k_samples;
      const double t = fraction * t_(i);
      // Horner's rule for p and its first three derivatives (the hot loop of the cost).
      const Eigen::Vector3d p = ((((c5 * t + c4) * t + c3) * t + c2) * t + c1) * t + c0;
      const Eigen::Vector3d v = (((v5 * t + v4) * t + v3) * t + v2) * t + c1;
      const Eigen::Vector3d a = ((a5 * t + a4) * t + a3) * t + v2;
      const Eigen::Vector3d jr = (j5 * t + j4) * t + a3;
      Eigen::Vector3d gp = Eigen::Vector3d::Zero();
      Eigen::Vector3d gv = Eigen::Vector3d::Zero();
      Eigen::Vector3d ga = Eigen::Vector3d::Zero();
      Eigen::Vector3d gj = Eigen::Vector3d::Zero();
      bool active = false;
      if (corridor) {
        for (int axis = 0; axis < 3; ++axis) {
          const double above = p(axis) - hi(axis);
          const double below = lo(axis) - p(axis);
          if (above > 0.0) {
            cost += params_.corridor_weight * penalty(above);
            gp(axis) += params_.corridor_weight * penaltyDerivative(above);
            active = true;
          } else if (below > 0.0) {
            cost += params_.corridor_weight * penalty(below);
            gp(axis) -= params_.corridor_weight * penaltyDerivative(below);
            active = true;
          }
        }
        if (margin_per_speed > 0.0) active |= addSpeedMarginTerm(i, p, v, cost, gp, gv);
      }
      if (velocity && v.squaredNorm() > v_limit2) {
        gv += addNormPenalty(v, params_.max_velocity_mps, params_.sample_velocity_weight, cost);
        active = true;
      }
      if (acceleration && a.squaredNorm() > a_limit2) {
        ga = addNormPenalty(a, params_.max_acceleration_mps2, params_.sample_acceleration_weight, cost);
        active = true;
      }
      if (jerk && jr.squaredNorm() > j_limit2) {
        gj = addNormPenalty(jr, params_.max_jerk_mps3, params_.sample_jerk_weight, cost);
        active = true;
      }
      double person_time_grad = 0.0;  // d cost / d (the sample's absolute time), through the person's motion
      if (view) {
        Eigen::Vector3d person_W_m;
        Eigen::Vector3d person_v_W_mps;
        personAt(piece_start_s + t, person_W_m, person_v_W_mps);
        CameraViewGradient g;
        if (addCameraViewTerm(p, a, person_W_m, person_torso_half_m_, view_sin_limit, params_.camera_view_weight, cost,
                              g)) {
          gp += g.p;
          ga += g.a;
          person_time_grad = g.person.dot(person_v_W_mps);
          later_time_grad_(i) += person_time_grad;  // the sample's time also moves with every earlier T_k
          active = true;
        }
      }
      if (!active) continue;
      const double t2 = t * t;
      const double t3 = t2 * t;
      const double t4 = t3 * t;
      auto rows = grad_c_.middleRows<6>(6 * i);
      // Only the active terms' outer products (usually one per sample).
      if (!gp.isZero(0.0)) rows += Eigen::Matrix<double, 6, 1>{1.0, t, t2, t3, t4, t4 * t} * gp.transpose();
      if (!gv.isZero(0.0))
        rows += Eigen::Matrix<double, 6, 1>{0.0, 1.0, 2.0 * t, 3.0 * t2, 4.0 * t3, 5.0 * t4} * gv.transpose();
      if (!ga.isZero(0.0))
        rows += Eigen::Matrix<double, 6, 1>{0.0, 0.0, 2.0, 6.0 * t, 12.0 * t2, 20.0 * t3} * ga.transpose();
      if (!gj.isZero(0.0))
        rows += Eigen::Matrix<double, 6, 1>{0.0, 0.0, 0.0, 6.0, 24.0 * t, 60.0 * t2} * gj.transpose();
      // The sample sits at t = fraction * T_i, so it moves with T_i: d/dT_i = fraction * (g . derivative).
      const Eigen::Vector3d snap = j4 + (2.0 * t) * j5;
      grad_t_(i) += fraction * (gp.dot(v) + gv.dot(a) + ga.dot(jr) + gj.dot(snap) + person_time_grad);
    }
    piece_start_s += t_(i);
  }
  // A sample of piece i sits at absolute time sum_{k<i} T_k + fraction T_i: d/dT_k (k < i) sums the later
  // pieces' person terms.
  double later = 0.0;
  for (Eigen::Index i = pieces_ - 1; i >= 1; --i) {
    later += later_time_grad_(i);
    grad_t_(i - 1) += later;
  }
}

void TrajectoryOptimizer::personAt(double s_s, Eigen::Vector3d& p_W_m, Eigen::Vector3d& v_W_mps) const {
  const std::size_t n = person_torso_W_m_.size();
  const double k_f = std::max(0.0, s_s / person_sample_dt_s_);
  if (n == 1 || k_f >= static_cast<double>(n - 1)) {  // held beyond the last sample
    p_W_m = person_torso_W_m_[n - 1];
    v_W_mps.setZero();
    return;
  }
  const auto k = static_cast<std::size_t>(k_f);
  const double frac = k_f - static_cast<double>(k);
  p_W_m = (1.0 - frac) * person_torso_W_m_[k] + frac * person_torso_W_m_[k + 1];
  v_W_mps = (person_torso_W_m_[k + 1] - person_torso_W_m_[k]) / person_sample_dt_s_;
}

rt::Expected<OptimizerResult> TrajectoryOptimizer::optimize(const TrajectoryProblem& problem,
                                                            PolynomialTrajectory& out) {
  if (const rt::Status s = setProblem(problem); !s) return s.error();
  OptimizerResult result;
  evaluations_ = 0;
  Eigen::VectorXd& x = solver_->x;
  x = x0_;
  best_x_ = x0_;
  best_cost_ = kInf;
  auto objective = [this](const Eigen::VectorXd& xv, Eigen::VectorXd& grad) {
    const double f = evaluate(xv, grad, kAllTerms);
    if (f < best_cost_) {
      best_cost_ = f;
      best_x_ = xv;
    }
    return f;
  };
  Eigen::VectorXd& scratch_grad = scratch_grad_;
  result.initial_cost = evaluate(x0_, scratch_grad, kAllTerms);
  if (!std::isfinite(result.initial_cost))
    return rt::Error{"trajectory optimizer: the initial guess is outside the barrier's domain"};
  // L-BFGS++ reports a failed line search (no decrease found along its direction) by throwing. That
  // happens mostly on badly scaled starts (penalties of 1e12), so the solver restarts from the best point
  // seen, with a fresh history and a step scaled to the new gradient, while restarts keep improving it.
  double fx = 0.0;
  int iterations_left = params_.max_iterations;
  for (int attempt = 0; attempt < kMaxRestarts && iterations_left > 0; ++attempt) {
    const double before = best_cost_;
    solver_->param.max_iterations = iterations_left;
    try {
      const int used = solver_->lbfgs->minimize(objective, x, fx);
      result.iterations += used;
      result.status = used >= iterations_left ? OptimizerStatus::kMaxIterations : OptimizerStatus::kConverged;
      break;
    } catch (const std::exception&) {
      result.status = OptimizerStatus::kLineSearch;
      result.iterations += 1;
      iterations_left -= 1;
      if (!(best_cost_ < before * (1.0 - params_.relative_cost_tolerance))) break;
      x = best_x_;
    }
  }
  if (!std::isfinite(best_cost_)) best_x_ = x0_;
  result.cost = evaluate(best_x_, scratch_grad, kAllTerms);
  result.evaluations = evaluations_;
  out.assign(spline_);
  return result;
}

}  // namespace aerotrack::planning
