// Minimum-jerk coefficient map and its adjoint: see min_jerk_spline.hpp.
#include "aerotrack/planning/min_jerk_spline.hpp"

#include <cmath>

namespace aerotrack::planning {

Eigen::Matrix<double, 6, 1> monomialBasis(int derivative, double t_s) {
  const double t = t_s;
  const double t2 = t * t;
  const double t3 = t2 * t;
  Eigen::Matrix<double, 6, 1> b;
  switch (derivative) {
    case 0:
      b << 1.0, t, t2, t3, t2 * t2, t3 * t2;
      break;
    case 1:
      b << 0.0, 1.0, 2.0 * t, 3.0 * t2, 4.0 * t3, 5.0 * t2 * t2;
      break;
    case 2:
      b << 0.0, 0.0, 2.0, 6.0 * t, 12.0 * t2, 20.0 * t3;
      break;
    case 3:
      b << 0.0, 0.0, 0.0, 6.0, 24.0 * t, 60.0 * t2;
      break;
    case 4:
      b << 0.0, 0.0, 0.0, 0.0, 24.0, 120.0 * t;
      break;
    case 5:
      b << 0.0, 0.0, 0.0, 0.0, 0.0, 120.0;
      break;
    default:
      b.setZero();
  }
  return b;
}

namespace {

// The row of junction i (offset 0..5 within rows 6i+3..6i+8) and the derivative order it constrains.
constexpr int kJunctionDerivative[6] = {3, 4, 0, 0, 1, 2};

}  // namespace

void MinJerkSpline::reset(const StatePva& start, const StatePva& end, int pieces) {
  start_ = start;
  end_ = end;
  pieces_ = pieces;
  system_.resize(6 * pieces, 6, 6);
  coeffs_.resize(Eigen::Index{6} * pieces, 3);
  durations_s_.resize(pieces);
}

bool MinJerkSpline::generate(const Eigen::Ref<const Eigen::Matrix3Xd>& waypoints_m,
                             const Eigen::Ref<const Eigen::VectorXd>& durations_s) {
  const Eigen::Index m = pieces_;
  if (durations_s.size() != m || waypoints_m.cols() != m - 1) return false;
  for (Eigen::Index i = 0; i < m; ++i) {
    if (!std::isfinite(durations_s(i)) || durations_s(i) <= 0.0) return false;
  }
  durations_s_ = durations_s;
  system_.setZero();
  coeffs_.setZero();
  // Start conditions: c_{0,0} = p, c_{0,1} = v, 2 c_{0,2} = a.
  system_(0, 0) = 1.0;
  system_(1, 1) = 1.0;
  system_(2, 2) = 2.0;
  coeffs_.row(0) = start_.col(0).transpose();
  coeffs_.row(1) = start_.col(1).transpose();
  coeffs_.row(2) = start_.col(2).transpose();
  for (Eigen::Index i = 0; i + 1 < m; ++i) {
    const double t = durations_s_(i);
    for (int r = 0; r < 6; ++r) {
      const Eigen::Index row = 6 * i + 3 + r;
      const int d = kJunctionDerivative[r];
      const Eigen::Matrix<double, 6, 1> end_of_piece = monomialBasis(d, t);
      for (int k = 0; k < 6; ++k) system_(row, 6 * i + k) = end_of_piece(k);
      if (r == 2) {
        coeffs_.row(row) = waypoints_m.col(i).transpose();
      } else {
        const Eigen::Matrix<double, 6, 1> start_of_next = monomialBasis(d, 0.0);
        system_(row, 6 * (i + 1) + d) = -start_of_next(d);
      }
    }
  }
  const double t_end = durations_s_(m - 1);
  for (int d = 0; d < 3; ++d) {
    const Eigen::Index row = 6 * m - 3 + d;
    const Eigen::Matrix<double, 6, 1> b = monomialBasis(d, t_end);
    for (int k = 0; k < 6; ++k) system_(row, 6 * (m - 1) + k) = b(k);
    coeffs_.row(row) = end_.col(d).transpose();
  }
  if (!system_.factorize()) return false;
  system_.solve(coeffs_);
  return true;
}

double MinJerkSpline::jerkEnergy() const {
  double energy = 0.0;
  for (Eigen::Index i = 0; i < pieces_; ++i) {
    const double t = durations_s_(i);
    const double t2 = t * t;
    const double t3 = t2 * t;
    const Eigen::RowVector3d c3 = coeffs_.row(6 * i + 3);
    const Eigen::RowVector3d c4 = coeffs_.row(6 * i + 4);
    const Eigen::RowVector3d c5 = coeffs_.row(6 * i + 5);
    energy += 36.0 * c3.squaredNorm() * t + 144.0 * c3.dot(c4) * t2 +
              (192.0 * c4.squaredNorm() + 240.0 * c3.dot(c5)) * t3 + 720.0 * c4.dot(c5) * t2 * t2 +
              720.0 * c5.squaredNorm() * t3 * t2;
  }
  return energy;
}

void MinJerkSpline::addJerkEnergyGradient(RowMatrixX3d& grad_c, Eigen::VectorXd& grad_T) const {
  for (Eigen::Index i = 0; i < pieces_; ++i) {
    const double t = durations_s_(i);
    const double t2 = t * t;
    const double t3 = t2 * t;
    const double t4 = t2 * t2;
    const Eigen::RowVector3d c3 = coeffs_.row(6 * i + 3);
    const Eigen::RowVector3d c4 = coeffs_.row(6 * i + 4);
    const Eigen::RowVector3d c5 = coeffs_.row(6 * i + 5);
    grad_c.row(6 * i + 3) += 72.0 * c3 * t + 144.0 * c4 * t2 + 240.0 * c5 * t3;
    grad_c.row(6 * i + 4) += 144.0 * c3 * t2 + 384.0 * c4 * t3 + 720.0 * c5 * t4;
    grad_c.row(6 * i + 5) += 240.0 * c3 * t3 + 720.0 * c4 * t4 + 1440.0 * c5 * t4 * t;
    // d/dT of int_0^T |p'''|^2 dt is |p'''(T)|^2.
    const Eigen::RowVector3d jerk_end = 6.0 * c3 + 24.0 * c4 * t + 60.0 * c5 * t2;
    grad_T(i) += jerk_end.squaredNorm();
  }
}

void MinJerkSpline::propagateGradient(RowMatrixX3d& grad_c, Eigen::VectorXd& grad_T, Eigen::Matrix3Xd& grad_q) const {
  const Eigen::Index m = pieces_;
  system_.solveAdjoint(grad_c);  // grad_c now holds G = A^-T dJ/dc
  const RowMatrixX3d& g = grad_c;
  grad_q.resize(3, m - 1);
  for (Eigen::Index i = 0; i + 1 < m; ++i) grad_q.col(i) = g.row(6 * i + 5).transpose();
  // dJ/dT_i -= G^T (dA/dT_i) c: the rows holding beta_d(T_i) for piece i change by beta_{d+1}(T_i) c_i.
  for (Eigen::Index i = 0; i < m; ++i) {
    const double t = durations_s_(i);
    const auto c_i = coeffs_.middleRows<6>(6 * i);
    if (i + 1 < m) {
      for (int r = 0; r < 6; ++r) {
        const Eigen::RowVector3d dA_c = monomialBasis(kJunctionDerivative[r] + 1, t).transpose() * c_i;
        grad_T(i) -= g.row(6 * i + 3 + r).dot(dA_c);
      }
    } else {
      for (int d = 0; d < 3; ++d) {
        const Eigen::RowVector3d dA_c = monomialBasis(d + 1, t).transpose() * c_i;
        grad_T(i) -= g.row(6 * m - 3 + d).dot(dA_c);
      }
    }
  }
}

}  // namespace aerotrack::planning
