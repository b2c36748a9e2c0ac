// Composition of the config sections: see app_config.hpp.
#include "app_config.hpp"

#include <array>
#include <cstdio>
#include <filesystem>

#include <yaml-cpp/yaml.h>

#include "aerotrack/localization/localization_io.hpp"
#include "aerotrack/mapping/mapping_task.hpp"
#include "aerotrack/perception/detection_task.hpp"
#include "planning_yaml.hpp"

namespace aerotrack::app {
namespace {

rt::TaskSpec parseTaskSpec(const rt::ConfigNode& node) {
  rt::TaskSpec t;
  t.name = node.getString("name");
  t.rate_hz = node.getDoubleOr("rate_hz", 0.0, 0.0, 100000.0);
  t.trigger = node.getStringOr("trigger", "");
  t.min_period_ms = node.getDoubleOr("min_period_ms", 0.0, 0.0, 10000.0);
  t.budget_ms = node.getDouble("budget_ms", 1e-6, 10000.0);
  t.priority = node.getIntOr("priority", 0, 0, 99);
  t.cpu = node.getIntOr("cpu", -1, -1, 1023);
  t.latency_ms = node.getDoubleOr("latency_ms", 0.0, 0.0, 10000.0);
  node.finish();
  if (const rt::Status s = rt::validate(t); !s) node.fail("", s.error().message);
  return t;
}

std::string formatMs(double ms) {
  std::array<char, 32> text{};
  std::snprintf(text.data(), text.size(), "%g ms", ms);
  return text.data();
}

AppConfig parseRoot(const rt::ConfigNode& root) {
  AppConfig c;
  c.source = root.sourceName();
  const rt::ConfigNode vehicle = root.child("vehicle");
  c.vehicle.radius_m = vehicle.getDouble("radius_m", 0.05, 2.0);
  c.vehicle.max_speed_mps = vehicle.getDouble("max_speed_mps", 0.1, 30.0);
  c.vehicle.max_accel_mps2 = vehicle.getDouble("max_accel_mps2", 0.1, 30.0);
  vehicle.finish();

  c.hal = hal::parseHalConfig(root.child("hal"));
  // Which scenario the sim backends fly; only a config that simulates needs the section.
  if (root.has("sim") || c.hal.usesSim()) c.sim = hal::parseSimConfig(root.child("sim"));

  const rt::ConfigNode server = root.child("trajectory_server");
  c.trajectory_server.yaw_min_speed_mps = server.getDouble("yaw_min_speed_mps", 0.0, 10.0);
  c.trajectory_server.max_late_takeover_s = server.getDouble("max_late_takeover_s", rt::Range::openClosed(0.0, 10.0));
  server.finish();

  if (root.has("mapping")) c.mapping = mapping::parseMapperParams(root.child("mapping"));
  if (root.has("perception")) c.perception = perception::parseDetectorParams(root.child("perception"));
  if (root.has("estimation")) c.estimation = parseEstimation(root.child("estimation"), c.source);
  // One torso-reliability rule for the detector's output and the estimator's input (keypoint mode, which
  // has no detector, keeps the rule's defaults).
  if (c.perception && c.estimation) c.estimation->task.torso = c.perception->torso;
  // ... and one appearance rule for the lock-on and the target task's association (issue 22).
  if (c.perception && c.estimation) c.estimation->task.tracker = c.perception->tracker;
  if (root.has("gimbal_control"))
    c.gimbal_control = gimbal_control::parseGimbalControlParams(root.child("gimbal_control"));
  if (root.has("supervisor")) {
    const rt::ConfigNode supervisor_node = root.child("supervisor");
    c.supervisor = supervisor::parseSupervisorParams(supervisor_node);
    if (const rt::Status s = supervisor::validate(*c.supervisor); !s)
      supervisor_node.fail("supervisor", s.error().message);
  }
  if (root.has("planning")) {
    const rt::ConfigNode planning_node = root.child("planning");
    c.planning = planning::parseTrackingPlannerParams(planning_node);
    if (const rt::Status s = planning::validate(*c.planning); !s) planning_node.fail("planning", s.error().message);
  }

  if (root.has("realtime")) {
    const rt::ConfigNode rt_node = root.child("realtime");
    c.realtime.use_realtime_priority = rt_node.getBool("realtime_priority");
    c.realtime.use_affinity = rt_node.getBool("affinity");
    c.realtime.lock_memory = rt_node.getBool("lock_memory");
    rt_node.finish();
  }

  const std::vector<rt::ConfigNode> tasks = root.childList("tasks");
  for (const rt::ConfigNode& t : tasks) c.tasks.push_back(parseTaskSpec(t));
  if (const rt::Status s = rt::validate(c.tasks); !s) root.fail("tasks", s.error().message);
  // The hand-over: a new trajectory takes over planning_budget_s after the cycle's release, so it must
  // cover every cycle that keeps the task's budget, or a trajectory would arrive after its own start.
  for (const rt::TaskSpec& t : c.tasks) {
    if (t.name == "planning" && c.planning && c.planning->planning_budget_s * 1e3 < t.budget_ms - 1e-9)
      root.fail("planning", "planning_budget_s, the hand-over (" + formatMs(c.planning->planning_budget_s * 1e3) +
                                ") is shorter than the planning task's budget_ms (" + formatMs(t.budget_ms) + ")");
  }
  root.finish();
  return c;
}

std::array<double, 3> triple(const std::vector<double>& v) {
  return {v[0], v[1], v[2]};
}

}  // namespace

void selectLocalization(AppConfig& config, bool image_camera) {
  if (!image_camera || !config.estimation || !config.estimation->localization_image) return;
  EstimationConfig& e = *config.estimation;
  e.task.localization = *e.localization_image;
  e.localization_params_path = e.localization_params_image_path;
  e.localization_image.reset();
  e.localization_params_image_path.clear();
}

EstimationConfig parseEstimation(const rt::ConfigNode& node, const std::string& config_path) {
  EstimationConfig e;
  std::filesystem::path params_path = node.getString("localization_params");
  if (params_path.is_relative()) params_path = std::filesystem::path(config_path).parent_path() / params_path;
  std::error_code ec;
  e.localization_params_path = std::filesystem::weakly_canonical(params_path, ec).string();
  if (ec) e.localization_params_path = params_path.string();
  auto localization = localization::readParamsYaml(e.localization_params_path);
  if (!localization) node.fail("localization_params", localization.error().message);
  e.task.localization = *localization;
  if (node.has("localization_params_image")) {
    std::filesystem::path image_path = node.getString("localization_params_image");
    if (image_path.is_relative()) image_path = std::filesystem::path(config_path).parent_path() / image_path;
    e.localization_params_image_path = std::filesystem::weakly_canonical(image_path, ec).string();
    if (ec) e.localization_params_image_path = image_path.string();
    auto image = localization::readParamsYaml(e.localization_params_image_path);
    if (!image) node.fail("localization_params_image", image.error().message);
    e.localization_image = *image;
  }
  const rt::ConfigNode camera = node.child("gimbal_camera");
  e.mount_m = triple(camera.getDoubleList("mount_m", 3, -10.0, 10.0));
  e.camera_in_gimbal_m = triple(camera.getDoubleList("camera_in_gimbal_m", 3, -10.0, 10.0));
  e.camera_in_gimbal_rpy_rad = triple(camera.getDoubleList("camera_in_gimbal_rpy_rad", 3, -7.0, 7.0));
  estimation::parseTargetTaskParams(node, e.task);
  node.finish();
  return e;
}

namespace {

rt::Expected<AppConfig> parseFrom(rt::Expected<rt::ConfigNode> root) {
  if (!root) return root.error();
  return rt::parseConfig<AppConfig>([&] { return parseRoot(*root); });
}

}  // namespace

rt::Expected<AppConfig> loadAppConfig(const std::string& path, const std::vector<rt::ConfigOverride>& overrides) {
  return parseFrom(rt::ConfigNode::loadFile(path, overrides));
}

rt::Expected<AppConfig> parseAppConfig(const std::string& yaml_text, const std::string& source_name) {
  return parseFrom(rt::ConfigNode::fromString(yaml_text, source_name));
}

std::string toYaml(const AppConfig& c) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "vehicle" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "radius_m" << YAML::Value << c.vehicle.radius_m;
  out << YAML::Key << "max_speed_mps" << YAML::Value << c.vehicle.max_speed_mps;
  out << YAML::Key << "max_accel_mps2" << YAML::Value << c.vehicle.max_accel_mps2;
  out << YAML::EndMap;
  out << YAML::Key << "hal" << YAML::Value;
  hal::emitYaml(out, c.hal);
  out << YAML::Key << "sim" << YAML::Value;
  hal::emitYaml(out, c.sim);
  out << YAML::Key << "trajectory_server" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "yaw_min_speed_mps" << YAML::Value << c.trajectory_server.yaw_min_speed_mps;
  out << YAML::Key << "max_late_takeover_s" << YAML::Value << c.trajectory_server.max_late_takeover_s;
  out << YAML::EndMap;
  if (c.mapping) {
    const mapping::MapperParams& m = *c.mapping;
    out << YAML::Key << "mapping" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "resolution_m" << YAML::Value << m.octomap.resolution_m;
    out << YAML::Key << "prob_hit" << YAML::Value << m.octomap.prob_hit;
    out << YAML::Key << "prob_miss" << YAML::Value << m.octomap.prob_miss;
    out << YAML::Key << "decimation" << YAML::Value << m.points.decimation;
    out << YAML::Key << "min_range_m" << YAML::Value << m.points.min_range_m;
    out << YAML::Key << "max_range_m" << YAML::Value << m.points.max_range_m;
    out << YAML::Key << "grid_size_m" << YAML::Value << YAML::Flow
        << std::vector<double>{m.grid.size_m.x(), m.grid.size_m.y(), m.grid.size_m.z()};
    out << YAML::Key << "inflation_radius_m" << YAML::Value << m.grid.inflation_radius_m;
    out << YAML::Key << "unknown_is_occupied" << YAML::Value << m.grid.unknown_is_occupied;
    out << YAML::Key << "recenter_distance_m" << YAML::Value << m.grid.recenter_distance_m;
    out << YAML::Key << "octree_snapshot_every_n_frames" << YAML::Value << m.octree_snapshot_every_n_frames;
    const mapping::TargetExclusionParams& x = m.exclude_target;
    out << YAML::Key << "exclude_target" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "enabled" << YAML::Value << x.enabled;
    out << YAML::Key << "body_radius_m" << YAML::Value << x.body_radius_m;
    out << YAML::Key << "sigmas" << YAML::Value << x.sigmas;
    out << YAML::Key << "max_radius_m" << YAML::Value << x.max_radius_m;
    out << YAML::Key << "floor_above_estimate_m" << YAML::Value << x.floor_above_estimate_m;
    out << YAML::Key << "height_above_estimate_m" << YAML::Value << x.height_above_estimate_m;
    out << YAML::EndMap;
    out << YAML::EndMap;
  }
  if (c.perception) {
    const perception::DetectorParams& p = *c.perception;
    out << YAML::Key << "perception" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "model_dir" << YAML::Value << p.model_dir;
    out << YAML::Key << "tracking_model" << YAML::Value << p.tracking_model;
    out << YAML::Key << "search_model" << YAML::Value << p.search_model;
    out << YAML::Key << "dnn_backend" << YAML::Value << p.dnn.backend;
    out << YAML::Key << "dnn_target" << YAML::Value << p.dnn.target;
    out << YAML::Key << "min_person_score" << YAML::Value << p.min_person_score;
    out << YAML::Key << "min_multipose_score" << YAML::Value << p.min_multipose_score;
    out << YAML::Key << "whole_frame" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "near_crop_sides" << YAML::Value << p.whole_frame.near_crop_sides;
    out << YAML::Key << "every_s" << YAML::Value << p.whole_frame.every_s;
    out << YAML::Key << "on_crop_lost" << YAML::Value << p.whole_frame.on_crop_lost;
    out << YAML::Key << "beside_crop_every_s" << YAML::Value << p.whole_frame.beside_crop_every_s;
    out << YAML::EndMap;
    out << YAML::Key << "follow_estimator" << YAML::Value << p.follow_estimator;
    out << YAML::Key << "torso_min_joint_score" << YAML::Value << p.torso.min_joint_score;
    out << YAML::Key << "torso_border_margin_px" << YAML::Value << p.torso.border_margin_px;
    out << YAML::Key << "torso_edge_margin_fraction" << YAML::Value << p.torso.edge_margin_torso_fraction;
    out << YAML::Key << "torso_edge_guess_max_score" << YAML::Value << p.torso.edge_guess_max_score;
    out << YAML::Key << "tracker" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "gate_torso_multiples" << YAML::Value << p.tracker.gate_torso_multiples;
    out << YAML::Key << "max_torso_ratio" << YAML::Value << p.tracker.max_torso_ratio;
    out << YAML::Key << "max_appearance_distance" << YAML::Value << p.tracker.max_appearance_distance;
    out << YAML::Key << "appearance_weight" << YAML::Value << p.tracker.appearance_weight;
    out << YAML::Key << "lost_after_s" << YAML::Value << p.tracker.lost_after_s;
    out << YAML::Key << "appearance_rate" << YAML::Value << p.tracker.appearance_rate;
    out << YAML::EndMap;
    out << YAML::EndMap;
  }
  if (c.estimation) {
    const EstimationConfig& e = *c.estimation;
    const estimation::TargetEstimatorParams& k = e.task.estimator;
    const auto list = [](const std::array<double, 3>& a) { return std::vector<double>(a.begin(), a.end()); };
    out << YAML::Key << "estimation" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "localization_params" << YAML::Value << e.localization_params_path;
    if (e.localization_image)
      out << YAML::Key << "localization_params_image" << YAML::Value << e.localization_params_image_path;
    out << YAML::Key << "gimbal_camera" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "mount_m" << YAML::Value << YAML::Flow << list(e.mount_m);
    out << YAML::Key << "camera_in_gimbal_m" << YAML::Value << YAML::Flow << list(e.camera_in_gimbal_m);
    out << YAML::Key << "camera_in_gimbal_rpy_rad" << YAML::Value << YAML::Flow << list(e.camera_in_gimbal_rpy_rad);
    out << YAML::EndMap;
    out << YAML::Key << "measurement_std_per_m" << YAML::Value << e.task.measurement_std_per_m;
    out << YAML::Key << "min_measurement_std_m" << YAML::Value << e.task.min_measurement_std_m;
    out << YAML::Key << "max_wait_s" << YAML::Value << rt::nsToSeconds(e.task.max_wait_ns);
    out << YAML::Key << "unreliable_torso" << YAML::Value << (e.task.bearing_fallback ? "bearing" : "skip");
    out << YAML::Key << "look_gate_sigmas" << YAML::Value << e.task.look_gate_sigmas;
    out << YAML::Key << "look_gate_confirm_s" << YAML::Value << e.task.look_gate_confirm_s;
    out << YAML::Key << "association" << YAML::Value << (e.task.choose_by_estimate ? "estimate" : "lock_on");
    out << YAML::Key << "in_front_after_ranged" << YAML::Value << e.task.in_front_after_ranged;
    out << YAML::Key << "in_front_streak_spans_unseen" << YAML::Value << e.task.in_front_streak_spans_unseen;
    out << YAML::Key << "in_front_unseen_limit" << YAML::Value << e.task.in_front_unseen_limit;
    out << YAML::Key << "in_front_gate_chi2" << YAML::Value << e.task.in_front_gate_chi2;
    out << YAML::Key << "in_front_test" << YAML::Value
        << (e.task.in_front_test == estimation::TargetTaskParams::InFrontTest::kGate ? "gate" : "nearer");
    out << YAML::Key << "hidden_behind_m" << YAML::Value << e.task.hidden_behind_m;
    out << YAML::Key << "depth_vets_bearings" << YAML::Value << e.task.depth_vets_bearings;
    out << YAML::Key << "bearing_by_likelihood" << YAML::Value << e.task.bearing_by_likelihood;
    out << YAML::Key << "in_front_doubtful_starts_track" << YAML::Value << e.task.in_front_doubtful_starts_track;
    out << YAML::Key << "look_gate_after_loss" << YAML::Value << e.task.look_gate_after_loss;
    out << YAML::Key << "refused_alone_frames" << YAML::Value << e.task.refused_alone_frames;
    out << YAML::Key << "look_refused_off_tracks" << YAML::Value << e.task.look_refused_off_tracks;
    out << YAML::Key << "lost_competing_colour_capped" << YAML::Value << e.task.lost_competing_colour_capped;
    out << YAML::Key << "verdict_torso_height_m" << YAML::Value << e.task.verdict_torso_height_m;
    out << YAML::Key << "verdict_torso_m" << YAML::Value << e.task.verdict_torso_m;
    const estimation::SwapCheckParams& w = e.task.swap_check;
    out << YAML::Key << "swap_check" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "frames" << YAML::Value << w.frames;
    out << YAML::Key << "chi2" << YAML::Value << w.chi2;
    out << YAML::Key << "horizon_s" << YAML::Value << w.horizon_s;
    out << YAML::Key << "confirm_frames" << YAML::Value << w.confirm_frames;
    out << YAML::EndMap;
    const estimation::DepthRangeParams& r = e.task.depth_range;
    out << YAML::Key << "depth_range" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "enabled" << YAML::Value << r.enabled;
    out << YAML::Key << "body_offset_m" << YAML::Value << r.body_offset_m;
    out << YAML::Key << "step_m" << YAML::Value << r.step_m;
    out << YAML::Key << "surface_tolerance_m" << YAML::Value << r.surface_tolerance_m;
    out << YAML::Key << "min_range_m" << YAML::Value << r.min_range_m;
    out << YAML::Key << "max_range_m" << YAML::Value << r.max_range_m;
    out << YAML::Key << "max_ratio" << YAML::Value << r.max_ratio;
    out << YAML::Key << "max_offset_s" << YAML::Value << r.max_offset_s;
    out << YAML::Key << "range_std_m" << YAML::Value << r.range_std_m;
    out << YAML::Key << "range_std_per_m2" << YAML::Value << r.range_std_per_m2;
    out << YAML::Key << "cross_std_per_m" << YAML::Value << r.cross_std_per_m;
    out << YAML::Key << "person_speed_mps" << YAML::Value << r.person_speed_mps;
    out << YAML::Key << "scale_rate" << YAML::Value << r.scale_rate;
    out << YAML::EndMap;
    const estimation::DepthPeopleParams& dp = e.task.depth_people;
    out << YAML::Key << "depth_people" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "enabled" << YAML::Value << dp.enabled;
    out << YAML::Key << "stride_px" << YAML::Value << dp.stride_px;
    out << YAML::Key << "max_range_m" << YAML::Value << dp.max_range_m;
    out << YAML::Key << "min_z_m" << YAML::Value << dp.min_z_m;
    out << YAML::Key << "min_top_m" << YAML::Value << dp.min_top_m;
    out << YAML::Key << "max_top_m" << YAML::Value << dp.max_top_m;
    out << YAML::Key << "max_width_m" << YAML::Value << dp.max_width_m;
    out << YAML::Key << "max_depth_m" << YAML::Value << dp.max_depth_m;
    out << YAML::Key << "depth_jump_m" << YAML::Value << dp.depth_jump_m;
    out << YAML::Key << "min_area_m2" << YAML::Value << dp.min_area_m2;
    out << YAML::Key << "split_two" << YAML::Value << dp.split_two;
    out << YAML::Key << "split_seam_m" << YAML::Value << dp.split_seam_m;
    out << YAML::Key << "centre_behind_m" << YAML::Value << dp.centre_behind_m;
    out << YAML::Key << "std_m" << YAML::Value << dp.std_m;
    out << YAML::Key << "std_per_m2" << YAML::Value << dp.std_per_m2;
    out << YAML::Key << "feed_followed" << YAML::Value << dp.feed_followed;
    out << YAML::Key << "feed_max_std_m" << YAML::Value << dp.feed_max_std_m;
    out << YAML::EndMap;
    out << YAML::Key << "estimator" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "accel_psd_xy_m2ps3" << YAML::Value << k.accel_psd_xy_m2ps3;
    out << YAML::Key << "accel_psd_z_m2ps3" << YAML::Value << k.accel_psd_z_m2ps3;
    out << YAML::Key << "measurement_std_xy_m" << YAML::Value << k.measurement_std_xy_m;
    out << YAML::Key << "measurement_std_z_m" << YAML::Value << k.measurement_std_z_m;
    out << YAML::Key << "initial_speed_std_mps" << YAML::Value << k.initial_speed_std_mps;
    out << YAML::Key << "gate_chi2" << YAML::Value << k.gate_chi2;
    out << YAML::Key << "reinit_after_rejections" << YAML::Value << k.reinit_after_rejections;
    out << YAML::Key << "lost_after_s" << YAML::Value << k.lost_after_s;
    out << YAML::Key << "replay_window_s" << YAML::Value << k.replay_window_s;
    out << YAML::Key << "max_buffered_measurements" << YAML::Value << k.max_buffered_measurements;
    out << YAML::Key << "manoeuvre_accel_psd_xy_m2ps3" << YAML::Value << k.manoeuvre_accel_psd_xy_m2ps3;
    out << YAML::Key << "steady_mean_s" << YAML::Value << k.steady_mean_s;
    out << YAML::Key << "manoeuvre_mean_s" << YAML::Value << k.manoeuvre_mean_s;
    out << YAML::Key << "hold_probabilities_coasting" << YAML::Value << k.hold_probabilities_coasting;
    out << YAML::EndMap;
    out << YAML::EndMap;
  }
  if (c.gimbal_control) {
    const gimbal_control::GimbalControlParams& g = *c.gimbal_control;
    out << YAML::Key << "gimbal_control" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "kp_per_s" << YAML::Value << g.kp_per_s;
    out << YAML::Key << "ki_per_s2" << YAML::Value << g.ki_per_s2;
    out << YAML::Key << "integral_limit_rad_s" << YAML::Value << g.integral_limit_rad_s;
    out << YAML::Key << "integral_zone_rad" << YAML::Value << g.integral_zone_rad;
    out << YAML::Key << "max_rate_radps" << YAML::Value << g.max_rate_radps;
    out << YAML::Key << "sweep_rate_radps" << YAML::Value << g.sweep_rate_radps;
    out << YAML::Key << "feed_forward" << YAML::Value << g.feed_forward;
    out << YAML::Key << "max_estimate_age_s" << YAML::Value << g.max_estimate_age_s;
    out << YAML::Key << "look_at_prediction_s" << YAML::Value << g.look_at_prediction_s;
    out << YAML::Key << "max_bearing_sigma_rad" << YAML::Value << g.max_bearing_sigma_rad;
    out << YAML::EndMap;
  }
  if (c.supervisor) {
    const supervisor::SupervisorParams& v = *c.supervisor;
    out << YAML::Key << "supervisor" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "takeoff_altitude_m" << YAML::Value << v.takeoff_altitude_m;
    out << YAML::Key << "takeoff_tolerance_m" << YAML::Value << v.takeoff_tolerance_m;
    out << YAML::Key << "relocate_after_s" << YAML::Value << v.relocate_after_s;
    out << YAML::Key << "relocate_timeout_s" << YAML::Value << v.relocate_timeout_s;
    out << YAML::Key << "search_timeout_s" << YAML::Value << v.search_timeout_s;
    out << YAML::Key << "hold_then_land_s" << YAML::Value << v.hold_then_land_s;
    out << YAML::Key << "odometry_timeout_s" << YAML::Value << v.odometry_timeout_s;
    out << YAML::Key << "depth_timeout_s" << YAML::Value << v.depth_timeout_s;
    out << YAML::Key << "camera_timeout_s" << YAML::Value << v.camera_timeout_s;
    out << YAML::Key << "gimbal_timeout_s" << YAML::Value << v.gimbal_timeout_s;
    out << YAML::Key << "max_planner_failures" << YAML::Value << v.max_planner_failures;
    out << YAML::Key << "overrun_storm" << YAML::Value << v.overrun_storm;
    out << YAML::Key << "overrun_window_s" << YAML::Value << v.overrun_window_s;
    out << YAML::Key << "startup_grace_s" << YAML::Value << v.startup_grace_s;
    out << YAML::EndMap;
  }
  if (c.planning) {
    out << YAML::Key << "planning" << YAML::Value;
    emitPlanningYaml(out, *c.planning);
  }
  out << YAML::Key << "realtime" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "realtime_priority" << YAML::Value << c.realtime.use_realtime_priority;
  out << YAML::Key << "affinity" << YAML::Value << c.realtime.use_affinity;
  out << YAML::Key << "lock_memory" << YAML::Value << c.realtime.lock_memory;
  out << YAML::EndMap;
  out << YAML::Key << "tasks" << YAML::Value << YAML::BeginSeq;
  for (const rt::TaskSpec& t : c.tasks) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << t.name;
    if (t.periodic()) out << YAML::Key << "rate_hz" << YAML::Value << t.rate_hz;
    if (t.triggered()) out << YAML::Key << "trigger" << YAML::Value << t.trigger;
    if (t.min_period_ms > 0.0) out << YAML::Key << "min_period_ms" << YAML::Value << t.min_period_ms;
    out << YAML::Key << "budget_ms" << YAML::Value << t.budget_ms;
    out << YAML::Key << "priority" << YAML::Value << t.priority;
    out << YAML::Key << "cpu" << YAML::Value << t.cpu;
    if (t.latency_ms > 0.0) out << YAML::Key << "latency_ms" << YAML::Value << t.latency_ms;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

}  // namespace aerotrack::app
