// The `hal.real:` map: see real_config.hpp.
#include "aerotrack/hal/real_config.hpp"

#include <filesystem>
#include <initializer_list>
#include <numbers>

namespace aerotrack::hal {
namespace {

constexpr double kRadPerDeg = std::numbers::pi / 180.0;

/// A relative path in a config file means: beside the config file.
std::string besideConfig(const rt::ConfigNode& node, const std::string& path) {
  if (path.empty() || std::filesystem::path(path).is_absolute()) return path;
  return (std::filesystem::path(node.sourceName()).parent_path() / path).lexically_normal().string();
}

Eigen::Vector3d vector3(const rt::ConfigNode& node, const char* key, double min, double max) {
  const std::vector<double> v = node.getDoubleList(key, 3, min, max);
  return {v[0], v[1], v[2]};
}

/// Fails if validate() refuses what was read (the drivers' own checks, across several keys), on the
/// first of keys that its message names (else the first of keys), so the error points into the file.
void check(const rt::ConfigNode& node, const rt::Status& valid, std::initializer_list<const char*> keys) {
  if (valid) return;
  const std::string& message = valid.error().message;
  const char* key = *keys.begin();
  for (const char* k : keys) {
    if (message.find(k) != std::string::npos) {
      key = k;
      break;
    }
  }
  node.fail(key, message);
}

void emitVector(YAML::Emitter& out, const char* key, const Eigen::Vector3d& v) {
  out << YAML::Key << key << YAML::Value << YAML::Flow << std::vector<double>{v.x(), v.y(), v.z()};
}

}  // namespace

Eigen::Isometry3d depthCameraPose(const Eigen::Vector3d& mount_B_m, const Eigen::Vector3d& mount_rpy_deg) {
  Eigen::Matrix3d optical_in_body;  // columns: the optical x (right), y (down), z (forward) in FLU
  optical_in_body << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  const Eigen::Matrix3d turn = (Eigen::AngleAxisd(mount_rpy_deg.z() * kRadPerDeg, Eigen::Vector3d::UnitZ()) *
                                Eigen::AngleAxisd(mount_rpy_deg.y() * kRadPerDeg, Eigen::Vector3d::UnitY()) *
                                Eigen::AngleAxisd(mount_rpy_deg.x() * kRadPerDeg, Eigen::Vector3d::UnitX()))
                                   .toRotationMatrix();
  Eigen::Isometry3d T_BC = Eigen::Isometry3d::Identity();
  T_BC.linear() = turn * optical_in_body;
  T_BC.translation() = mount_B_m;
  return T_BC;
}

RealConfig parseRealConfig(const rt::ConfigNode& node, const RealDevices& devices) {
  RealConfig c;
  const auto section = [&node](const char* key, bool wanted) {
    if (!wanted && node.has(key)) node.fail(key, "set only for a device whose backend is real");
    if (wanted && !node.has(key)) node.fail(key, "required: the device's backend is real");
    return wanted;
  };
  if (section("gimbal_camera", devices.gimbal_camera)) {
    const rt::ConfigNode n = node.child("gimbal_camera");
    real::V4l2GimbalCameraParams& p = c.gimbal_camera;
    p.device = n.getString("device");
    p.pixel_format = n.getEnum("pixel_format", {"MJPG", "YUYV"});
    p.width_px = n.getInt("width_px", 16, 8192);
    p.height_px = n.getInt("height_px", 16, 8192);
    p.rate_hz = n.getDouble("rate_hz", 1.0, 1000.0);
    c.gimbal_camera_calibration = besideConfig(n, n.getString("calibration"));
    p.frame_timeout_s = n.getDouble("frame_timeout_s", 0.01, 60.0);
    p.reconnect_period_s = n.getDouble("reconnect_period_s", 0.01, 60.0);
    n.finish();
  }
  if (section("depth_camera", devices.depth_camera)) {
    const rt::ConfigNode n = node.child("depth_camera");
    real::V4l2DepthCameraParams& p = c.depth_camera;
    c.depth_driver = n.getEnum("driver", {"v4l2", "realsense"});
    p.device = n.getString("device");
    p.width_px = n.getInt("width_px", 16, 8192);
    p.height_px = n.getInt("height_px", 16, 8192);
    p.rate_hz = n.getDouble("rate_hz", 1.0, 1000.0);
    p.calibration_dir = besideConfig(n, n.getStringOr("calibration_dir", ""));
    p.calibration_file = besideConfig(n, n.getStringOr("calibration_file", ""));
    if (p.calibration_dir.empty() == p.calibration_file.empty() && c.depth_driver == "v4l2")
      n.fail("calibration_dir", "give calibration_dir (d435_<serial>.yaml) or calibration_file, not both");
    c.depth_mount_B_m = vector3(n, "mount_B_m", -5.0, 5.0);
    c.depth_mount_rpy_deg = vector3(n, "mount_rpy_deg", -180.0, 180.0);
    p.T_BC = depthCameraPose(c.depth_mount_B_m, c.depth_mount_rpy_deg);
    p.min_range_m = n.getDouble("min_range_m", 0.0, 100.0);
    p.max_range_m = n.getDouble("max_range_m", 0.1, 100.0);
    p.frame_timeout_s = n.getDouble("frame_timeout_s", 0.01, 60.0);
    p.reconnect_period_s = n.getDouble("reconnect_period_s", 0.01, 60.0);
    check(n, real::validate(p), {"min_range_m", "max_range_m", "width_px", "height_px", "rate_hz", "device"});
    n.finish();
  }
  if (section("gimbal", devices.gimbal)) {
    const rt::ConfigNode n = node.child("gimbal");
    real::RmdGimbalParams& p = c.gimbal;
    c.can_interface = n.getString("interface");
    p.motor_id = n.getInt("motor_id", 1, 32);
    p.reply_timeout_s = n.getDouble("reply_timeout_s", 0.001, 10.0);
    p.watchdog_s = n.getDouble("watchdog_s", 0.0, 10.0);
    p.default_max_rate_radps = n.getDouble("default_max_rate_radps", 0.01, 100.0);
    p.direction = n.getDouble("direction", -1.0, 1.0);
    if (p.direction != 1.0 && p.direction != -1.0) n.fail("direction", "must be 1 or -1");
    p.zero_offset_rad = n.getDouble("zero_offset_rad", -10.0, 10.0);
    n.finish();
  }
  if (section("flight_controller", devices.flight_controller)) {
    const rt::ConfigNode n = node.child("flight_controller");
    real::MavlinkParams& p = c.flight_controller;
    p.url = n.getString("url");
    p.system_id = n.getInt("system_id", 1, 255);
    p.component_id = n.getInt("component_id", 1, 255);
    p.target_system = n.getInt("target_system", 1, 255);
    p.target_component = n.getInt("target_component", 0, 255);
    p.heartbeat_period_s = n.getDouble("heartbeat_period_s", 0.1, 10.0);
    p.setpoint_period_s = n.getDouble("setpoint_period_s", 0.001, 0.05);  // PX4 offboard wants >= 20 Hz
    p.setpoint_stale_s = n.getDouble("setpoint_stale_s", 0.05, 5.0);
    p.link_timeout_s = n.getDouble("link_timeout_s", 0.1, 60.0);
    p.odometry_timeout_s = n.getDouble("odometry_timeout_s", 0.01, 10.0);
    check(
        n, real::validate(p),
        {"link_timeout_s", "heartbeat_period_s", "setpoint_stale_s", "setpoint_period_s", "odometry_timeout_s", "url"});
    n.finish();
  }
  node.finish();
  return c;
}

void emitYaml(YAML::Emitter& out, const RealConfig& c, const RealDevices& devices) {
  out << YAML::BeginMap;
  if (devices.gimbal_camera) {
    const real::V4l2GimbalCameraParams& p = c.gimbal_camera;
    out << YAML::Key << "gimbal_camera" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "device" << YAML::Value << p.device;
    out << YAML::Key << "pixel_format" << YAML::Value << p.pixel_format;
    out << YAML::Key << "width_px" << YAML::Value << p.width_px;
    out << YAML::Key << "height_px" << YAML::Value << p.height_px;
    out << YAML::Key << "rate_hz" << YAML::Value << p.rate_hz;
    out << YAML::Key << "calibration" << YAML::Value << c.gimbal_camera_calibration;
    out << YAML::Key << "frame_timeout_s" << YAML::Value << p.frame_timeout_s;
    out << YAML::Key << "reconnect_period_s" << YAML::Value << p.reconnect_period_s;
    out << YAML::EndMap;
  }
  if (devices.depth_camera) {
    const real::V4l2DepthCameraParams& p = c.depth_camera;
    out << YAML::Key << "depth_camera" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "driver" << YAML::Value << c.depth_driver;
    out << YAML::Key << "device" << YAML::Value << p.device;
    out << YAML::Key << "width_px" << YAML::Value << p.width_px;
    out << YAML::Key << "height_px" << YAML::Value << p.height_px;
    out << YAML::Key << "rate_hz" << YAML::Value << p.rate_hz;
    if (!p.calibration_dir.empty()) out << YAML::Key << "calibration_dir" << YAML::Value << p.calibration_dir;
    if (!p.calibration_file.empty()) out << YAML::Key << "calibration_file" << YAML::Value << p.calibration_file;
    emitVector(out, "mount_B_m", c.depth_mount_B_m);
    emitVector(out, "mount_rpy_deg", c.depth_mount_rpy_deg);
    out << YAML::Key << "min_range_m" << YAML::Value << p.min_range_m;
    out << YAML::Key << "max_range_m" << YAML::Value << p.max_range_m;
    out << YAML::Key << "frame_timeout_s" << YAML::Value << p.frame_timeout_s;
    out << YAML::Key << "reconnect_period_s" << YAML::Value << p.reconnect_period_s;
    out << YAML::EndMap;
  }
  if (devices.gimbal) {
    const real::RmdGimbalParams& p = c.gimbal;
    out << YAML::Key << "gimbal" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "interface" << YAML::Value << c.can_interface;
    out << YAML::Key << "motor_id" << YAML::Value << p.motor_id;
    out << YAML::Key << "reply_timeout_s" << YAML::Value << p.reply_timeout_s;
    out << YAML::Key << "watchdog_s" << YAML::Value << p.watchdog_s;
    out << YAML::Key << "default_max_rate_radps" << YAML::Value << p.default_max_rate_radps;
    out << YAML::Key << "direction" << YAML::Value << p.direction;
    out << YAML::Key << "zero_offset_rad" << YAML::Value << p.zero_offset_rad;
    out << YAML::EndMap;
  }
  if (devices.flight_controller) {
    const real::MavlinkParams& p = c.flight_controller;
    out << YAML::Key << "flight_controller" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "url" << YAML::Value << p.url;
    out << YAML::Key << "system_id" << YAML::Value << p.system_id;
    out << YAML::Key << "component_id" << YAML::Value << p.component_id;
    out << YAML::Key << "target_system" << YAML::Value << p.target_system;
    out << YAML::Key << "target_component" << YAML::Value << p.target_component;
    out << YAML::Key << "heartbeat_period_s" << YAML::Value << p.heartbeat_period_s;
    out << YAML::Key << "setpoint_period_s" << YAML::Value << p.setpoint_period_s;
    out << YAML::Key << "setpoint_stale_s" << YAML::Value << p.setpoint_stale_s;
    out << YAML::Key << "link_timeout_s" << YAML::Value << p.link_timeout_s;
    out << YAML::Key << "odometry_timeout_s" << YAML::Value << p.odometry_timeout_s;
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
}

}  // namespace aerotrack::hal
