// Camera calibration files: see camera_calibration.hpp.
#include "aerotrack/hal/real/camera_calibration.hpp"

#include <filesystem>
#include <fstream>

#include "aerotrack/rt/config_node.hpp"

namespace aerotrack::hal::real {
namespace {

constexpr int kMaxSidePx = 16384;
constexpr double kMaxFocalPx = 1e6;
constexpr double kMaxDistortion = 1e3;  // rational models can have large k's; plumb_bob rarely > 10

void checkPrincipalPoint(const rt::ConfigNode& node, const std::string& cx_key, const std::string& cy_key,
                         const CameraIntrinsics& k) {
  if (k.cx_px < 0.0 || k.cx_px > k.width_px) node.fail(cx_key, "the principal point lies outside the image width");
  if (k.cy_px < 0.0 || k.cy_px > k.height_px) node.fail(cy_key, "the principal point lies outside the image height");
}

CameraCalibration parseOurs(const rt::ConfigNode& root) {
  CameraCalibration c;
  CameraIntrinsics& k = c.intrinsics;
  k.width_px = root.getInt("width_px", 1, kMaxSidePx);
  k.height_px = root.getInt("height_px", 1, kMaxSidePx);
  k.fx_px = root.getDouble("fx_px", 1e-3, kMaxFocalPx);
  k.fy_px = root.getDouble("fy_px", 1e-3, kMaxFocalPx);
  k.cx_px = root.getDouble("cx_px", 0.0, kMaxSidePx);
  k.cy_px = root.getDouble("cy_px", 0.0, kMaxSidePx);
  const std::vector<double> d = root.getDoubleList("distortion", 5, -kMaxDistortion, kMaxDistortion);
  for (std::size_t i = 0; i < 5; ++i) k.distortion.at(i) = d[i];
  c.serial = root.getStringOr("serial", "");
  c.depth_scale_m = root.getDoubleOr("depth_scale_m", 0.001, 1e-6, 1.0);
  checkPrincipalPoint(root, "cx_px", "cy_px", k);
  root.finish();
  return c;
}

/// A ROS matrix {rows, cols, data}: checks the shape and returns data.
std::vector<double> rosMatrix(const rt::ConfigNode& parent, const std::string& key, int rows, int cols, double min,
                              double max) {
  const rt::ConfigNode m = parent.child(key);
  m.getInt("rows", rows, rows);
  m.getInt("cols", cols, cols);
  std::vector<double> data =
      m.getDoubleList("data", static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols), min, max);
  m.finish();
  return data;
}

CameraCalibration parseRos(const rt::ConfigNode& root) {
  CameraCalibration c;
  CameraIntrinsics& k = c.intrinsics;
  k.width_px = root.getInt("image_width", 1, kMaxSidePx);
  k.height_px = root.getInt("image_height", 1, kMaxSidePx);
  c.serial = root.getStringOr("camera_name", "");
  const std::vector<double> m = rosMatrix(root, "camera_matrix", 3, 3, -kMaxFocalPx, kMaxFocalPx);
  // Row-major [fx s cx; 0 fy cy; 0 0 1]; a skewed or non-pinhole matrix has no CameraIntrinsics.
  if (m[0] <= 0.0 || m[4] <= 0.0) root.fail("camera_matrix", "fx and fy (data[0], data[4]) must be positive");
  if (m[1] != 0.0 || m[3] != 0.0 || m[6] != 0.0 || m[7] != 0.0 || m[8] != 1.0)
    root.fail("camera_matrix", "expected [fx, 0, cx, 0, fy, cy, 0, 0, 1] (no skew)");
  k.fx_px = m[0];
  k.cx_px = m[2];
  k.fy_px = m[4];
  k.cy_px = m[5];
  root.getEnum("distortion_model", {"plumb_bob"});
  const std::vector<double> d = rosMatrix(root, "distortion_coefficients", 1, 5, -kMaxDistortion, kMaxDistortion);
  for (std::size_t i = 0; i < 5; ++i) k.distortion.at(i) = d[i];
  // Monocular files carry these too; for a single camera they are identity and a copy of K.
  if (root.has("rectification_matrix")) rosMatrix(root, "rectification_matrix", 3, 3, -kMaxFocalPx, kMaxFocalPx);
  if (root.has("projection_matrix")) rosMatrix(root, "projection_matrix", 3, 4, -kMaxFocalPx, kMaxFocalPx);
  checkPrincipalPoint(root, "camera_matrix", "camera_matrix", k);
  root.finish();
  return c;
}

rt::Expected<CameraCalibration> parseCalibrationRoot(const rt::Expected<rt::ConfigNode>& root) {
  if (!root) return root.error();
  const rt::ConfigNode& node = *root;
  return rt::parseConfig<CameraCalibration>(
      [&node] { return node.has("image_width") ? parseRos(node) : parseOurs(node); });
}

}  // namespace

rt::Expected<CameraCalibration> parseCameraCalibration(const std::string& yaml_text, const std::string& source_name) {
  return parseCalibrationRoot(rt::ConfigNode::fromString(yaml_text, source_name));
}

rt::Expected<CameraCalibration> loadCameraCalibration(const std::string& path) {
  return parseCalibrationRoot(rt::ConfigNode::loadFile(path));
}

std::string depthCalibrationPath(const std::string& directory, const std::string& serial) {
  return (std::filesystem::path(directory) / ("d435_" + serial + ".yaml")).string();
}

rt::Expected<std::string> usbSerialOfVideoNode(const std::string& device_path, const std::string& sysfs_root) {
  std::error_code ec;
  const std::filesystem::path node = std::filesystem::canonical(device_path, ec);  // follows udev symlinks
  if (ec) return rt::Error{device_path + ": cannot resolve the device node: " + ec.message()};
  const std::filesystem::path serial_file =
      std::filesystem::path(sysfs_root) / node.filename() / "device" / ".." / "serial";
  std::ifstream in(serial_file);
  if (!in) return rt::Error{device_path + ": no USB serial number (" + serial_file.string() + " is unreadable)"};
  std::string serial;
  std::getline(in, serial);
  while (!serial.empty() && (serial.back() == ' ' || serial.back() == '\r' || serial.back() == '\t')) serial.pop_back();
  if (serial.empty()) return rt::Error{device_path + ": the USB serial number is empty (" + serial_file.string() + ")"};
  return serial;
}

}  // namespace aerotrack::hal::real
