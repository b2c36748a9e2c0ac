// Device factory: see factory.hpp. Adding a backend means one more name in the allowed list of
// its device and one more branch in make*(); nothing else in the tree changes.
#include "aerotrack/hal/factory.hpp"

#include "aerotrack/hal/null/devices.hpp"
#include "aerotrack/hal/sim/devices.hpp"

namespace aerotrack::hal {

bool HalConfig::usesSim() const {
  for (const std::string* backend : {&gimbal_camera, &depth_camera, &gimbal, &odometry, &vehicle_link})
    if (*backend == "sim") return true;
  return false;
}

HalConfig parseHalConfig(const rt::ConfigNode& node) {
  HalConfig c;
  c.gimbal_camera = node.getEnum("gimbal_camera", {"null"});
  c.depth_camera = node.getEnum("depth_camera", {"null"});
  c.gimbal = node.getEnum("gimbal", {"null"});
  c.odometry = node.getEnum("odometry", {"null", "sim"});
  c.vehicle_link = node.getEnum("vehicle_link", {"null", "sim"});
  node.finish();
  return c;
}

void emitYaml(YAML::Emitter& out, const HalConfig& c) {
  out << YAML::BeginMap;
  out << YAML::Key << "gimbal_camera" << YAML::Value << c.gimbal_camera;
  out << YAML::Key << "depth_camera" << YAML::Value << c.depth_camera;
  out << YAML::Key << "gimbal" << YAML::Value << c.gimbal;
  out << YAML::Key << "odometry" << YAML::Value << c.odometry;
  out << YAML::Key << "vehicle_link" << YAML::Value << c.vehicle_link;
  out << YAML::EndMap;
}

sim::PointMassParams parsePointMassParams(const rt::ConfigNode& node) {
  sim::PointMassParams p;
  p.position_gain_per_s2 = node.getDouble("position_gain_per_s2", 0.0, 100.0);
  p.velocity_gain_per_s = node.getDouble("velocity_gain_per_s", 0.0, 100.0);
  p.max_accel_mps2 = node.getDouble("max_accel_mps2", 0.1, 100.0);
  p.max_yaw_rate_radps = node.getDouble("max_yaw_rate_radps", 0.1, 50.0);
  p.substep_s = node.getDouble("substep_s", 1e-5, 0.01);
  node.finish();
  return p;
}

void emitYaml(YAML::Emitter& out, const sim::PointMassParams& p) {
  out << YAML::BeginMap;
  out << YAML::Key << "position_gain_per_s2" << YAML::Value << p.position_gain_per_s2;
  out << YAML::Key << "velocity_gain_per_s" << YAML::Value << p.velocity_gain_per_s;
  out << YAML::Key << "max_accel_mps2" << YAML::Value << p.max_accel_mps2;
  out << YAML::Key << "max_yaw_rate_radps" << YAML::Value << p.max_yaw_rate_radps;
  out << YAML::Key << "substep_s" << YAML::Value << p.substep_s;
  out << YAML::EndMap;
}

rt::Expected<Devices> makeDevices(const HalConfig& config, const sim::PointMassParams& sim_params, TimeNs start_ns) {
  Devices d;
  if (config.usesSim()) d.world = std::make_shared<sim::PointMassWorld>(sim_params, start_ns);

  // Backends without a sim or real implementation yet accept only "null" in parseHalConfig.
  d.gimbal_camera = std::make_unique<null::NullGimbalCamera>();
  d.depth_camera = std::make_unique<null::NullDepthCamera>();
  d.gimbal = std::make_unique<null::NullGimbal>();

  if (config.odometry == "sim")
    d.odometry = std::make_unique<sim::SimOdometry>(d.world);
  else if (config.odometry == "null")
    d.odometry = std::make_unique<null::NullOdometry>();
  else
    return rt::Error{"hal.odometry: unknown backend '" + config.odometry + "'"};

  if (config.vehicle_link == "sim")
    d.vehicle_link = std::make_unique<sim::SimVehicleLink>(d.world);
  else if (config.vehicle_link == "null")
    d.vehicle_link = std::make_unique<null::NullVehicleLink>();
  else
    return rt::Error{"hal.vehicle_link: unknown backend '" + config.vehicle_link + "'"};

  return d;
}

}  // namespace aerotrack::hal
