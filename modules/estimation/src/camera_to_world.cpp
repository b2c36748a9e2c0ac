// Camera to world through the yaw gimbal (see camera_to_world.hpp).
#include "aerotrack/estimation/camera_to_world.hpp"

#include <cmath>
#include <string>
#include <vector>

namespace aerotrack::estimation {

GimbalCameraExtrinsics parseGimbalCameraExtrinsics(const rt::ConfigNode& node) {
  GimbalCameraExtrinsics e;
  const std::vector<double> mount = node.getDoubleList("mount_m", 3, -10.0, 10.0);
  const std::vector<double> offset = node.getDoubleList("camera_in_gimbal_m", 3, -10.0, 10.0);
  const std::vector<double> rpy = node.getDoubleList("camera_in_gimbal_rpy_rad", 3, -7.0, 7.0);
  node.finish();
  e.p_BG_m = Eigen::Vector3d(mount[0], mount[1], mount[2]);
  e.T_GC.linear() =
      (Eigen::AngleAxisd(rpy[2], Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(rpy[1], Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(rpy[0], Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  e.T_GC.translation() = Eigen::Vector3d(offset[0], offset[1], offset[2]);
  return e;
}

Eigen::Matrix3d opticalAxesInCamera() {
  Eigen::Matrix3d R;  // columns: optical x (right) = -y_C, optical y (down) = -z_C, optical z = x_C
  R << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return R;
}

namespace {

/// The level frame's orientation in W: the camera's heading (its forward axis projected on the ground).
Eigen::Matrix3d levelRotation(const Eigen::Isometry3d& T_WC) {
  const Eigen::Vector3d forward_W = T_WC.linear().col(0);
  return Eigen::AngleAxisd(std::atan2(forward_W.y(), forward_W.x()), Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

}  // namespace

Eigen::Isometry3d cameraPoseInWorld(const Eigen::Isometry3d& T_WB, double gimbal_angle_rad,
                                    const GimbalCameraExtrinsics& extrinsics) {
  Eigen::Isometry3d T_BG = Eigen::Isometry3d::Identity();
  T_BG.linear() = Eigen::AngleAxisd(gimbal_angle_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T_BG.translation() = extrinsics.p_BG_m;
  return T_WB * T_BG * extrinsics.T_GC;
}

Eigen::Vector3d cameraToWorld(const Eigen::Vector3d& p_C_m, const Eigen::Isometry3d& T_WC, CameraFrame frame) {
  if (frame == CameraFrame::kCamera) return T_WC * p_C_m;
  return T_WC.translation() + levelRotation(T_WC) * p_C_m;
}

Eigen::Vector3d cameraToWorld(const Eigen::Vector3d& p_C_m, const Eigen::Isometry3d& T_WB, double gimbal_angle_rad,
                              const GimbalCameraExtrinsics& extrinsics, CameraFrame frame) {
  return cameraToWorld(p_C_m, cameraPoseInWorld(T_WB, gimbal_angle_rad, extrinsics), frame);
}

Eigen::Matrix3d levelHomography(const Eigen::Isometry3d& T_WC, const hal::CameraIntrinsics& intrinsics) {
  Eigen::Matrix3d K;
  K << intrinsics.fx_px, 0.0, intrinsics.cx_px, 0.0, intrinsics.fy_px, intrinsics.cy_px, 0.0, 0.0, 1.0;
  // A ray in the camera's optical frame, into W, into the level camera's optical frame.
  const Eigen::Matrix3d R_W_optical = T_WC.linear() * opticalAxesInCamera();
  const Eigen::Matrix3d R_W_level_optical = levelRotation(T_WC) * opticalAxesInCamera();
  return K * (R_W_level_optical.transpose() * R_W_optical) * K.inverse();
}

std::optional<PixelAndDepth> worldToPixel(const Eigen::Vector3d& p_W_m, const Eigen::Isometry3d& T_WC,
                                          const hal::CameraIntrinsics& intrinsics) {
  const Eigen::Vector3d p_optical = opticalAxesInCamera().transpose() * (T_WC.inverse() * p_W_m);
  if (!p_optical.allFinite() || !(p_optical.z() > 0.01)) return std::nullopt;
  return PixelAndDepth{intrinsics.fx_px * p_optical.x() / p_optical.z() + intrinsics.cx_px,
                       intrinsics.fy_px * p_optical.y() / p_optical.z() + intrinsics.cy_px, p_optical.z()};
}

rt::Expected<Eigen::Isometry3d> cameraPoseAt(rt::TimeNs stamp_ns, const hal::OdometryHistory& poses,
                                             const GimbalAngleHistory& gimbal,
                                             const GimbalCameraExtrinsics& extrinsics) {
  const hal::OdometryHistory::Lookup pose = poses.lookup(stamp_ns);
  if (pose.status != rt::HistoryStatus::kOk) {
    return rt::Error{std::string("camera to world: no body pose at t = ") + std::to_string(stamp_ns) +
                     " ns: " + rt::toString(pose.status)};
  }
  const GimbalAngleLookup angle = gimbal.lookup(stamp_ns);
  if (angle.status != rt::HistoryStatus::kOk) {
    return rt::Error{std::string("camera to world: no gimbal angle at t = ") + std::to_string(stamp_ns) +
                     " ns: " + rt::toString(angle.status)};
  }
  return cameraPoseInWorld(pose.value, angle.value, extrinsics);
}

rt::Expected<Eigen::Vector3d> cameraToWorldAt(rt::TimeNs stamp_ns, const Eigen::Vector3d& p_C_m,
                                              const hal::OdometryHistory& poses, const GimbalAngleHistory& gimbal,
                                              const GimbalCameraExtrinsics& extrinsics, CameraFrame frame) {
  if (!p_C_m.allFinite()) return rt::Error{"camera to world: p_C is not finite"};
  const auto T_WC = cameraPoseAt(stamp_ns, poses, gimbal, extrinsics);
  if (!T_WC) return T_WC.error();
  return cameraToWorld(p_C_m, T_WC.value(), frame);
}

}  // namespace aerotrack::estimation
