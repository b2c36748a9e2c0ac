// The `hal.real:` map (issue 11 item 5): the parameters of the drone's drivers, one sub-map per device
// whose backend is "real" (and only those). Relative file paths are taken from the config file's
// folder, so config/drone.yaml finds config/calibration/ wherever the tree is installed.
//
//   real:
//     gimbal_camera: {device, pixel_format: MJPG | YUYV, width_px, height_px, rate_hz, calibration,
//                     frame_timeout_s, reconnect_period_s}
//     depth_camera:  {driver: v4l2 | realsense, device (v4l2: a node or auto; realsense: the camera's serial
//                     or auto), width_px, height_px, rate_hz,
//                     calibration_dir (d435_<serial>.yaml) or calibration_file, mount_B_m [x, y, z],
//                     mount_rpy_deg [roll, pitch, yaw] (0: the optical axis along body x), min_range_m,
//                     max_range_m, frame_timeout_s, reconnect_period_s}
//     gimbal:        {interface (can0), motor_id, reply_timeout_s, watchdog_s, default_max_rate_radps,
//                     direction (+1 | -1), zero_offset_rad}
//     flight_controller: {url (udp://[host]:port | udpout://host:port), system_id, component_id,
//                     target_system, target_component, heartbeat_period_s, setpoint_period_s,
//                     setpoint_stale_s, link_timeout_s, odometry_timeout_s}
#pragma once

#include <string>

#include <yaml-cpp/emitter.h>

#include "aerotrack/hal/real/mavlink_vehicle.hpp"
#include "aerotrack/hal/real/rmd_gimbal.hpp"
#include "aerotrack/hal/real/v4l2_depth_camera.hpp"
#include "aerotrack/hal/real/v4l2_gimbal_camera.hpp"
#include "aerotrack/rt/config_node.hpp"

namespace aerotrack::hal {

struct RealConfig {
  /// gimbal_camera: the calibration file's path; its intrinsics are loaded when the device is built.
  std::string gimbal_camera_calibration;
  real::V4l2GimbalCameraParams gimbal_camera;
  std::string depth_driver = "v4l2";  ///< v4l2 | realsense
  real::V4l2DepthCameraParams depth_camera;
  Eigen::Vector3d depth_mount_B_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d depth_mount_rpy_deg = Eigen::Vector3d::Zero();
  std::string can_interface = "can0";
  real::RmdGimbalParams gimbal;
  real::MavlinkParams flight_controller;
};

/// Which devices of the `hal:` map have the backend "real": their sub-maps are required, others refused.
struct RealDevices {
  bool gimbal_camera = false;
  bool depth_camera = false;
  bool gimbal = false;
  bool flight_controller = false;  ///< odometry or vehicle_link
};

/// Reads `hal.real` (throws rt::ConfigError naming the key; use inside rt::parseConfig).
RealConfig parseRealConfig(const rt::ConfigNode& node, const RealDevices& devices);
void emitYaml(YAML::Emitter& out, const RealConfig& config, const RealDevices& devices);

/// The depth camera's pose in the body from its mount: optical frame (x right, y down, z forward) turned
/// so that, at rpy 0, z is body x; then rolled, pitched (positive: nose down, as a body pitch) and yawed.
Eigen::Isometry3d depthCameraPose(const Eigen::Vector3d& mount_B_m, const Eigen::Vector3d& mount_rpy_deg);

}  // namespace aerotrack::hal
