// The Bezier target prediction as one QP per axis (see target_predictor.hpp).
#include "aerotrack/prediction/target_predictor.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

namespace aerotrack::prediction {
namespace {

/// sum_i points[i] b_i^degree(s).
Eigen::Vector3d evaluate(std::span<const Eigen::Vector3d> points, int degree, double s) {
  std::array<double, kMaxBezierDegree + 1> b{};
  bernsteinBasis(degree, s, b);
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int i = 0; i <= degree; ++i) p += b[static_cast<std::size_t>(i)] * points[static_cast<std::size_t>(i)];
  return p;
}

}  // namespace

const rt::FieldTable<TargetPredictorParams>& targetPredictorFields() {
  using P = TargetPredictorParams;
  using rt::Range;
  static const rt::FieldTable<P> kTable(
      {
          rt::integer("bezier_degree", &P::bezier_degree, 3, kMaxBezierDegree),
          rt::number("window_s", &P::window_s, Range::closed(0.05, 60.0)),
          rt::number("horizon_s", &P::horizon_s, Range::closed(0.01, 60.0)),
          rt::number("weight_half_life_s", &P::weight_half_life_s, Range::closed(1e-3, 3600.0)),
          rt::number("accel_energy_weight_s3", &P::accel_energy_weight_s3, Range::closed(0.0, 1e6)),
          rt::number("max_speed_mps", &P::max_speed_mps, Range::closed(1e-3, 100.0)),
          rt::number("max_accel_mps2", &P::max_accel_mps2, Range::closed(1e-3, 100.0)),
          rt::flag("fit_z", &P::fit_z),
          rt::flag("pin_to_newest", &P::pin_to_newest),
          rt::flag("pin_velocity_to_newest", &P::pin_velocity_to_newest),
          rt::number("newest_velocity_weight", &P::newest_velocity_weight, Range::closed(0.0, 1e6)),
          rt::integer("min_samples", &P::min_samples, 2, 100'000),
          rt::number("max_data_age_s", &P::max_data_age_s, Range::closed(1e-3, 3600.0)),
          rt::integer("max_samples", &P::max_samples, 2, 100'000),
          rt::integer("qp_max_iterations", &P::qp_max_iterations, 1, 100'000),
      },
      {{"max_samples", "must be >= min_samples", [](const P& p) { return p.max_samples >= p.min_samples; }}});
  return kTable;
}

rt::Status validate(const TargetPredictorParams& params) {
  return targetPredictorFields().validate(params);
}

TargetPredictorParams parseTargetPredictorParams(const rt::ConfigNode& node) {
  return targetPredictorFields().parse(node);
}

Eigen::Vector3d TargetPrediction::position(rt::TimeNs t_ns) const {
  const double s = rt::nsToSeconds(t_ns - start_ns) / durationS();
  return evaluate(control_points_W_m, degree, s);
}

Eigen::Vector3d TargetPrediction::velocityControlPoint(int i) const {
  const auto k = static_cast<std::size_t>(i);
  return static_cast<double>(degree) / durationS() * (control_points_W_m[k + 1] - control_points_W_m[k]);
}

Eigen::Vector3d TargetPrediction::accelerationControlPoint(int i) const {
  const auto k = static_cast<std::size_t>(i);
  const double t = durationS();
  return static_cast<double>(degree * (degree - 1)) / (t * t) *
         (control_points_W_m[k + 2] - 2.0 * control_points_W_m[k + 1] + control_points_W_m[k]);
}

Eigen::Vector3d TargetPrediction::velocity(rt::TimeNs t_ns) const {
  std::array<Eigen::Vector3d, kMaxBezierDegree> points{};
  for (int i = 0; i < degree; ++i) points[static_cast<std::size_t>(i)] = velocityControlPoint(i);
  return evaluate(points, degree - 1, rt::nsToSeconds(t_ns - start_ns) / durationS());
}

Eigen::Vector3d TargetPrediction::acceleration(rt::TimeNs t_ns) const {
  std::array<Eigen::Vector3d, kMaxBezierDegree> points{};
  for (int i = 0; i + 1 < degree; ++i) points[static_cast<std::size_t>(i)] = accelerationControlPoint(i);
  return evaluate(points, degree - 2, rt::nsToSeconds(t_ns - start_ns) / durationS());
}

rt::Expected<TargetPredictor> TargetPredictor::create(const TargetPredictorParams& params) {
  if (rt::Status status = validate(params); !status) return rt::Error{"target predictor: " + status.error().message};
  const int n = params.bezier_degree;
  DenseQpSolverParams qp;
  qp.max_variables = n + 1;
  qp.max_equalities = 1;
  qp.max_inequalities = 2 * n + 2 * (n - 1);
  qp.max_iterations = params.qp_max_iterations;
  auto solver = DenseQpSolver::create(qp);
  if (!solver) return solver.error();
  return TargetPredictor(params, std::move(solver.value()));
}

TargetPredictor::TargetPredictor(const TargetPredictorParams& params, DenseQpSolver solver)
    : params_(params), solver_(std::move(solver)) {
  const int n = params.bezier_degree;
  const int m_in = 2 * n + 2 * (n - 1);
  samples_.reserve(static_cast<std::size_t>(params.max_samples));
  energy_unit_.setZero(n + 1, n + 1);
  accelerationEnergyMatrix(n, 1.0, energy_unit_);
  basis_.setZero(n + 1, params.max_samples);
  weights_.setZero(params.max_samples);
  hessian_.setZero(n + 1, n + 1);
  gradient_.setZero(n + 1);
  a_eq_.setZero(2, n + 1);
  b_eq_.setZero(2);
  a_in_.setZero(m_in, n + 1);
  b_in_.setZero(m_in);
  for (auto& warm : warm_active_) warm.reserve(static_cast<std::size_t>(m_in));
}

void TargetPredictor::reset() {
  samples_.clear();
  for (auto& warm : warm_active_) warm.clear();
}

bool TargetPredictor::add(rt::TimeNs stamp_ns, const Eigen::Vector3d& p_WT_m) {
  if (!p_WT_m.allFinite() || (!samples_.empty() && stamp_ns <= samples_.back().stamp_ns)) return false;
  const rt::TimeNs oldest_kept_ns = stamp_ns - rt::secondsToNs(params_.window_s);
  const auto first_kept =
      std::find_if(samples_.begin(), samples_.end(), [&](const Sample& s) { return s.stamp_ns >= oldest_kept_ns; });
  samples_.erase(samples_.begin(), first_kept);
  if (samples_.size() == samples_.capacity()) samples_.erase(samples_.begin());
  samples_.push_back(Sample{stamp_ns, p_WT_m});
  return true;
}

bool TargetPredictor::add(rt::TimeNs stamp_ns, const Eigen::Vector3d& p_WT_m, const Eigen::Vector3d& v_WT_mps) {
  if (!v_WT_mps.allFinite() || !add(stamp_ns, p_WT_m)) return false;
  samples_.back().v_WT_mps = v_WT_mps;
  samples_.back().has_velocity = true;
  return true;
}

rt::Expected<TargetPrediction> TargetPredictor::predict(rt::TimeNs now_ns) {
  const int count = static_cast<int>(samples_.size());
  if (count < params_.min_samples) {
    return rt::Error{"target predictor: " + std::to_string(count) + " estimates in the window, need " +
                     std::to_string(params_.min_samples)};
  }
  const Sample& newest = samples_.back();
  const rt::TimeNs effective_now_ns = std::max(now_ns, newest.stamp_ns);
  const double age_s = rt::nsToSeconds(effective_now_ns - newest.stamp_ns);
  if (age_s > params_.max_data_age_s) {
    return rt::Error{"target predictor: newest estimate is " + std::to_string(age_s) + " s old"};
  }
  const int n = params_.bezier_degree;
  const int size = n + 1;
  const rt::TimeNs start_ns = samples_.front().stamp_ns;
  const rt::TimeNs end_ns = effective_now_ns + rt::secondsToNs(params_.horizon_s);
  const double duration_s = rt::nsToSeconds(end_ns - start_ns);

  // Residual term: H = 2 sum_k w_k b_k b_k' (w normalised to sum 1), g_axis = -2 sum_k w_k b_k p_k.
  // Positions are taken relative to the newest estimate (conditioning far from the origin).
  double weight_sum = 0.0;
  for (int k = 0; k < count; ++k) {
    const Sample& sample = samples_[static_cast<std::size_t>(k)];
    const double age_k_s = rt::nsToSeconds(newest.stamp_ns - sample.stamp_ns);
    weights_(k) = std::exp2(-age_k_s / params_.weight_half_life_s);
    weight_sum += weights_(k);
    std::array<double, kMaxBezierDegree + 1> b{};
    bernsteinBasis(n, rt::nsToSeconds(sample.stamp_ns - start_ns) / duration_s, b);
    for (int i = 0; i < size; ++i) basis_(i, k) = b[static_cast<std::size_t>(i)];
  }
  weights_.head(count) /= weight_sum;
  hessian_ = (2.0 * params_.accel_energy_weight_s3 / (duration_s * duration_s * duration_s)) * energy_unit_;
  for (int k = 0; k < count; ++k) {
    for (int c = 0; c < size; ++c) {
      for (int r = c; r < size; ++r) hessian_(r, c) += 2.0 * weights_(k) * basis_(r, k) * basis_(c, k);
    }
  }
  for (int c = 0; c < size; ++c) {
    for (int r = 0; r < c; ++r) hessian_(r, c) = hessian_(c, r);
  }

  // Hodograph bounds: +-(n/T)(c_{i+1} - c_i) >= -v_max, +-(n(n-1)/T^2)(c_{i+2} - 2c_{i+1} + c_i) >= -a_max.
  a_in_.setZero();
  const double v_scale = static_cast<double>(n) / duration_s;
  const double a_scale = static_cast<double>(n * (n - 1)) / (duration_s * duration_s);
  int row = 0;
  for (int i = 0; i < n; ++i) {
    for (const double sign : {1.0, -1.0}) {
      a_in_(row, i) = -sign * v_scale;
      a_in_(row, i + 1) = sign * v_scale;
      b_in_(row) = -params_.max_speed_mps;
      ++row;
    }
  }
  for (int i = 0; i + 1 < n; ++i) {
    for (const double sign : {1.0, -1.0}) {
      a_in_(row, i) = sign * a_scale;
      a_in_(row, i + 1) = -2.0 * sign * a_scale;
      a_in_(row, i + 2) = sign * a_scale;
      b_in_(row) = -params_.max_accel_mps2;
      ++row;
    }
  }
  int m_eq = 0;
  if (params_.pin_to_newest) {
    for (int i = 0; i < size; ++i) a_eq_(m_eq, i) = basis_(i, count - 1);
    b_eq_(m_eq) = 0.0;  // relative to the newest estimate
    ++m_eq;
  }
  // The velocity row (its right-hand side is per axis, below): d/dt sum_i c_i b_{n,i}(s) with s = t / T and
  // d b_{n,i} / ds = n (b_{n-1,i-1} - b_{n-1,i}).
  const bool soft = !params_.pin_velocity_to_newest && params_.newest_velocity_weight > 0.0 && newest.has_velocity;
  const int velocity_row = (params_.pin_velocity_to_newest && newest.has_velocity) || soft ? m_eq : -1;
  if (velocity_row >= 0) {
    std::array<double, kMaxBezierDegree + 1> b{};
    bernsteinBasis(n - 1, rt::nsToSeconds(newest.stamp_ns - start_ns) / duration_s, b);
    for (int i = 0; i < size; ++i) {
      const double lower = i > 0 ? b[static_cast<std::size_t>(i - 1)] : 0.0;
      const double upper = i < n ? b[static_cast<std::size_t>(i)] : 0.0;
      a_eq_(velocity_row, i) = v_scale * (lower - upper);
    }
    if (soft) {
      const double w = params_.newest_velocity_weight;
      for (int c = 0; c < size; ++c)
        for (int r = 0; r < size; ++r) hessian_(r, c) += 2.0 * w * a_eq_(velocity_row, r) * a_eq_(velocity_row, c);
    } else {
      ++m_eq;
    }
  }

  TargetPrediction prediction;
  prediction.degree = n;
  prediction.start_ns = start_ns;
  prediction.end_ns = end_ns;
  prediction.now_ns = effective_now_ns;
  prediction.newest_data_ns = newest.stamp_ns;
  prediction.samples_used = count;
  const int axes = params_.fit_z ? 3 : 2;
  for (int axis = 0; axis < axes; ++axis) {
    gradient_.setZero();
    for (int k = 0; k < count; ++k) {
      const double offset = samples_[static_cast<std::size_t>(k)].p_WT_m(axis) - newest.p_WT_m(axis);
      gradient_ -= (2.0 * weights_(k) * offset) * basis_.col(k);
    }
    if (soft) {
      gradient_ -= (2.0 * params_.newest_velocity_weight * newest.v_WT_mps(axis)) * a_eq_.row(velocity_row).transpose();
    }
    // The velocity pin is clamped into the hodograph's bounds (else the QP has no solution).
    if (velocity_row >= 0 && !soft)
      b_eq_(velocity_row) = std::clamp(newest.v_WT_mps(axis), -params_.max_speed_mps, params_.max_speed_mps);
    const QpProblem problem{hessian_, gradient_, a_eq_.topRows(m_eq), b_eq_.head(m_eq), a_in_, b_in_};
    std::vector<int>& warm = warm_active_[static_cast<std::size_t>(axis)];
    QpResult result = solver_.solve(problem, warm);
    if (result.status != QpStatus::kOptimal && velocity_row >= 0 && !soft) {
      // The pinned velocity can still clash with the acceleration bounds near the window's start: fit unpinned.
      warm.clear();
      const int m_unpinned = m_eq - 1;
      const QpProblem unpinned{hessian_, gradient_, a_eq_.topRows(m_unpinned), b_eq_.head(m_unpinned), a_in_, b_in_};
      result = solver_.solve(unpinned, warm);
    }
    prediction.qp_iterations += result.iterations;
    if (result.status != QpStatus::kOptimal) {
      warm.clear();
      return rt::Error{std::string("target predictor: QP ") + toString(result.status) + " on axis " +
                       std::to_string(axis)};
    }
    const auto active = solver_.activeInequalities();
    warm.assign(active.begin(), active.end());  // within the reserved capacity
    const auto x = solver_.solution();
    for (int i = 0; i < size; ++i) {
      prediction.control_points_W_m[static_cast<std::size_t>(i)](axis) = x(i) + newest.p_WT_m(axis);
    }
  }
  if (!params_.fit_z) {
    double z_m = 0.0;
    for (int k = 0; k < count; ++k) z_m += weights_(k) * samples_[static_cast<std::size_t>(k)].p_WT_m.z();
    for (int i = 0; i < size; ++i) prediction.control_points_W_m[static_cast<std::size_t>(i)].z() = z_m;
  }
  return prediction;
}

}  // namespace aerotrack::prediction
