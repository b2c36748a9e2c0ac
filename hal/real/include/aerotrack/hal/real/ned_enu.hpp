// Frame conversions between the project's frames and MAVLink's (issue 11 item 4): inside the project
// the world W is ENU (x east, y north, z up) and the body B is FLU (x forward, y left, z up); on the
// wire PX4 and ArduPilot use a local NED frame N (x north, y east, z down) and the body FRD frame F
// (x forward, y right, z down). Both changes of frame are proper rotations by pi:
//   R_WN = [[0 1 0] [1 0 0] [0 0 -1]]  (swap x and y, negate z; its own inverse),
//   R_FB = diag(1, -1, -1)              (negate y and z; its own inverse),
// so q_WB = q_WN * q_NF * q_FB. Yaw: MAVLink's yaw is measured from north, clockwise seen from above;
// ours from east, counter-clockwise: yaw_ned = pi/2 - yaw_enu (wrapped to (-pi, pi]), and a yaw rate
// changes sign. Pure functions, no allocation, thread-safe.
#pragma once

#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

namespace aerotrack::hal::real::ned_enu {

/// R_WN: rotates vectors expressed in local NED into ENU (and, being its own inverse, back).
inline Eigen::Matrix3d rotationEnuNed() {
  Eigen::Matrix3d r;
  r << 0, 1, 0, 1, 0, 0, 0, 0, -1;
  return r;
}

/// R_FB: rotates vectors expressed in body FLU into FRD (and back).
inline Eigen::Matrix3d rotationFrdFlu() {
  return Eigen::Vector3d(1, -1, -1).asDiagonal();
}

/// A position, velocity or acceleration expressed in NED, expressed in ENU; and the way back.
inline Eigen::Vector3d nedToEnu(const Eigen::Vector3d& v_ned) {
  return {v_ned.y(), v_ned.x(), -v_ned.z()};
}
inline Eigen::Vector3d enuToNed(const Eigen::Vector3d& v_enu) {
  return {v_enu.y(), v_enu.x(), -v_enu.z()};
}

/// A vector expressed in body FRD (an angular velocity, a body velocity) expressed in FLU; and back.
inline Eigen::Vector3d frdToFlu(const Eigen::Vector3d& v_frd) {
  return {v_frd.x(), -v_frd.y(), -v_frd.z()};
}
inline Eigen::Vector3d fluToFrd(const Eigen::Vector3d& v_flu) {
  return {v_flu.x(), -v_flu.y(), -v_flu.z()};
}

/// q_NF (FRD body to local NED, MAVLink's ATTITUDE_QUATERNION / ODOMETRY q) to q_WB (FLU to ENU).
inline Eigen::Quaterniond nedFrdToEnuFlu(const Eigen::Quaterniond& q_NF) {
  const Eigen::Matrix3d r_WB = rotationEnuNed() * q_NF.normalized().toRotationMatrix() * rotationFrdFlu();
  return Eigen::Quaterniond(r_WB).normalized();
}
/// q_WB (FLU to ENU) to q_NF (FRD to local NED).
inline Eigen::Quaterniond enuFluToNedFrd(const Eigen::Quaterniond& q_WB) {
  const Eigen::Matrix3d r_NF = rotationEnuNed() * q_WB.normalized().toRotationMatrix() * rotationFrdFlu();
  return Eigen::Quaterniond(r_NF).normalized();
}

/// MAVLink's Euler angles (ATTITUDE: roll, pitch, yaw; the z-y-x sequence, FRD body in NED) to q_NF.
inline Eigen::Quaterniond eulerNedToQuaternion(double roll_rad, double pitch_rad, double yaw_rad) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()));
}

/// An angle wrapped to (-pi, pi].
inline double wrapPi(double angle_rad) {
  double a = std::remainder(angle_rad, 2.0 * std::numbers::pi);  // in [-pi, pi]
  if (a <= -std::numbers::pi) a += 2.0 * std::numbers::pi;
  return a;
}

/// Heading from east counter-clockwise (ENU) to heading from north clockwise (NED), and back: the same
/// formula both ways. Rates only change sign.
inline double yawEnuToNed(double yaw_enu_rad) {
  return wrapPi(std::numbers::pi / 2.0 - yaw_enu_rad);
}
inline double yawNedToEnu(double yaw_ned_rad) {
  return wrapPi(std::numbers::pi / 2.0 - yaw_ned_rad);
}

}  // namespace aerotrack::hal::real::ned_enu
