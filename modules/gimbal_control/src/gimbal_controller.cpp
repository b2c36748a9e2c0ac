// Gimbal control: see gimbal_controller.hpp.
#include "aerotrack/gimbal_control/gimbal_controller.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace aerotrack::gimbal_control {
namespace {

double wrapPi(double a) {
  return std::remainder(a, 2.0 * M_PI);
}

}  // namespace

std::string_view toString(GimbalMode mode) {
  switch (mode) {
    case GimbalMode::kIdle:
      return "idle";
    case GimbalMode::kTrack:
      return "track";
    case GimbalMode::kSearch:
      return "search";
  }
  return "unknown";
}

rt::Status validate(const GimbalControlParams& p) {
  if (!(p.kp_per_s > 0.0)) return rt::Error{"kp_per_s must be > 0"};
  if (!(p.ki_per_s2 >= 0.0)) return rt::Error{"ki_per_s2 must be >= 0"};
  if (!(p.integral_limit_rad_s >= 0.0)) return rt::Error{"integral_limit_rad_s must be >= 0"};
  if (!(p.integral_zone_rad > 0.0)) return rt::Error{"integral_zone_rad must be > 0"};
  if (!(p.max_rate_radps > 0.0)) return rt::Error{"max_rate_radps must be > 0"};
  if (!(p.sweep_rate_radps > 0.0 && p.sweep_rate_radps <= p.max_rate_radps))
    return rt::Error{"sweep_rate_radps must be in (0, max_rate_radps]"};
  if (!(p.max_estimate_age_s > 0.0)) return rt::Error{"max_estimate_age_s must be > 0"};
  if (!(p.look_at_prediction_s >= 0.0)) return rt::Error{"look_at_prediction_s must be >= 0"};
  if (!(p.max_bearing_sigma_rad > 0.0)) return rt::Error{"max_bearing_sigma_rad must be > 0"};
  return rt::ok();
}

GimbalControlParams parseGimbalControlParams(const rt::ConfigNode& node) {
  GimbalControlParams p;
  p.kp_per_s = node.getDouble("kp_per_s", 0.01, 100.0);
  p.ki_per_s2 = node.getDouble("ki_per_s2", 0.0, 100.0);
  p.integral_limit_rad_s = node.getDouble("integral_limit_rad_s", 0.0, 10.0);
  p.integral_zone_rad = node.getDouble("integral_zone_rad", 1e-3, 4.0);
  p.max_rate_radps = node.getDouble("max_rate_radps", 0.1, 50.0);
  p.sweep_rate_radps = node.getDouble("sweep_rate_radps", 0.1, 50.0);
  p.feed_forward = node.getBool("feed_forward");
  p.max_estimate_age_s = node.getDouble("max_estimate_age_s", 0.01, 10.0);
  p.look_at_prediction_s = node.getDouble("look_at_prediction_s", 0.0, 60.0);
  p.max_bearing_sigma_rad = node.getDouble("max_bearing_sigma_rad", 0.01, 3.2);
  if (p.sweep_rate_radps > p.max_rate_radps) node.fail("sweep_rate_radps", "must not exceed max_rate_radps");
  node.finish();
  return p;
}

double horizontalBearingError(const Eigen::Isometry3d& T_WC, const Eigen::Vector3d& p_W_m) {
  const Eigen::Vector3d d = p_W_m - T_WC.translation();
  const Eigen::Vector3d axis = T_WC.linear().col(0);  // C is FLU: x is the optical axis
  return wrapPi(std::atan2(d.y(), d.x()) - std::atan2(axis.y(), axis.x()));
}

double bearingSigmaRad(const Eigen::Isometry3d& T_WC, const estimation::TargetEstimate& target) {
  const Eigen::Vector2d d = (target.p_WT_m - T_WC.translation()).head<2>();
  const double range_m = d.norm();
  if (range_m < 1e-6) return M_PI;
  const Eigen::Vector2d across(-d.y() / range_m, d.x() / range_m);
  const double variance_m2 = across.dot(target.covariance.topLeftCorner<2, 2>() * across);
  return std::atan2(std::sqrt(std::max(variance_m2, 0.0)), range_m);
}

