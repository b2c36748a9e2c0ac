// The Goldfarb-Idnani dual active-set QP solver (see dense_qp.hpp). Loops over small blocks are
// written out so that solve() allocates nothing (Eigen's triangular solvers may use scratch memory).
#include "aerotrack/prediction/dense_qp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace aerotrack::prediction {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
/// A new normal whose component outside the active span is below this fraction of its length is
/// treated as linearly dependent on the active normals.
constexpr double kDependentRatio = 1e-10;
/// Multipliers above -this after a warm start count as non-negative (then clamped to 0).
constexpr double kMultiplierTolerance = 1e-10;

}  // namespace

const char* toString(QpStatus status) {
  switch (status) {
    case QpStatus::kOptimal:
      return "optimal";
    case QpStatus::kInfeasible:
      return "infeasible";
    case QpStatus::kMaxIterations:
      return "max_iterations";
    case QpStatus::kNotPositiveDefinite:
      return "not_positive_definite";
    case QpStatus::kInvalidProblem:
      return "invalid_problem";
  }
  return "unknown";
}

rt::Expected<DenseQpSolver> DenseQpSolver::create(const DenseQpSolverParams& params) {
  if (params.max_variables < 1) return rt::Error{"dense qp: max_variables must be >= 1"};
  if (params.max_equalities < 0) return rt::Error{"dense qp: max_equalities must be >= 0"};
  if (params.max_inequalities < 0) return rt::Error{"dense qp: max_inequalities must be >= 0"};
  if (params.max_iterations < 1) return rt::Error{"dense qp: max_iterations must be >= 1"};
  if (!std::isfinite(params.feasibility_tolerance) || params.feasibility_tolerance <= 0.0) {
    return rt::Error{"dense qp: feasibility_tolerance must be finite and > 0"};
  }
  return DenseQpSolver(params);
}

DenseQpSolver::DenseQpSolver(const DenseQpSolverParams& params) : params_(params) {
  const int n = params.max_variables;
  const int m = params.max_equalities + params.max_inequalities;
  const int max_active = std::min(n, m);
  l_.setZero(n, n);
  j_.setZero(n, n);
  r_.setZero(n, n);
  x_.setZero(n);
  normal_.setZero(n);
  d_.setZero(n);
  z_.setZero(n);
  r_dir_.setZero(n);
  u_.setZero(n);
  row_norm_in_.setZero(params.max_inequalities);
  slack_in_.setZero(params.max_inequalities);
  active_.assign(static_cast<std::size_t>(max_active), 0);
  active_in_out_.assign(static_cast<std::size_t>(max_active), 0);
  u_in_out_.assign(static_cast<std::size_t>(max_active), 0.0);
  warm_.assign(static_cast<std::size_t>(params.max_inequalities), 0);
  in_warm_.assign(static_cast<std::size_t>(params.max_inequalities), 0);
  is_active_in_.assign(static_cast<std::size_t>(params.max_inequalities), 0);
}

std::span<const int> DenseQpSolver::activeInequalities() const {
  return {active_in_out_.data(), static_cast<std::size_t>(active_in_count_)};
}

std::span<const double> DenseQpSolver::inequalityMultipliers() const {
  return {u_in_out_.data(), static_cast<std::size_t>(active_in_count_)};
}

bool DenseQpSolver::factorise(const Eigen::Ref<const Eigen::MatrixXd>& h) {
  // H = L L' (lower half of H), then J = L^-T by back substitution on L' J = I.
  for (int c = 0; c < n_; ++c) {
    double diag = h(c, c);
    for (int k = 0; k < c; ++k) diag -= l_(c, k) * l_(c, k);
    if (!(diag > 1e-14 * std::abs(h(c, c))) || !(diag > 0.0)) return false;
    l_(c, c) = std::sqrt(diag);
    for (int i = c + 1; i < n_; ++i) {
      double v = h(i, c);
      for (int k = 0; k < c; ++k) v -= l_(i, k) * l_(c, k);
      l_(i, c) = v / l_(c, c);
    }
  }
  for (int c = 0; c < n_; ++c) {
    for (int i = n_ - 1; i >= 0; --i) {
      double v = i == c ? 1.0 : 0.0;
      for (int k = i + 1; k < n_; ++k) v -= l_(k, i) * j_(k, c);
      j_(i, c) = v / l_(i, i);
    }
  }
  return true;
}

