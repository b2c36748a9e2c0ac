// The person in the gimbal camera's vertical field of view: see camera_view.hpp.
#include "aerotrack/planning/camera_view.hpp"

#include <array>

namespace aerotrack::planning {

bool addCameraViewTerm(const Eigen::Vector3d& p_W_m, const Eigen::Vector3d& a_W_mps2,
                       const Eigen::Vector3d& torso_centre_W_m, double torso_half_m, double sin_limit, double weight,
                       double& cost, CameraViewGradient& gradient) {
  const Eigen::Vector3d f = a_W_mps2 + Eigen::Vector3d(0.0, 0.0, kGravityMps2);
  const double f_norm = f.norm();
  if (!(f_norm > 0.01 * kGravityMps2)) return false;
  const Eigen::Vector3d b3 = f / f_norm;
  bool active = false;
  // The hips must not fall below the image (sign -1: the violation is -sin_limit - b3 . d), the shoulders
  // must not rise above it (sign +1: b3 . d - sin_limit).
  const std::array<double, 2> signs = {-1.0, 1.0};
  for (const double sign : signs) {
    const Eigen::Vector3d r = torso_centre_W_m + Eigen::Vector3d(0.0, 0.0, sign * torso_half_m) - p_W_m;
    const double r_norm = r.norm();
    if (!(r_norm > 0.01)) continue;
    const Eigen::Vector3d d = r / r_norm;
    const double s = b3.dot(d);
    const double violation = sign * s - sin_limit;
    if (violation <= 0.0) continue;
    active = true;
    cost += weight * violation * violation * violation;
    const double ds = sign * weight * 3.0 * violation * violation;  // d cost / d (b3 . d)
    const Eigen::Vector3d ds_dr = (b3 - s * d) / r_norm;            // (I - d d^T) b3 / |r|
    gradient.p -= ds * ds_dr;
    gradient.person += ds * ds_dr;
    gradient.a += ds * (d - s * b3) / f_norm;  // (I - b3 b3^T) d / |f|
  }
  return active;
}

}  // namespace aerotrack::planning
