// The typed configuration of one aerotrack process (config/*.yaml): vehicle limits, device
// backends, module parameters and the task table. Each section is parsed by its owner (hal,
// modules, rt); this file only composes them and owns the top-level keys.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <optional>

#include "aerotrack/estimation/target_task.hpp"
#include "aerotrack/gimbal_control/gimbal_controller.hpp"
#include "aerotrack/hal/factory.hpp"
#include "aerotrack/mapping/mapper.hpp"
#include "aerotrack/perception/detector.hpp"
#include "aerotrack/planning/tracking_planner.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/realtime_executor.hpp"
#include "aerotrack/rt/task.hpp"
#include "aerotrack/supervisor/supervisor.hpp"
#include "aerotrack/trajectory_server/trajectory_server.hpp"

namespace aerotrack::app {

struct VehicleConfig {
  double radius_m = 0.25;  ///< Collision radius (paper: 300 x 300 mm frame).
  double max_speed_mps = 3.0;
  double max_accel_mps2 = 4.0;
};

/// The `estimation:` section: the target pipeline's parameters, with the localization regression
/// loaded from the file it names (relative paths: from the config file's folder).
struct EstimationConfig {
  std::string localization_params_path;  ///< Resolved.
  /// Optional `localization_params_image`: the regression fitted to the real network's detections on
  /// rendered frames (issue 22 item 3), used instead of localization_params when the simulated gimbal
  /// camera renders images (selectLocalization). Empty: none.
  std::string localization_params_image_path;
  std::optional<localization::LocalizationParams> localization_image;
  std::array<double, 3> mount_m{}, camera_in_gimbal_m{}, camera_in_gimbal_rpy_rad{};  ///< As written.
  estimation::TargetTaskParams task;
};

struct AppConfig {
  std::string source;  ///< The file it was read from.
  /// The paper's comparison (not in YAML; `sim --mode`): false, this system; true, Fast-Tracker 1.0 --
  /// camera fixed to the body (the drone yaws to face the person), no occlusion term, no camera sweep.
  bool baseline_mode = false;
  /// `--record DIR` (run, sim): record what the devices deliver and are told into a dataset there
  /// (hal/replay/README.md). Empty: no recording.
  std::string record_dir;
  /// The run is on the lockstep executor: the recorder waits for the disk instead of dropping records.
  bool record_lossless = false;
  /// `--mcap FILE` (run, sim, replay): the flight log for Foxglove (flight_log.hpp). Empty: none.
  std::string mcap_path;
  /// `--mcap-compression zstd|lz4|none`.
  std::string mcap_compression = "zstd";
  /// `--live PORT|HOST:PORT` (run, sim --realtime): the live view (live_view.hpp). Empty: no socket.
  std::string live_address;
  VehicleConfig vehicle;
  hal::HalConfig hal;
  hal::SimConfig sim;  ///< Used when a backend is "sim"; `aerotrack sim` overrides scenario and seed.
  trajectory_server::TrajectoryServerParams trajectory_server;
  std::optional<mapping::MapperParams> mapping;  ///< `mapping:` section; needed by the mapping task.
  /// `perception:` section; needed by the detection task. model_dir "default" is resolved by the app.
  std::optional<perception::DetectorParams> perception;
  std::optional<EstimationConfig> estimation;               ///< `estimation:` section; needed by the target task.
  std::optional<planning::TrackingPlannerParams> planning;  ///< `planning:` section; needed by the planning task.
  /// `gimbal_control:` section; needed by the gimbal_control task (which also needs estimation's extrinsics).
  std::optional<gimbal_control::GimbalControlParams> gimbal_control;
  std::optional<supervisor::SupervisorParams> supervisor;  ///< `supervisor:` section; needed by the supervisor task.
  rt::RealtimeOptions realtime;
  std::vector<rt::TaskSpec> tasks;
};

/// The simulated camera's mode decides the regression: in image mode the real network measures the
/// torso, so the estimation takes localization_params_image where the config gives it (its path then
/// becomes localization_params, as a recording's config must say what ran).
void selectLocalization(AppConfig& config, bool image_camera);

/// Reads the `estimation:` section; config_path locates relative localization_params paths.
/// Throws rt::ConfigError naming the key (use inside rt::parseConfig).
EstimationConfig parseEstimation(const rt::ConfigNode& node, const std::string& config_path);

/// Loads and checks a config file. The error names the file, line and key.
/// `overrides` (--set KEY=VALUE) replace the file's values before it is checked.
rt::Expected<AppConfig> loadAppConfig(const std::string& path, const std::vector<rt::ConfigOverride>& overrides = {});
/// Same, from YAML text (tests); source_name stands for the file name in messages.
rt::Expected<AppConfig> parseAppConfig(const std::string& yaml_text, const std::string& source_name);

/// The effective configuration as YAML (what --print-config shows); parses back to the same.
std::string toYaml(const AppConfig& config);

}  // namespace aerotrack::app