void DenseQpSolver::loadNormal(const QpProblem& problem, int constraint) {
  if (constraint < m_eq_) {
    for (int i = 0; i < n_; ++i) normal_(i) = problem.a_eq(constraint, i);
  } else {
    for (int i = 0; i < n_; ++i) normal_(i) = problem.a_in(constraint - m_eq_, i);
  }
}

double DenseQpSolver::slack(const QpProblem& problem, int constraint) const {
  if (constraint < m_eq_) return problem.a_eq.row(constraint).dot(x_.head(n_)) - problem.b_eq(constraint);
  const int row = constraint - m_eq_;
  return problem.a_in.row(row).dot(x_.head(n_)) - problem.b_in(row);
}

double DenseQpSolver::violationTolerance(int inequality) const {
  return params_.feasibility_tolerance * row_norm_in_(inequality) * (1.0 + x_.head(n_).lpNorm<Eigen::Infinity>());
}

bool DenseQpSolver::computeDirections() {
  double d_sq = 0.0;
  double d2_sq = 0.0;
  for (int i = 0; i < n_; ++i) {
    d_(i) = j_.col(i).head(n_).dot(normal_.head(n_));
    d_sq += d_(i) * d_(i);
    if (i >= q_) d2_sq += d_(i) * d_(i);
  }
  z_.head(n_).setZero();
  for (int i = q_; i < n_; ++i) z_.head(n_) += d_(i) * j_.col(i).head(n_);
  for (int i = q_ - 1; i >= 0; --i) {  // r = R^-1 d1
    double v = d_(i);
    for (int k = i + 1; k < q_; ++k) v -= r_(i, k) * r_dir_(k);
    r_dir_(i) = v / r_(i, i);
  }
  return d2_sq <= kDependentRatio * kDependentRatio * d_sq;
}

void DenseQpSolver::addConstraint(int constraint, double multiplier) {
  // Rotate d(q..n-1) into d(q) (and J's columns alike), so that J' N stays triangular.
  for (int j = n_ - 1; j > q_; --j) {
    const double a = d_(j - 1);
    const double b = d_(j);
    const double h = std::hypot(a, b);
    if (h == 0.0) continue;
    const double c = a / h;
    const double s = b / h;
    d_(j - 1) = h;
    d_(j) = 0.0;
    for (int k = 0; k < n_; ++k) {
      const double t1 = j_(k, j - 1);
      const double t2 = j_(k, j);
      j_(k, j - 1) = c * t1 + s * t2;
      j_(k, j) = -s * t1 + c * t2;
    }
  }
  for (int i = 0; i <= q_; ++i) r_(i, q_) = d_(i);
  active_[static_cast<std::size_t>(q_)] = constraint;
  u_(q_) = multiplier;
  if (constraint >= m_eq_) is_active_in_[static_cast<std::size_t>(constraint - m_eq_)] = 1;
  ++q_;
}

void DenseQpSolver::dropConstraint(int position) {
  const int constraint = active_[static_cast<std::size_t>(position)];
  if (constraint >= m_eq_) is_active_in_[static_cast<std::size_t>(constraint - m_eq_)] = 0;
  for (int i = position; i < q_ - 1; ++i) {
    active_[static_cast<std::size_t>(i)] = active_[static_cast<std::size_t>(i) + 1];
    u_(i) = u_(i + 1);
    for (int k = 0; k < q_; ++k) r_(k, i) = r_(k, i + 1);
  }
  --q_;
  // R is now upper Hessenberg from column `position`: rotate rows (j, j+1) back to triangular.
  for (int j = position; j < q_; ++j) {
    const double a = r_(j, j);
    const double b = r_(j + 1, j);
    const double h = std::hypot(a, b);
    if (h == 0.0) continue;
    const double c = a / h;
    const double s = b / h;
    r_(j, j) = h;
    r_(j + 1, j) = 0.0;
    for (int k = j + 1; k < q_; ++k) {
      const double t1 = r_(j, k);
      const double t2 = r_(j + 1, k);
      r_(j, k) = c * t1 + s * t2;
      r_(j + 1, k) = -s * t1 + c * t2;
    }
    for (int k = 0; k < n_; ++k) {
      const double t1 = j_(k, j);
      const double t2 = j_(k, j + 1);
      j_(k, j) = c * t1 + s * t2;
      j_(k, j + 1) = -s * t1 + c * t2;
    }
  }
}

