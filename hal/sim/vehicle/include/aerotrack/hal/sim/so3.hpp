// Small rotation-group (SO(3)) helpers for the vehicle model and its controller: the hat (skew)
// operator, the exponential map by Rodrigues' formula, the logarithm, and re-orthonormalisation of
// a rotation matrix that has picked up rounding drift.
//   exp(phi) = I + sin(t)/t [phi]x + (1 - cos(t))/t^2 [phi]x^2,  t = |phi|
//   log(R)   = t / (2 sin t) vee(R - R^T),                         cos t = (trace(R) - 1) / 2
// (Murray, Li & Sastry 1994, "A Mathematical Introduction to Robotic Manipulation", ch. 2; small
// angles use the Taylor series of the coefficients.)
//
// Header-only, pure, allocation-free, thread-safe (no state).
#pragma once

#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace aerotrack::hal::sim::so3 {

/// [v]x: the skew-symmetric matrix with [v]x u = v x u.
inline Eigen::Matrix3d hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

/// exp([phi]x) for a rotation vector phi (axis times angle, radians). Exact to rounding.
inline Eigen::Matrix3d expMap(const Eigen::Vector3d& phi) {
  const double theta_sq = phi.squaredNorm();
  double a = 0.0;  // sin(t) / t
  double b = 0.0;  // (1 - cos(t)) / t^2
  if (theta_sq < 1e-12) {
    a = 1.0 - theta_sq / 6.0 * (1.0 - theta_sq / 20.0);
    b = 0.5 - theta_sq / 24.0 * (1.0 - theta_sq / 30.0);
  } else {
    const double theta = std::sqrt(theta_sq);
    const double s_half = std::sin(0.5 * theta);
    const double c_half = std::cos(0.5 * theta);
    a = 2.0 * s_half * c_half / theta;
    b = 2.0 * s_half * s_half / theta_sq;  // no cancellation, unlike 1 - cos(t)
  }
  const Eigen::Matrix3d k = hat(phi);
  return Eigen::Matrix3d::Identity() + a * k + b * (k * k);
}

/// The rotation vector phi with exp([phi]x) = R, |phi| in [0, pi]. R must be a rotation.
/// Near an angle of pi the axis is taken from the diagonal of R (sign is then arbitrary).
inline Eigen::Vector3d logMap(const Eigen::Matrix3d& R) {
  const double cos_theta = std::clamp(0.5 * (R.trace() - 1.0), -1.0, 1.0);
  const Eigen::Vector3d vee(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));  // 2 sin(t) axis
  const double sin_theta = 0.5 * vee.norm();
  const double theta = std::atan2(sin_theta, cos_theta);
  if (theta < 1e-6) return 0.5 * (1.0 + theta * theta / 6.0) * vee;
  if (M_PI - theta > 1e-6) return theta / (2.0 * sin_theta) * vee;
  // theta close to pi: R ~ 2 n n^T - I. Take the column of the largest diagonal entry.
  Eigen::Index i = 0;
  R.diagonal().maxCoeff(&i);
  Eigen::Vector3d n = R.col(i) + Eigen::Vector3d::Unit(i);
  n.normalize();
  if (n.dot(vee) < 0.0) n = -n;  // keep the sign consistent with the (tiny) antisymmetric part
  return theta * n;
}

/// Removes rounding drift from an almost-orthonormal matrix (as in Premerlani & Bizard's DCM
/// renormalisation): splits the x/y column error half and half, normalises, z = x cross y.
/// Costs three square roots.
inline Eigen::Matrix3d reorthonormalize(const Eigen::Matrix3d& R) {
  const Eigen::Vector3d x = R.col(0);
  const Eigen::Vector3d y = R.col(1);
  const double error = x.dot(y);
  const Eigen::Vector3d x_new = (x - 0.5 * error * y).normalized();
  const Eigen::Vector3d y_new = (y - 0.5 * error * x).normalized();
  Eigen::Matrix3d out;
  out.col(0) = x_new;
  out.col(1) = y_new;
  out.col(2) = x_new.cross(y_new);
  return out;
}

}  // namespace aerotrack::hal::sim::so3
