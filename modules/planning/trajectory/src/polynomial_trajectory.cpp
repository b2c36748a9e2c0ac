// Piecewise quintic evaluation: see polynomial_trajectory.hpp.
#include "aerotrack/planning/polynomial_trajectory.hpp"

#include <algorithm>
#include <cmath>

namespace aerotrack::planning {

PolynomialTrajectory::PolynomialTrajectory(int max_pieces) {
  coeffs_.reserve(static_cast<std::size_t>(max_pieces));
  durations_s_.reserve(static_cast<std::size_t>(max_pieces));
}

void PolynomialTrajectory::assign(const MinJerkSpline& spline) {
  assign(spline.coefficients(), spline.durations());
}

void PolynomialTrajectory::assign(const RowMatrixX3d& coefficients, const Eigen::VectorXd& durations_s) {
  const auto m = static_cast<std::size_t>(durations_s.size());
  coeffs_.resize(m);
  durations_s_.resize(m);
  total_s_ = 0.0;
  for (std::size_t i = 0; i < m; ++i) {
    coeffs_[i] = coefficients.middleRows<6>(static_cast<Eigen::Index>(6 * i));
    durations_s_[i] = durations_s(static_cast<Eigen::Index>(i));
    total_s_ += durations_s_[i];
  }
}

void PolynomialTrajectory::append(const Eigen::Matrix<double, 6, 3>& coefficients, double duration_s) {
  coeffs_.push_back(coefficients);
  durations_s_.push_back(duration_s);
  total_s_ += duration_s;
}

int PolynomialTrajectory::locate(double& t_s) const {
  t_s = std::clamp(t_s, 0.0, total_s_);
  const int last = pieces() - 1;
  for (int i = 0; i < last; ++i) {
    const double d = durations_s_[static_cast<std::size_t>(i)];
    if (t_s <= d) return i;
    t_s -= d;
  }
  t_s = std::min(t_s, durations_s_.back());
  return last;
}

Eigen::Vector3d PolynomialTrajectory::derivative(int order, double t_s) const {
  if (coeffs_.empty()) return Eigen::Vector3d::Zero();
  const int i = locate(t_s);
  return coeffs_[static_cast<std::size_t>(i)].transpose() * monomialBasis(order, t_s);
}

trajectory_server::TrajectorySample PolynomialTrajectory::sample(double t_s) const {
  trajectory_server::TrajectorySample s;
  if (coeffs_.empty()) return s;
  const int i = locate(t_s);
  const Eigen::Matrix<double, 6, 3>& c = coeffs_[static_cast<std::size_t>(i)];
  s.p_W_m = c.transpose() * monomialBasis(0, t_s);
  s.v_W_mps = c.transpose() * monomialBasis(1, t_s);
  s.a_W_mps2 = c.transpose() * monomialBasis(2, t_s);
  return s;
}

void PolynomialTrajectory::stretchTime(double factor) {
  // p'(t) = p(t / k) = sum_n c_n k^-n t^n on [0, k T].
  double scale = 1.0;
  Eigen::Matrix<double, 6, 1> per_order;
  for (int n = 0; n < 6; ++n, scale /= factor) per_order(n) = scale;
  for (auto& c : coeffs_) c = per_order.asDiagonal() * c;
  for (double& d : durations_s_) d *= factor;
  total_s_ *= factor;
}

bool retimeKeepingStart(const PolynomialTrajectory& in, const StatePva& start, double factor, MinJerkSpline& spline,
                        PolynomialTrajectory& out) {
  const int m = in.pieces();
  if (m < 1 || !(factor > 0.0) || !std::isfinite(factor)) return false;
  Eigen::Matrix3Xd waypoints_m(3, m - 1);
  Eigen::VectorXd durations_s(m);
  double t_s = 0.0;
  for (int i = 0; i < m; ++i) {
    t_s += in.pieceDurationS(i);
    durations_s(i) = factor * in.pieceDurationS(i);
    if (i + 1 < m) waypoints_m.col(i) = in.derivative(0, t_s);
  }
  const trajectory_server::TrajectorySample last = in.sample(in.durationS());
  StatePva end;
  end << last.p_W_m, last.v_W_mps / factor, last.a_W_mps2 / (factor * factor);
  spline.reset(start, end, m);
  if (!spline.generate(waypoints_m, durations_s)) return false;
  out.assign(spline);
  return true;
}

}  // namespace aerotrack::planning
