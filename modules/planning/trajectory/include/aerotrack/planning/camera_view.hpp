// The person in the gimbal camera's vertical field of view, as a cost on a trajectory sample (issue 21).
//
// Why: the gimbal turns about the body's z axis only (paper Sect. IV: one degree of freedom), so the
// camera's optical axis lies in the body's x-y plane and the body's tilt moves the image up and down. A
// quadrotor's body z axis is its thrust direction, b3 = (a + g e3) / |a + g e3|, so braking hard with the
// person close below lifts them out of the bottom of the image: in the forest at 4-5 m/s every first loss
// of sight "out of image" began with the torso below the image's lower edge, 0.9-1.8 m ahead of the camera,
// the body pitched up to 26 degrees (issue 21, `sim --scenario forest --speed 5 --seed 9`).
//
// With the gimbal turned towards the person, a point at unit direction d from the camera appears at the
// vertical angle asin(b3 . d) above the optical axis, so it is in the image while |b3 . d| <= sin(half
// vertical field of view). The torso's lowest point (the hips) and highest (the shoulders), the centre
// minus and plus torso_half_m along W z, are kept within sin(limit_rad) by
//   w (l(-sin(limit) - b3 . d_hips) + l(b3 . d_shoulders - sin(limit))),   l(x) = max(x, 0)^3,
// the same penalty shape as the optimiser's other sampled terms. Gradients (checked against central
// differences in the tests) with respect to the sample's position p, acceleration a and the person's
// torso centre h: with r = point - p, d = r / |r|, f = a + g e3, b3 = f / |f|,
//   d(b3 . d)/dp = -(I - d d^T) b3 / |r|,  d(b3 . d)/dh = (I - d d^T) b3 / |r|,  d(b3 . d)/da = (I - b3 b3^T) d / |f|.
// The camera is taken at the body's origin (its 8 cm offset is small against the 1-3 m to the person).
#pragma once

#include <Eigen/Core>

namespace aerotrack::planning {

/// Standard gravity (m/s^2): the thrust direction of a quadrotor is a + g e3.
inline constexpr double kGravityMps2 = 9.81;

struct CameraViewGradient {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();       ///< d cost / d sample position.
  Eigen::Vector3d a = Eigen::Vector3d::Zero();       ///< d cost / d sample acceleration.
  Eigen::Vector3d person = Eigen::Vector3d::Zero();  ///< d cost / d the person's torso centre.
};

/// Adds the penalty of one sample (see the file comment) to `cost` and its gradient to `gradient`; returns
/// whether it was active. A point within 1 cm of the camera, or a thrust below 1 % of g, adds nothing (the
/// direction is undefined there; the person-distance check and the vehicle limits cover those cases).
/// Pure, allocation-free.
bool addCameraViewTerm(const Eigen::Vector3d& p_W_m, const Eigen::Vector3d& a_W_mps2,
                       const Eigen::Vector3d& torso_centre_W_m, double torso_half_m, double sin_limit, double weight,
                       double& cost, CameraViewGradient& gradient);

}  // namespace aerotrack::planning
