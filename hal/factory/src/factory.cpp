// Device factory: see factory.hpp. Adding a backend means one more name in the allowed list of
// its device and one more branch in makeDevices(); nothing else in the tree changes.
#include "aerotrack/hal/factory.hpp"

#include "aerotrack/hal/null/devices.hpp"
#include "aerotrack/hal/sim/devices.hpp"
#include "real_devices.hpp"

namespace aerotrack::hal {

bool HalConfig::usesSim() const {
  for (const std::string* backend : {&gimbal_camera, &depth_camera, &gimbal, &odometry, &vehicle_link})
    if (*backend == "sim") return true;
  return false;
}

bool HalConfig::usesReal() const {
  const RealDevices r = realDevices();
  return r.gimbal_camera || r.depth_camera || r.gimbal || r.flight_controller;
}

RealDevices HalConfig::realDevices() const {
  return {gimbal_camera == "real", depth_camera == "real", gimbal == "real",
          odometry == "real" || vehicle_link == "real"};
}

bool HalConfig::usesReplay() const {
  for (const std::string* backend : {&gimbal_camera, &depth_camera, &gimbal, &odometry, &vehicle_link})
    if (*backend == "replay") return true;
  return false;
}

HalConfig parseHalConfig(const rt::ConfigNode& node) {
  HalConfig c;
  c.gimbal_camera = node.getEnum("gimbal_camera", {"null", "sim", "replay", "real"});
  c.depth_camera = node.getEnum("depth_camera", {"null", "sim", "replay", "real"});
  c.gimbal = node.getEnum("gimbal", {"null", "sim", "replay", "real"});
  c.odometry = node.getEnum("odometry", {"null", "sim", "replay", "real"});
  c.vehicle_link = node.getEnum("vehicle_link", {"null", "sim", "replay", "real"});
  if (node.has("replay")) {
    const rt::ConfigNode r = node.child("replay");
    c.replay.dir = r.getString("dir");
    c.replay.offset_s = r.getDouble("offset_s", 0.0, 1e9);
    c.replay.loop = r.getBool("loop");
    c.replay.bad_rows = r.getEnum("bad_rows", {"skip", "strict"}) == "strict" ? replay::BadRowPolicy::kStrict
                                                                              : replay::BadRowPolicy::kSkip;
    r.finish();
  } else if (c.usesReplay()) {
    node.fail("replay", "a replay backend needs the replay: map (dir, offset_s, loop, bad_rows)");
  }
  if (node.has("real") || c.usesReal()) {
    if (!node.has("real")) node.fail("real", "a real backend needs the real: map (the drivers' parameters)");
    c.real = parseRealConfig(node.child("real"), c.realDevices());
  }
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
  if (c.usesReplay()) {
    out << YAML::Key << "replay" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "dir" << YAML::Value << c.replay.dir;
    out << YAML::Key << "offset_s" << YAML::Value << c.replay.offset_s;
    out << YAML::Key << "loop" << YAML::Value << c.replay.loop;
    out << YAML::Key << "bad_rows" << YAML::Value
        << (c.replay.bad_rows == replay::BadRowPolicy::kStrict ? "strict" : "skip");
    out << YAML::EndMap;
  }
  if (c.usesReal()) {
    out << YAML::Key << "real" << YAML::Value;
    emitYaml(out, c.real, c.realDevices());
  }
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
    window("gimbal_stuck_s", c.faults.gimbal_stuck);
    window("gimbal_silent_s", c.faults.gimbal_silent);
    window("vehicle_link_lost_s", c.faults.vehicle_link_lost);
    window("camera_late_s", c.faults.camera_late);
    window("detector_garbage_s", c.faults.detector_garbage);
    window("depth_zero_s", c.faults.depth_zero);
    if (faults.has("task_overrun")) {
      const rt::ConfigNode overrun = faults.child("task_overrun");
      c.task_overrun.task = overrun.getString("task");
      if (c.task_overrun.task.empty()) overrun.fail("task", "must name a task of the table");
      const auto read_window = [&overrun](const char* key, sim::FaultWindow& out) {
        const std::vector<double> w = overrun.getDoubleList(key, 2, 0.0, 1e6);
        if (w[1] <= w[0]) overrun.fail(key, "end must be after begin");
        out = {w[0], w[1]};
      };
      read_window("window_s", c.task_overrun.window);
      if (overrun.has("run_ms")) c.task_overrun.run_ms = overrun.getDouble("run_ms", rt::Range::openClosed(0.0, 1e6));
      overrun.finish();
    }
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
  const std::pair<const char*, const sim::FaultWindow*> windows[] = {
      {"camera_stop_s", &c.faults.camera_stop},
      {"person_occluded_s", &c.faults.person_occluded},
      {"odometry_freeze_s", &c.faults.odometry_freeze},
      {"depth_stop_s", &c.faults.depth_stop},
      {"gimbal_stuck_s", &c.faults.gimbal_stuck},
      {"gimbal_silent_s", &c.faults.gimbal_silent},
      {"vehicle_link_lost_s", &c.faults.vehicle_link_lost},
      {"camera_late_s", &c.faults.camera_late},
      {"detector_garbage_s", &c.faults.detector_garbage},
      {"depth_zero_s", &c.faults.depth_zero}};
  bool any = !c.task_overrun.task.empty();
  for (const auto& [key, w] : windows) any = any || w->begin_s >= 0.0;
  if (any) {
    out << YAML::Key << "faults" << YAML::Value << YAML::BeginMap;
    for (const auto& [key, w] : windows) {
      if (w->begin_s >= 0.0)
        out << YAML::Key << key << YAML::Value << YAML::Flow << std::vector<double>{w->begin_s, w->end_s};
    }
    if (!c.task_overrun.task.empty()) {
      const sim::FaultWindow& w = c.task_overrun.window;
      out << YAML::Key << "task_overrun" << YAML::Value << YAML::BeginMap << YAML::Key << "task" << YAML::Value
          << c.task_overrun.task << YAML::Key << "window_s" << YAML::Value << YAML::Flow
          << std::vector<double>{w.begin_s, w.end_s};
      if (c.task_overrun.run_ms > 0.0) out << YAML::Key << "run_ms" << YAML::Value << c.task_overrun.run_ms;
      out << YAML::EndMap;
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
  std::shared_ptr<replay::ReplayDataset> recording;
  if (config.usesReplay()) {
    auto opened = replay::ReplayDataset::open(config.replay, start_ns);
    if (!opened) return rt::Error{"hal: replay: " + opened.error().message};
    recording = std::move(opened.value());
    d.recording = recording;
    // A replayed device whose stream was not recorded would be silent: say so at start, not in flight.
    const std::pair<const std::string*, const char*> needs[] = {
        {&config.odometry, "odometry"}, {&config.gimbal, "gimbal"}, {&config.depth_camera, "depth_camera"}};
    for (const auto& [backend, device] : needs) {
      if (*backend == "replay" && recording->manifest().stream(device) == nullptr) {
        return rt::Error{"hal: replay: " + config.replay.dir + " has no " + device + " stream"};
      }
    }
    if (config.gimbal_camera == "replay" && recording->manifest().stream("gimbal_camera") == nullptr &&
        recording->manifest().stream("detections") == nullptr) {
      return rt::Error{"hal: replay: " + config.replay.dir + " has no gimbal_camera (images) or detections stream"};
    }
  }
  if (config.usesReal()) {
    if (rt::Status s = makeRealDevices(config, start_ns, d); !s) return s.error();
  }
  if (config.gimbal_camera == "sim")
    d.gimbal_camera = std::make_unique<sim::SimGimbalCamera>(d.simulation);
  else if (config.gimbal_camera == "replay")
    d.gimbal_camera = std::make_unique<replay::ReplayGimbalCamera>(recording);
  else if (config.gimbal_camera != "real")
    d.gimbal_camera = std::make_unique<null::NullGimbalCamera>();
  if (config.depth_camera == "sim")
    d.depth_camera = std::make_unique<sim::SimDepthCamera>(d.simulation);
  else if (config.depth_camera == "replay")
    d.depth_camera = std::make_unique<replay::ReplayDepthCamera>(recording);
  else if (config.depth_camera != "real")
    d.depth_camera = std::make_unique<null::NullDepthCamera>();
  if (config.gimbal == "sim")
    d.gimbal = std::make_unique<sim::SimGimbal>(d.simulation);
  else if (config.gimbal == "replay")
    d.gimbal = std::make_unique<replay::ReplayGimbal>(recording);
  else if (config.gimbal != "real")
    d.gimbal = std::make_unique<null::NullGimbal>();
  if (config.odometry == "sim")
    d.odometry = std::make_unique<sim::SimOdometry>(d.simulation);
  else if (config.odometry == "replay")
    d.odometry = std::make_unique<replay::ReplayOdometry>(recording);
  else if (config.odometry != "real")
    d.odometry = std::make_unique<null::NullOdometry>();
  if (config.vehicle_link == "sim")
    d.vehicle_link = std::make_unique<sim::SimVehicleLink>(d.simulation);
  else if (config.vehicle_link == "replay")
    d.vehicle_link = std::make_unique<replay::ReplayVehicleLink>(recording);
  else if (config.vehicle_link != "real")
    d.vehicle_link = std::make_unique<null::NullVehicleLink>();
  return d;
}

}  // namespace aerotrack::hal
