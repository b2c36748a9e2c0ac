// Geometric tracking controller for the simulated quadrotor: turns a full-state setpoint
// (hal::Setpoint: position, velocity, acceleration, yaw, yaw rate) into a collective thrust and a
// body-rate command for the vehicle's rate loop, as a flight controller's position and attitude
// loops do.
//
// Position loop (Lee, Leok & McClamroch 2010, "Geometric tracking control of a quadrotor UAV on
// SE(3)"; feed-forward by differential flatness as in Mellinger & Kumar 2011 and Faessler, Franchi
// & Scaramuzza 2018, "Differential flatness of quadrotor dynamics subject to rotor drag"):
//   t = Kp (p_ref - p) + Kd (v_ref - v) + a_ref + g e3 + R D R^T v_ref     (specific thrust, W)
// the last term cancelling the drag the vehicle feels at the reference velocity (current attitude R).
// Limits, altitude first: t_z >= kMinVerticalAccelMps2; the horizontal part is shortened so the tilt
// stays within max_tilt_rad; if |t| exceeds max_thrust_n / m the horizontal part is shortened again
// (if t_z alone exceeds it: straight up at full thrust).
// Desired attitude: z_Bd = t / |t|, y_Bd = z_Bd x x_C / |z_Bd x x_C|, x_Bd = y_Bd x z_Bd with
// x_C = (cos yaw, sin yaw, 0). Feed-forward body rate (no jerk in the setpoint, so only yaw):
//   w_d = (0, 0, yaw_rate (y_C . y_Bd) / |z_Bd x x_C|)  in B_d, the exact rate of this R_d when
//   z_Bd is constant (Mellinger's yaw_rate (z_W . z_Bd) is its small-tilt approximation).
// Collective thrust: m t . (R e3), the projection onto the current body z axis (Lee et al.).
// Attitude loop, tilt first (Brescianini & D'Andrea 2018, "Tilt-prioritized quadrocopter attitude
// control"): the error q_e = q(R^T R_d), w >= 0 (short way), is split as q_e = q_xy * q_z, a tilt
// about an axis in the body xy plane followed by a turn about z. The rate command is
//   w_c = K_att (tilt angle * tilt axis + yaw angle * e3) + R^T R_d w_d,
// then the x/y part is scaled together to fit the rate limits (keeping its direction) and z clipped.
// Yaw error is the short way round (through +-pi when shorter), proportional to the angle.
//
// Stateless: update() is const, pure and allocation-free, so one object may be shared by threads.
#pragma once

#include <Eigen/Core>

#include "aerotrack/hal/sim/quadrotor.hpp"
#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::sim {

struct GeometricControllerParams {
  /// Acceleration per metre of position error, per world axis (x, y, z), 1/s^2.
  Eigen::Vector3d position_gain_per_s2 = Eigen::Vector3d(6.0, 6.0, 8.0);
  /// Acceleration per m/s of velocity error, per world axis, 1/s.
  Eigen::Vector3d velocity_gain_per_s = Eigen::Vector3d(4.0, 4.0, 5.0);
  /// Body-rate command per radian of attitude error (roll, pitch, yaw), 1/s. Must stay well below
  /// 1 / body_rate_time_constant_s (damping of the rate-loop + attitude-loop pair: 1/(2 sqrt(k tau))).
  Eigen::Vector3d attitude_gain_per_s = Eigen::Vector3d(10.0, 10.0, 5.0);
  /// Largest tilt (angle between body z and world z) the controller asks for, rad, in (0, pi/2).
  double max_tilt_rad = 0.6;
  /// Add R D R^T v_ref to the thrust (drag feed-forward with the vehicle model's drag).
  bool compensate_drag = true;
};

/// The desired attitude and what led to it (for logs and tests).
struct AttitudeReference {
  Eigen::Vector3d thrust_accel_W_mps2 = Eigen::Vector3d::Zero();  ///< Limited specific thrust t, W.
  Eigen::Matrix3d R_WBd = Eigen::Matrix3d::Identity();            ///< Desired attitude.
  Eigen::Vector3d w_Bd_radps = Eigen::Vector3d::Zero();           ///< Feed-forward rate of R_WBd, in B_d.
};

class GeometricController {
 public:
  /// The smallest vertical specific thrust asked for, m/s^2: keeps the attitude defined when the
  /// setpoint asks to fall faster than gravity.
  static constexpr double kMinVerticalAccelMps2 = 0.5;

  /// Validates the gains (position and velocity >= 0, attitude > 0, finite) and max_tilt_rad in
  /// (0, pi/2). `vehicle` is the controller's model of the vehicle: mass, gravity, drag and limits.
  /// Allocates only for an error message.
  static rt::Expected<GeometricController> create(const GeometricControllerParams& params,
                                                  const QuadrotorParams& vehicle);

  /// Thrust and body-rate command for the setpoint (W frame, SI units; stamp_ns unused) given the
  /// vehicle's state estimate (only p, v, R_WB are read). Outputs are within the vehicle's limits.
  /// Pure: const, allocation-free, thread-safe.
  QuadrotorCommand update(const hal::Setpoint& setpoint, const QuadrotorState& estimate) const;

  /// The position loop alone: desired attitude and feed-forward rate. Pure, as update().
  AttitudeReference reference(const hal::Setpoint& setpoint, const QuadrotorState& estimate) const;

  const GeometricControllerParams& params() const { return params_; }

 private:
  GeometricController(const GeometricControllerParams& params, const QuadrotorParams& vehicle);

  GeometricControllerParams params_;
  QuadrotorParams vehicle_;
  double tan_max_tilt_ = 0.0;
  double max_thrust_accel_mps2_ = 0.0;
};

}  // namespace aerotrack::hal::sim