void DenseQpSolver::resetToUnconstrained(const QpProblem& problem) {
  // J = L^-T again (rotations changed it), x = -J J' g.
  for (int c = 0; c < n_; ++c) {
    for (int i = n_ - 1; i >= 0; --i) {
      double v = i == c ? 1.0 : 0.0;
      for (int k = i + 1; k < n_; ++k) v -= l_(k, i) * j_(k, c);
      j_(i, c) = v / l_(i, i);
    }
  }
  for (int i = 0; i < n_; ++i) d_(i) = j_.col(i).head(n_).dot(problem.gradient);
  x_.head(n_).setZero();
  for (int i = 0; i < n_; ++i) x_.head(n_) -= d_(i) * j_.col(i).head(n_);
  q_ = 0;
  std::fill_n(is_active_in_.begin(), m_in_, 0);
}

bool DenseQpSolver::stepOntoAsEquality(const QpProblem& problem, int constraint) {
  loadNormal(problem, constraint);
  if (computeDirections()) return false;
  const double t = -slack(problem, constraint) / z_.head(n_).dot(normal_.head(n_));
  x_.head(n_) += t * z_.head(n_);
  u_.head(q_) -= t * r_dir_.head(q_);
  addConstraint(constraint, t);
  return true;
}

bool DenseQpSolver::addEqualities(const QpProblem& problem, int& iterations) {
  for (int i = 0; i < m_eq_; ++i) {
    ++iterations;
    if (stepOntoAsEquality(problem, i)) continue;
    // Dependent on the equalities already active: redundant if it already holds, else inconsistent.
    const double norm = problem.a_eq.row(i).norm();
    const double tolerance = params_.feasibility_tolerance * norm * (1.0 + x_.head(n_).lpNorm<Eigen::Infinity>());
    if (std::abs(slack(problem, i)) > tolerance) return false;
  }
  return true;
}

