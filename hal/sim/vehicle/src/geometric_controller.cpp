// Geometric tracking controller (position loop with flatness and drag feed-forward, tilt-first
// attitude loop on body rates): see geometric_controller.hpp for the laws and references.
#include "aerotrack/hal/sim/geometric_controller.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace aerotrack::hal::sim {

rt::Expected<GeometricController> GeometricController::create(const GeometricControllerParams& params,
                                                              const QuadrotorParams& vehicle) {
  if (!(params.position_gain_per_s2.allFinite() && params.position_gain_per_s2.minCoeff() >= 0.0))
    return rt::Error{"geometric controller: position_gain_per_s2 must be >= 0 on every axis"};
  if (!(params.velocity_gain_per_s.allFinite() && params.velocity_gain_per_s.minCoeff() >= 0.0))
    return rt::Error{"geometric controller: velocity_gain_per_s must be >= 0 on every axis"};
  if (!(params.attitude_gain_per_s.allFinite() && params.attitude_gain_per_s.minCoeff() > 0.0))
    return rt::Error{"geometric controller: attitude_gain_per_s must be > 0 on every axis"};
  if (!(params.max_tilt_rad > 0.0 && params.max_tilt_rad < 0.5 * M_PI))
    return rt::Error{"geometric controller: max_tilt_rad must be in (0, pi/2)"};
  if (!(std::isfinite(vehicle.mass_kg) && vehicle.mass_kg > 0.0 && std::isfinite(vehicle.gravity_mps2) &&
        std::isfinite(vehicle.max_thrust_n) && vehicle.max_thrust_n > vehicle.min_thrust_n &&
        vehicle.max_body_rate_radps.allFinite() && vehicle.max_body_rate_radps.minCoeff() > 0.0 &&
        vehicle.drag_B_per_s.allFinite()))
    return rt::Error{"geometric controller: invalid vehicle parameters (see Quadrotor::create)"};
  return GeometricController(params, vehicle);
}

GeometricController::GeometricController(const GeometricControllerParams& params, const QuadrotorParams& vehicle)
    : params_(params),
      vehicle_(vehicle),
      tan_max_tilt_(std::tan(params.max_tilt_rad)),
      max_thrust_accel_mps2_(vehicle.max_thrust_n / vehicle.mass_kg) {}

AttitudeReference GeometricController::reference(const hal::Setpoint& setpoint, const QuadrotorState& estimate) const {
  const Eigen::Matrix3d& R = estimate.R_WB;
  Eigen::Vector3d t = params_.position_gain_per_s2.cwiseProduct(setpoint.p_W_m - estimate.p_W_m) +
                      params_.velocity_gain_per_s.cwiseProduct(setpoint.v_W_mps - estimate.v_W_mps) + setpoint.a_W_mps2;
  t.z() += vehicle_.gravity_mps2;
  if (params_.compensate_drag) t += R * vehicle_.drag_B_per_s.cwiseProduct(R.transpose() * setpoint.v_W_mps);

  // Limits, altitude first: vertical floor, tilt, then total thrust at the expense of the horizontal.
  const double a_max = max_thrust_accel_mps2_;
  t.z() = std::clamp(t.z(), std::min(kMinVerticalAccelMps2, a_max), a_max);
  double horizontal = std::hypot(t.x(), t.y());
  double horizontal_max = t.z() * tan_max_tilt_;
  horizontal_max = std::min(horizontal_max, std::sqrt(std::max(0.0, a_max * a_max - t.z() * t.z())));
  if (horizontal > horizontal_max) {
    const double scale = horizontal_max / horizontal;
    t.x() *= scale;
    t.y() *= scale;
  }

  AttitudeReference ref;
  ref.thrust_accel_W_mps2 = t;
  const Eigen::Vector3d z_B = t.normalized();
  const double yaw_c = std::cos(setpoint.yaw_rad);
  const double yaw_s = std::sin(setpoint.yaw_rad);
  const Eigen::Vector3d x_C(yaw_c, yaw_s, 0.0);
  const Eigen::Vector3d y_C(-yaw_s, yaw_c, 0.0);
  const Eigen::Vector3d y_B_unnormalized = z_B.cross(x_C);
  const double y_norm = y_B_unnormalized.norm();  // >= cos(max_tilt) > 0
  const Eigen::Vector3d y_B = y_B_unnormalized / y_norm;
  ref.R_WBd.col(0) = y_B.cross(z_B);
  ref.R_WBd.col(1) = y_B;
  ref.R_WBd.col(2) = z_B;
  ref.w_Bd_radps = Eigen::Vector3d(0.0, 0.0, setpoint.yaw_rate_radps * y_C.dot(y_B) / y_norm);
  return ref;
}

