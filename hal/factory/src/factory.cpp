// Device factory: see factory.hpp. Adding a backend means one more name in the allowed list of
// its device and one more branch in makeDevices(); nothing else in the tree changes.
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
  c.gimbal_camera = node.getEnum("gimbal_camera", {"null", "sim"});
  c.depth_camera = node.getEnum("depth_camera", {"null", "sim"});
  c.gimbal = node.getEnum("gimbal", {"null", "sim"});
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

SimConfig parseSimConfig(const rt::ConfigNode& node) {
  SimConfig c;
  c.scenario = node.getString("scenario");
  c.seed = node.getUint64("seed");
  c.physics_step_s = node.getDouble("physics_step_s", 1e-4, 0.01);
  c.render_depth = node.getBool("render_depth");
  if (node.has("faults")) {
    const rt::ConfigNode faults = node.child("faults");
    const auto window = [&faults](const char* key, sim::FaultWindow& out) {
      if (!faults.has(key)) return;
      const std::vector<double> w = faults.getDoubleList(key, 2, 0.0, 1e6);
      if (w[1] <= w[0]) faults.fail(key, "end must be after begin");
      out = {w[0], w[1]};
    };
    window("camera_stop_s", c.faults.camera_stop);
    window("person_occluded_s", c.faults.person_occluded);
    window("odometry_freeze_s", c.faults.odometry_freeze);
    window("depth_stop_s", c.faults.depth_stop);
    faults.finish();
  }
  node.finish();
  return c;
}

void emitYaml(YAML::Emitter& out, const SimConfig& c) {
  out << YAML::BeginMap;
  out << YAML::Key << "scenario" << YAML::Value << c.scenario;
  out << YAML::Key << "seed" << YAML::Value << c.seed;
  out << YAML::Key << "physics_step_s" << YAML::Value << c.physics_step_s;
  out << YAML::Key << "render_depth" << YAML::Value << c.render_depth;
  const std::pair<const char*, const sim::FaultWindow*> windows[] = {{"camera_stop_s", &c.faults.camera_stop},
                                                                     {"person_occluded_s", &c.faults.person_occluded},
                                                                     {"odometry_freeze_s", &c.faults.odometry_freeze},
                                                                     {"depth_stop_s", &c.faults.depth_stop}};
  bool any = false;
  for (const auto& [key, w] : windows) any = any || w->begin_s >= 0.0;
  if (any) {
    out << YAML::Key << "faults" << YAML::Value << YAML::BeginMap;
    for (const auto& [key, w] : windows) {
      if (w->begin_s >= 0.0)
        out << YAML::Key << key << YAML::Value << YAML::Flow << std::vector<double>{w->begin_s, w->end_s};
    }
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
}

rt::Expected<Devices> makeDevices(const HalConfig& config, const sim::ScenarioInstance* scenario,
                                  const sim::SimulationOptions& sim_options, TimeNs start_ns) {
  Devices d;
  if (config.usesSim()) {
    if (scenario == nullptr) return rt::Error{"hal: sim backends need a scenario"};
    auto simulation = sim::Simulation::create(*scenario, sim_options, start_ns);
    if (!simulation) return simulation.error();
    d.simulation = std::move(simulation.value());
  }
  const bool sim_camera = config.gimbal_camera == "sim";
  if (sim_camera)
    d.gimbal_camera = std::make_unique<sim::SimGimbalCamera>(d.simulation);
  else
    d.gimbal_camera = std::make_unique<null::NullGimbalCamera>();
  if (config.depth_camera == "sim")
    d.depth_camera = std::make_unique<sim::SimDepthCamera>(d.simulation);
  else
    d.depth_camera = std::make_unique<null::NullDepthCamera>();
  if (config.gimbal == "sim")
    d.gimbal = std::make_unique<sim::SimGimbal>(d.simulation);
  else
    d.gimbal = std::make_unique<null::NullGimbal>();
  if (config.odometry == "sim")
    d.odometry = std::make_unique<sim::SimOdometry>(d.simulation);
  else
    d.odometry = std::make_unique<null::NullOdometry>();
  if (config.vehicle_link == "sim")
    d.vehicle_link = std::make_unique<sim::SimVehicleLink>(d.simulation);
  else
    d.vehicle_link = std::make_unique<null::NullVehicleLink>();
  return d;
}

}  // namespace aerotrack::hal
