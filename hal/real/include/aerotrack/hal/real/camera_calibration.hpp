// Camera calibration files (issue 11 items 1 and 2): pinhole intrinsics and Brown-Conrady distortion
// for the gimbal camera and the D435's depth stream, read strictly (rt::ConfigNode: every error is
// one line naming the file, the line and the key). Two formats are accepted:
//   ours:  width_px, height_px, fx_px, fy_px, cx_px, cy_px, distortion: [k1, k2, p1, p2, k3], and for
//          a depth camera optionally serial (string) and depth_scale_m (default 0.001: 1 mm per unit);
//   ROS camera_info (what ROS camera_calibration and kalibr's exporters write): image_width,
//          image_height, camera_matrix {rows: 3, cols: 3, data: [9]}, distortion_model: plumb_bob,
//          distortion_coefficients {rows: 1, cols: 5, data: [5]}, optionally camera_name,
//          rectification_matrix and projection_matrix (monocular: not used).
// The format is told by its keys: a file with image_width is ROS camera_info.
//
// A D435's depth calibration is per camera: calibration_dir/d435_<serial>.yaml, the serial being the
// USB serial number the camera reports (sysfs, see usbSerialOfVideoNode). Thread safety: the functions
// are pure apart from reading files; call them from any thread.
#pragma once

#include <string>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::real {

struct CameraCalibration {
  CameraIntrinsics intrinsics;
  std::string serial;            ///< Our format's optional `serial`, or ROS camera_name; empty if absent.
  double depth_scale_m = 0.001;  ///< Metres per depth unit (depth cameras; D435 default 1 mm).
};

/// Reads a calibration file (either format). Error: one line naming the file, line and key.
rt::Expected<CameraCalibration> loadCameraCalibration(const std::string& path);
/// Parses calibration YAML text; source_name stands for the file in messages.
rt::Expected<CameraCalibration> parseCameraCalibration(const std::string& yaml_text, const std::string& source_name);

/// The per-serial depth calibration file: `<directory>/d435_<serial>.yaml` (not checked for existence).
std::string depthCalibrationPath(const std::string& directory, const std::string& serial);

/// The USB serial number of the camera behind a V4L2 node (`/dev/video2`, or a udev symlink to one),
/// read from `<sysfs_root>/videoN/device/../serial` (the node's USB interface's parent is the USB
/// device). Error: one line naming the device.
rt::Expected<std::string> usbSerialOfVideoNode(const std::string& device_path,
                                               const std::string& sysfs_root = "/sys/class/video4linux");

}  // namespace aerotrack::hal::real
