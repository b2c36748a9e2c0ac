// The vehicle's recent odometry, to look up the body pose T_WB at the capture time of a sensor's
// data: the mapper at a depth frame's time (issue 4), the target estimator at an image's time (issue 6,
// the paper's Sect. IV-B). One instance of rt::StampedHistory (its contract: strictly increasing
// stamps, fixed capacity allocated once, no extrapolation) for hal::OdometrySample, here beside the
// message so that every module that needs it shares this one and none depends on another for it.
// Interpolation between the two samples around t: position linearly, orientation by spherical linear
// interpolation (Eigen's slerp, shortest arc). A sample with a non-finite position or orientation, or a
// zero quaternion, is refused; q_WB is stored normalised.
#pragma once

#include <string_view>

#include <Eigen/Geometry>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/stamped_history.hpp"

namespace aerotrack::hal {

/// rt::StampedHistory traits of odometry: T_WB (body in world; W ENU, B FLU) from OdometrySample.
struct OdometryPoseTraits {
  using Sample = OdometrySample;
  using Value = Eigen::Isometry3d;
  static constexpr std::string_view kName = "pose history";

  /// Refuses a non-finite p_WB_m or q_WB and a zero quaternion; normalises q_WB.
  static bool admit(OdometrySample& s) {
    const double q_norm = s.q_WB.norm();
    if (!s.p_WB_m.allFinite() || !s.q_WB.coeffs().allFinite() || !(q_norm > 1e-9)) return false;
    s.q_WB.coeffs() /= q_norm;
    return true;
  }
  static Eigen::Isometry3d value(const OdometrySample& s) {
    Eigen::Isometry3d T_WB = Eigen::Isometry3d::Identity();
    T_WB.linear() = s.q_WB.toRotationMatrix();
    T_WB.translation() = s.p_WB_m;
    return T_WB;
  }
  /// Position a + alpha (b - a); rotation slerp(q_a, q_b, alpha).
  static Eigen::Isometry3d interpolate(const OdometrySample& a, const OdometrySample& b, double alpha) {
    Eigen::Isometry3d T_WB = Eigen::Isometry3d::Identity();
    T_WB.linear() = a.q_WB.slerp(alpha, b.q_WB).toRotationMatrix();
    T_WB.translation() = a.p_WB_m + alpha * (b.p_WB_m - a.p_WB_m);
    return T_WB;
  }
  static Eigen::Isometry3d none() { return Eigen::Isometry3d::Identity(); }
};

/// Body poses by time. Thread safety: none (one owner). Allocation: once, in create().
using OdometryHistory = rt::StampedHistory<OdometryPoseTraits>;

}  // namespace aerotrack::hal
