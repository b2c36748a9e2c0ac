// Builds the devices from config (DESIGN.md rule 5): backends are chosen at run time, and this is
// the only place that knows which backends exist (and the only place for `#if` around optional
// drivers). Every device slot is filled: a device this vehicle lacks gets a null backend.
#pragma once

#include <memory>
#include <string>

#include <yaml-cpp/emitter.h>

#include "aerotrack/hal/devices.hpp"
#include "aerotrack/hal/sim/point_mass_world.hpp"
#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal {

/// The `hal:` section of a config: one backend name per device.
struct HalConfig {
  std::string gimbal_camera = "null";
  std::string depth_camera = "null";
  std::string gimbal = "null";
  std::string odometry = "null";
  std::string vehicle_link = "null";

  bool usesSim() const;
};

/// Reads the `hal:` map (throws rt::ConfigError naming the key; use inside rt::parseConfig).
HalConfig parseHalConfig(const rt::ConfigNode& node);
void emitYaml(YAML::Emitter& out, const HalConfig& config);

/// Reads the `sim:` map: the simulated vehicle's controller (its start pose comes from the scenario).
sim::PointMassParams parsePointMassParams(const rt::ConfigNode& node);
void emitYaml(YAML::Emitter& out, const sim::PointMassParams& params);

/// The devices of one vehicle. world is set when any backend is "sim": the app must then step it
/// with the `sim_world` task.
struct Devices {
  std::unique_ptr<GimbalCamera> gimbal_camera;
  std::unique_ptr<DepthCamera> depth_camera;
  std::unique_ptr<Gimbal> gimbal;
  std::unique_ptr<Odometry> odometry;
  std::unique_ptr<VehicleLink> vehicle_link;
  std::shared_ptr<sim::PointMassWorld> world;
};

/// Builds every device. sim_params and start_ns are used only if a backend is "sim".
rt::Expected<Devices> makeDevices(const HalConfig& config, const sim::PointMassParams& sim_params, TimeNs start_ns);

}  // namespace aerotrack::hal
