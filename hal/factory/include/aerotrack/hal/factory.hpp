// Builds the devices from config (DESIGN.md rule 5): backends are chosen at run time, and this is
// the only place that knows which backends exist (and the only place for `#if` around optional
// drivers). Every device slot is filled: a device this vehicle lacks gets a null backend.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <yaml-cpp/emitter.h>

#include "aerotrack/hal/devices.hpp"
#include "aerotrack/hal/real_config.hpp"
#include "aerotrack/hal/replay/replay_devices.hpp"
#include "aerotrack/hal/sim/simulation.hpp"
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
  /// The `replay:` map inside `hal:`: required when a backend is "replay" (issue 10): `dir`, `offset_s`,
  /// `loop`, `bad_rows` (skip | strict).
  replay::ReplayOptions replay;
  /// The `real:` map inside `hal:` (issue 11): the drivers' parameters, a sub-map per real device.
  RealConfig real;

  bool usesSim() const;
  bool usesReplay() const;
  bool usesReal() const;
  RealDevices realDevices() const;
};

/// The `sim:` section: which scenario the sim backends fly and how.
struct SimConfig {
  std::string scenario = "open";  ///< Name in config/scenarios/ or a YAML path.
  std::uint64_t seed = 1;
  double physics_step_s = 0.002;
  bool render_depth = true;
  /// Optional `faults:` map: camera_stop_s, person_occluded_s, odometry_freeze_s, depth_stop_s,
  /// gimbal_stuck_s, gimbal_silent_s, vehicle_link_lost_s, camera_late_s, detector_garbage_s,
  /// depth_zero_s, each [begin, end] seconds of simulated time (each optional; sim::SimFaults). For
  /// tests of the failsafes and the fault matrix.
  sim::SimFaults faults;
  /// Optional `faults: task_overrun: {task: NAME, window_s: [begin, end], run_ms: R}`: each release of
  /// the task in the window takes R ms (run_ms optional: the window's length, one stall of the whole
  /// window); rt::LockstepExecutor::stall, rt::RealtimeExecutor::stall. Empty task: none.
  struct TaskOverrun {
    std::string task;
    sim::FaultWindow window;
    double run_ms = 0.0;  ///< 0: the window's length
  } task_overrun;
};

/// Reads the `hal:` map (throws rt::ConfigError naming the key; use inside rt::parseConfig).
HalConfig parseHalConfig(const rt::ConfigNode& node);
void emitYaml(YAML::Emitter& out, const HalConfig& config);
SimConfig parseSimConfig(const rt::ConfigNode& node);
void emitYaml(YAML::Emitter& out, const SimConfig& config);

/// The devices of one vehicle. simulation is set when any backend is "sim": the app must then
/// step it with the `sim_world` task.
struct Devices {
  std::unique_ptr<GimbalCamera> gimbal_camera;
  std::unique_ptr<DepthCamera> depth_camera;
  std::unique_ptr<Gimbal> gimbal;
  std::unique_ptr<Odometry> odometry;
  std::unique_ptr<VehicleLink> vehicle_link;
  std::shared_ptr<sim::Simulation> simulation;
  /// Set when any backend is "replay": the dataset the replayed devices share (its timeline tells
  /// `aerotrack replay` when the recording ends).
  std::shared_ptr<const replay::ReplayDataset> recording;
};

/// Builds every device. scenario (one instantiated trial) is needed only if a backend is "sim".
rt::Expected<Devices> makeDevices(const HalConfig& config, const sim::ScenarioInstance* scenario,
                                  const sim::SimulationOptions& sim_options, TimeNs start_ns);

}  // namespace aerotrack::hal