QuadrotorCommand GeometricController::update(const hal::Setpoint& setpoint, const QuadrotorState& estimate) const {
  const AttitudeReference ref = reference(setpoint, estimate);
  const Eigen::Matrix3d& R = estimate.R_WB;
  const Eigen::Matrix3d R_error = R.transpose() * ref.R_WBd;  // desired attitude seen from the body

  // Attitude error as q_e = q_xy * q_z (tilt about a body xy axis, then a turn about z), w >= 0.
  Eigen::Quaterniond q_e(R_error);
  if (q_e.w() < 0.0) q_e.coeffs() = -q_e.coeffs();
  const double qw = q_e.w(), qx = q_e.x(), qy = q_e.y(), qz = q_e.z();
  const double n = std::sqrt(qw * qw + qz * qz);
  Eigen::Vector3d rate_B = Eigen::Vector3d::Zero();
  if (n > 1e-9) {
    const double tilt_x = (qw * qx - qy * qz) / n;
    const double tilt_y = (qw * qy + qx * qz) / n;
    const double tilt_sin_half = std::hypot(tilt_x, tilt_y);
    // angle / sin(angle/2) with angle = 2 atan2(sin_half, cos_half), cos_half = n
    const double per_component = tilt_sin_half > 1e-9 ? 2.0 * std::atan2(tilt_sin_half, n) / tilt_sin_half : 2.0 / n;
    rate_B.x() = per_component * tilt_x;
    rate_B.y() = per_component * tilt_y;
    rate_B.z() = 2.0 * std::atan2(qz, qw);  // yaw angle, in [-pi, pi] since qw >= 0
  } else {
    // A tilt error of pi (q_e = (0, x, y, 0)): tilt about (x, y), the yaw part is undefined.
    const double axis_norm = std::max(std::hypot(qx, qy), 1e-12);
    rate_B.x() = M_PI * qx / axis_norm;
    rate_B.y() = M_PI * qy / axis_norm;
  }
  Eigen::Vector3d w_cmd = params_.attitude_gain_per_s.cwiseProduct(rate_B) + R_error * ref.w_Bd_radps;

  // Rate limits: x/y scaled together (tilt direction kept), z clipped.
  const Eigen::Vector3d& limit = vehicle_.max_body_rate_radps;
  double scale = 1.0;
  for (int i = 0; i < 2; ++i)
    if (std::abs(w_cmd[i]) > limit[i]) scale = std::min(scale, limit[i] / std::abs(w_cmd[i]));
  w_cmd.x() *= scale;
  w_cmd.y() *= scale;
  for (int i = 0; i < 3; ++i) w_cmd[i] = std::clamp(w_cmd[i], -limit[i], limit[i]);  // z, and x/y rounding

  QuadrotorCommand command;
  command.w_B_radps = w_cmd;
  command.thrust_n = std::clamp(vehicle_.mass_kg * ref.thrust_accel_W_mps2.dot(R.col(2)), vehicle_.min_thrust_n,
                                vehicle_.max_thrust_n);
  return command;
}

}  // namespace aerotrack::hal::sim