GimbalOutput GimbalController::update(const GimbalInputs& in) {
  GimbalOutput out;
  out.command.stamp_ns = in.now_ns;
  out.command.mode = hal::GimbalCommand::Mode::kRate;
  const double dt_s = last_ns_ >= 0 ? std::clamp(rt::nsToSeconds(in.now_ns - last_ns_), 0.0, 0.1) : 0.0;
  last_ns_ = in.now_ns;
  if (in.gimbal == nullptr || in.odometry == nullptr) {
    integral_rad_s_ = 0.0;
    return out;
  }
  Eigen::Isometry3d T_WB = Eigen::Isometry3d::Identity();
  T_WB.linear() = in.odometry->q_WB.toRotationMatrix();
  T_WB.translation() = in.odometry->p_WB_m;
  const Eigen::Isometry3d T_WC = estimation::cameraPoseInWorld(T_WB, in.gimbal->angle_rad, extrinsics_);
  // The body's yaw rate in W (the gimbal turns about body z; for a near-level body that is W z).
  const double body_yaw_rate_radps = (T_WB.linear() * in.odometry->w_WB_B_radps).z();

  const estimation::TargetEstimate* target = in.target;
  const bool fresh = target != nullptr && target->initialised &&
                     rt::nsToSeconds(in.now_ns - target->stamp_ns) <= params_.max_estimate_age_s;
  // Lost (or relocating) recently, with a prediction still sharp enough to put the person in the image:
  // it is the best place to look.
  const bool recently_seen = fresh &&
                             rt::nsToSeconds(in.now_ns - target->last_accepted_ns) <= params_.look_at_prediction_s &&
                             bearingSigmaRad(T_WC, *target) <= params_.max_bearing_sigma_rad;
  const bool live = fresh && !target->lost && !in.search_requested;
  if (!live && !recently_seen) {
    // Sweep: a constant rate over the ground, whatever the body does.
    out.mode = GimbalMode::kSearch;
    integral_rad_s_ = 0.0;
    const double ff = params_.feed_forward ? -body_yaw_rate_radps : 0.0;
    out.command.rate_radps =
        std::clamp(sweep_direction_ * params_.sweep_rate_radps + ff, -params_.max_rate_radps, params_.max_rate_radps);
    return out;
  }

  out.mode = GimbalMode::kTrack;
  const double ahead_s = rt::nsToSeconds(in.now_ns - target->stamp_ns);
  const Eigen::Vector3d p_WT = target->p_WT_m + ahead_s * target->v_WT_mps;
  const double error = horizontalBearingError(T_WC, p_WT);
  out.error_rad = error;
  sweep_direction_ = error >= 0.0 ? 1.0 : -1.0;  // if lost, look first where the person was going out of view

  double ff = 0.0;
  if (params_.feed_forward) {
    // Bearing rate of the person seen from the camera: (d x v_rel)_z / |d_xy|^2.
    const Eigen::Vector3d d = p_WT - T_WC.translation();
    const Eigen::Vector3d v_rel = target->v_WT_mps - in.odometry->v_WB_mps;
    const double range2 = d.x() * d.x() + d.y() * d.y();
    const double bearing_rate = range2 > 0.25 ? (d.x() * v_rel.y() - d.y() * v_rel.x()) / range2 : 0.0;
    ff = bearing_rate - body_yaw_rate_radps;
  }
  const double unsaturated = params_.kp_per_s * error + params_.ki_per_s2 * integral_rad_s_ + ff;
  const double command = std::clamp(unsaturated, -params_.max_rate_radps, params_.max_rate_radps);
  // Conditional integration: not while saturated in the direction the error pushes.
  const bool saturated_same_way = command != unsaturated && (unsaturated > 0.0) == (error > 0.0);
  if (!saturated_same_way && std::abs(error) < params_.integral_zone_rad) {
    integral_rad_s_ =
        std::clamp(integral_rad_s_ + error * dt_s, -params_.integral_limit_rad_s, params_.integral_limit_rad_s);
  }
  out.command.rate_radps = command;
  return out;
}

}  // namespace aerotrack::gimbal_control
