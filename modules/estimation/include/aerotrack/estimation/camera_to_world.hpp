// Camera to world (issue 6, item 4; the paper's Sect. IV-B: "p_C is converted to p_W through
// coordinate transformation"). The localization gives the person's position p_C in the gimbal
// camera's frame C (x forward along the optical axis, y left, z up: FLU). The camera sits on a
// yaw gimbal: the gimbal frame G is the body frame B turned by the encoder angle psi about body
// z (unwrapped, multi-turn, from body x), with its origin at the gimbal's rotation centre p_BG
// (fixed in B); C is fixed in G by T_GC. So
//   T_WC = T_WB * Translation(p_BG) * Rz(psi) * T_GC,    p_WT = T_WC * p_C,
// with T_WB and psi taken at the image's capture time. This matches the simulator exactly
// (hal/sim Simulation::cameraPose: R_WC_optical = R_WB Rz(psi) R_FLU_optical, camera centre
// p_WB + R_WB mount_B_m): there p_BG = gimbal_camera.mount_m and T_GC = identity, and the
// simulator's optical frame (x right, y down, z forward) is C turned by opticalAxesInCamera().
#pragma once

#include <optional>

#include <Eigen/Geometry>

#include "aerotrack/estimation/gimbal_history.hpp"
#include "aerotrack/hal/odometry_history.hpp"
#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/time.hpp"

namespace aerotrack::estimation {

struct GimbalCameraExtrinsics {
  Eigen::Vector3d p_BG_m = Eigen::Vector3d::Zero();        ///< Gimbal rotation centre in B (sim: mount_m).
  Eigen::Isometry3d T_GC = Eigen::Isometry3d::Identity();  ///< Camera C (FLU) in the gimbal frame G.
};

/// Reads `{mount_m: [x, y, z], camera_in_gimbal_m: [x, y, z], camera_in_gimbal_rpy_rad: [r, p, y]}`
/// (all required; rpy: roll about x, then pitch about y, then yaw about z, R = Rz(yaw) Ry(pitch)
/// Rx(roll)). Throws rt::ConfigError naming the key (use inside rt::parseConfig).
GimbalCameraExtrinsics parseGimbalCameraExtrinsics(const rt::ConfigNode& node);

/// The rotation from the optical frame (OpenCV: x right, y down, z forward) to C (FLU):
/// R_C_optical, so that T_WC_optical = T_WC * R_C_optical. Pure.
Eigen::Matrix3d opticalAxesInCamera();

/// T_WC (C the FLU camera frame) for the body pose T_WB and the unwrapped gimbal angle. Pure,
/// reentrant, allocation-free.
Eigen::Isometry3d cameraPoseInWorld(const Eigen::Isometry3d& T_WB, double gimbal_angle_rad,
                                    const GimbalCameraExtrinsics& extrinsics);

/// Which frame p_C is given in. kCamera: the camera's own frame C, tilted with the body. kLevel: a
/// gravity-aligned frame at the camera with the camera's heading -- the frame of a localization
/// regression fitted on a level camera (the paper's x_c, y_c, z_c): reading its output in the
/// tilted frame would swing the person by the drone's pitch (10 degrees of pitch moves a person
/// 2.5 m ahead and 1.7 m below by 0.3 m).
enum class CameraFrame : std::uint8_t { kCamera, kLevel };

/// p_WT = T_WC p_C (kCamera), or the camera's position plus p_C turned by the camera's heading
/// (kLevel), in metres. Pure, reentrant, allocation-free.
Eigen::Vector3d cameraToWorld(const Eigen::Vector3d& p_C_m, const Eigen::Isometry3d& T_WC, CameraFrame frame);

/// The same, with T_WC = cameraPoseInWorld(T_WB, gimbal_angle_rad, extrinsics).
Eigen::Vector3d cameraToWorld(const Eigen::Vector3d& p_C_m, const Eigen::Isometry3d& T_WB, double gimbal_angle_rad,
                              const GimbalCameraExtrinsics& extrinsics, CameraFrame frame = CameraFrame::kCamera);

/// T_WC with T_WB and the gimbal angle interpolated from the histories at stamp_ns. Error (saying which
/// history and why) if either lookup fails. Allocation: only for an error.
rt::Expected<Eigen::Isometry3d> cameraPoseAt(rt::TimeNs stamp_ns, const hal::OdometryHistory& poses,
                                             const GimbalAngleHistory& gimbal,
                                             const GimbalCameraExtrinsics& extrinsics);

/// The homography H = K R K^-1 that takes a pixel of the image of the camera at T_WC to the pixel where a
/// level camera (kLevel: the same centre and heading, no roll or pitch) with the same intrinsics sees the
/// same ray (homogeneous; a third coordinate <= 0 is a ray the level camera has behind it). Why: the
/// localization regression was fitted on level views (hal/sim calibration_views.hpp), and a drone tilted
/// 30 degrees while braking turns and moves the person in its image: the regression read there put the
/// person 0.8 m off (crowd, seed 2, 21.1 s), where the level camera's image gives the fitted reading.
/// Lens distortion is not modelled (the intrinsics' distortion is ignored). Pure, allocation-free.
Eigen::Matrix3d levelHomography(const Eigen::Isometry3d& T_WC, const hal::CameraIntrinsics& intrinsics);

/// Where the camera at T_WC (C the FLU frame) with these intrinsics sees the world point p_W_m: the pixel (u, v)
/// and the depth along the optical axis (metres); nothing for a point not in front of the camera (depth <= 0.01 m)
/// or not finite. A pinhole without distortion, as levelHomography. The inverse of the ray a depth lookup casts
/// through a pixel (TargetTask::rangeByDepth). Pure, allocation-free.
struct PixelAndDepth {
  double u_px = 0.0;
  double v_px = 0.0;
  double depth_m = 0.0;
};
std::optional<PixelAndDepth> worldToPixel(const Eigen::Vector3d& p_W_m, const Eigen::Isometry3d& T_WC,
                                          const hal::CameraIntrinsics& intrinsics);

/// cameraToWorld with T_WB and the gimbal angle interpolated from the histories at the image's
/// capture time stamp_ns. Error (saying which history and why) if either lookup fails or p_C is
/// not finite. Thread safety: as the histories' const lookups. Allocation: only for an error.
rt::Expected<Eigen::Vector3d> cameraToWorldAt(rt::TimeNs stamp_ns, const Eigen::Vector3d& p_C_m,
                                              const hal::OdometryHistory& poses, const GimbalAngleHistory& gimbal,
                                              const GimbalCameraExtrinsics& extrinsics,
                                              CameraFrame frame = CameraFrame::kCamera);

}  // namespace aerotrack::estimation