QpResult DenseQpSolver::solve(const QpProblem& problem, std::span<const int> warm_start_active) {
  QpResult result;
  active_in_count_ = 0;
  const auto n = problem.hessian.rows();
  const auto m_eq = problem.a_eq.rows();
  const auto m_in = problem.a_in.rows();
  if (n < 1 || n > params_.max_variables || problem.hessian.cols() != n || problem.gradient.size() != n ||
      m_eq > params_.max_equalities || m_in > params_.max_inequalities || problem.b_eq.size() != m_eq ||
      problem.b_in.size() != m_in || (m_eq > 0 && problem.a_eq.cols() != n) || (m_in > 0 && problem.a_in.cols() != n)) {
    return result;
  }
  if (!problem.hessian.allFinite() || !problem.gradient.allFinite() || !problem.a_eq.allFinite() ||
      !problem.b_eq.allFinite() || !problem.a_in.allFinite() || !problem.b_in.allFinite()) {
    return result;
  }
  n_ = static_cast<int>(n);
  m_eq_ = static_cast<int>(m_eq);
  m_in_ = static_cast<int>(m_in);
  q_ = 0;
  if (!factorise(problem.hessian)) {
    result.status = QpStatus::kNotPositiveDefinite;
    return result;
  }
  for (int i = 0; i < m_in_; ++i) row_norm_in_(i) = problem.a_in.row(i).norm();

  int iterations = 0;
  const auto finish = [&](QpStatus status) {
    result.status = status;
    result.iterations = iterations;
    const auto x = x_.head(n_);
    double quadratic = 0.0;
    for (int c = 0; c < n_; ++c) {
      double hx = 0.0;
      for (int r = 0; r < n_; ++r) hx += problem.hessian(std::max(r, c), std::min(r, c)) * x(r);
      quadratic += x(c) * hx;
    }
    result.objective = 0.5 * quadratic + problem.gradient.dot(x);
    active_in_count_ = 0;
    for (int k = 0; k < q_; ++k) {
      if (active_[static_cast<std::size_t>(k)] < m_eq_) continue;
      active_in_out_[static_cast<std::size_t>(active_in_count_)] = active_[static_cast<std::size_t>(k)] - m_eq_;
      u_in_out_[static_cast<std::size_t>(active_in_count_)] = u_(k);
      ++active_in_count_;
    }
    return result;
  };

  resetToUnconstrained(problem);
  if (!addEqualities(problem, iterations)) return finish(QpStatus::kInfeasible);

  // Warm start: impose the guessed active set as equalities; release rows with negative
  // multipliers and start over until the start point is dual feasible (an S-pair).
  std::fill_n(in_warm_.begin(), m_in_, 0);
  int warm_count = 0;
  for (const int row : warm_start_active) {
    if (row < 0 || row >= m_in_ || in_warm_[static_cast<std::size_t>(row)] != 0) continue;
    in_warm_[static_cast<std::size_t>(row)] = 1;
    warm_[static_cast<std::size_t>(warm_count++)] = row;
  }
  while (warm_count > 0) {
    for (int k = 0; k < warm_count; ++k) {
      ++iterations;
      stepOntoAsEquality(problem, m_eq_ + warm_[static_cast<std::size_t>(k)]);
    }
    int kept = 0;
    for (int k = 0; k < warm_count; ++k) {
      const int row = warm_[static_cast<std::size_t>(k)];
      bool keep = false;
      for (int a = 0; a < q_; ++a) {
        if (active_[static_cast<std::size_t>(a)] == m_eq_ + row) keep = u_(a) >= -kMultiplierTolerance;
      }
      if (keep) warm_[static_cast<std::size_t>(kept++)] = row;
    }
    if (kept == warm_count) break;
    warm_count = kept;
    if (iterations > params_.max_iterations) return finish(QpStatus::kMaxIterations);
    resetToUnconstrained(problem);
    if (!addEqualities(problem, iterations)) return finish(QpStatus::kInfeasible);
  }
  for (int a = 0; a < q_; ++a) {
    if (active_[static_cast<std::size_t>(a)] >= m_eq_) u_(a) = std::max(u_(a), 0.0);
  }

  // The dual iterations: add the most violated inequality until none is violated.
  while (true) {
    int p = -1;
    double worst = 0.0;
    for (int i = 0; i < m_in_; ++i) {
      if (is_active_in_[static_cast<std::size_t>(i)] != 0) continue;
      const double s = slack(problem, m_eq_ + i);
      if (s >= -violationTolerance(i)) continue;
      const double scaled = s / std::max(row_norm_in_(i), std::numeric_limits<double>::min());
      if (p < 0 || scaled < worst) {
        worst = scaled;
        p = i;
      }
    }
    if (p < 0) return finish(QpStatus::kOptimal);
    const int constraint = m_eq_ + p;
    loadNormal(problem, constraint);
    double u_p = 0.0;
    double s_p = slack(problem, constraint);
    while (true) {
      if (++iterations > params_.max_iterations) return finish(QpStatus::kMaxIterations);
      const bool dependent = computeDirections();
      // Partial (dual) step: the largest step keeping the active inequalities' multipliers >= 0.
      double t1 = kInf;
      int blocking = -1;
      for (int k = 0; k < q_; ++k) {
        if (active_[static_cast<std::size_t>(k)] < m_eq_ || !(r_dir_(k) > 0.0)) continue;
        const double ratio = u_(k) / r_dir_(k);
        if (ratio < t1) {
          t1 = ratio;
          blocking = k;
        }
      }
      // Full (primal) step: onto the constraint.
      const double t2 = dependent ? kInf : -s_p / z_.head(n_).dot(normal_.head(n_));
      if (t1 == kInf && t2 == kInf) return finish(QpStatus::kInfeasible);
      if (t2 == kInf) {  // dual step only; x stays
        u_.head(q_) -= t1 * r_dir_.head(q_);
        u_p += t1;
        dropConstraint(blocking);
        continue;
      }
      const double t = std::min(t1, t2);
      x_.head(n_) += t * z_.head(n_);
      u_.head(q_) -= t * r_dir_.head(q_);
      u_p += t;
      if (t2 <= t1) {
        addConstraint(constraint, u_p);
        break;
      }
      dropConstraint(blocking);
      s_p = slack(problem, constraint);
    }
  }
}

}  // namespace aerotrack::prediction
