// Reading scenario files: see scenario.hpp and config/scenarios/README.md. Every key is checked
// (rt::ConfigNode); optional sections keep the defaults written in scenario.hpp.
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "aerotrack/hal/sim/scenario.hpp"

#include "aerotrack/hal/sim/cast_file.hpp"
#include "aerotrack/hal/sim/obstacle_world.hpp"
#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/input_limits.hpp"

namespace aerotrack::hal::sim {
namespace {

using rt::ConfigNode;

constexpr double kBig = rt::limits::kMaxWorldExtentM;  // every coordinate, the input policy

Eigen::Vector2d vec2(const ConfigNode& n, const std::string& key, double lo = -kBig, double hi = kBig) {
  const auto v = n.getDoubleList(key, 2, lo, hi);
  return {v[0], v[1]};
}

Eigen::Vector3d vec3(const ConfigNode& n, const std::string& key, double lo = -kBig, double hi = kBig) {
  const auto v = n.getDoubleList(key, 3, lo, hi);
  return {v[0], v[1], v[2]};
}

Eigen::Vector3d vec3Or(const ConfigNode& n, const std::string& key, const Eigen::Vector3d& fallback) {
  return n.has(key) ? vec3(n, key) : fallback;
}

/// region_min_m and region_max_m, [x, y] each, with max > min.
void parseRegion(const ConfigNode& n, Eigen::Vector2d& min_m, Eigen::Vector2d& max_m) {
  min_m = vec2(n, "region_min_m");
  max_m = vec2(n, "region_max_m");
  if ((max_m.array() <= min_m.array()).any()) n.fail("region_max_m", "must exceed region_min_m");
}

std::vector<Box> parseBoxes(const ConfigNode& root) {
  std::vector<Box> boxes;
  if (!root.has("boxes")) return boxes;
  for (const ConfigNode& b : root.childList("boxes")) {
    Box box{vec3(b, "min_m"), vec3(b, "max_m")};
    if ((box.max_W_m.array() <= box.min_W_m.array()).any()) b.fail("max_m", "must be greater than min_m on every axis");
    b.finish();
    boxes.push_back(box);
  }
  return boxes;
}

std::vector<Cylinder> parseCylinders(const ConfigNode& root) {
  std::vector<Cylinder> cylinders;
  if (!root.has("cylinders")) return cylinders;
  for (const ConfigNode& c : root.childList("cylinders")) {
    Cylinder cyl;
    cyl.center_W_m = vec2(c, "center_m");
    cyl.radius_m = c.getDouble("radius_m", 0.01, 50.0);
    cyl.z_min_m = c.getDoubleOr("z_min_m", 0.0, -kBig, kBig);
    cyl.z_max_m = c.getDouble("height_m", 0.01, 1000.0) + cyl.z_min_m;
    c.finish();
    cylinders.push_back(cyl);
  }
  return cylinders;
}

ForestGenerator parseForest(const ConfigNode& n) {
  ForestGenerator f;
  parseRegion(n, f.region_min_m, f.region_max_m);
  f.density_per_m2 = n.getDouble("density_per_m2", 0.0, 2.0);
  const auto radius = n.getDoubleList("radius_m", 2, 0.01, 5.0);
  f.radius_min_m = radius[0];
  f.radius_max_m = radius[1];
  if (f.radius_max_m < f.radius_min_m) n.fail("radius_m", "[min, max] with min <= max");
  f.height_m = n.getDouble("height_m", 0.1, 100.0);
  f.min_gap_m = n.getDouble("min_gap_m", 0.0, 20.0);
  f.path_clearance_m = n.getDouble("path_clearance_m", 0.0, 20.0);
  const Eigen::Vector2d size_m = f.region_max_m - f.region_min_m;
  const double trees = f.density_per_m2 * size_m.x() * size_m.y();
  if (trees > static_cast<double>(rt::limits::kMaxObstacles))
    n.fail("density_per_m2", "gives " + std::to_string(std::llround(trees)) +
                                 " trees over the region, more than the limit of " +
                                 std::to_string(rt::limits::kMaxObstacles) + " obstacles");
  n.finish();
  return f;
}

CorridorGenerator parseCorridor(const ConfigNode& n) {
  CorridorGenerator c;
  for (const auto& row : n.getDoubleRows("centreline_m", 2, -kBig, kBig)) c.centreline_m.emplace_back(row[0], row[1]);
  if (c.centreline_m.size() < 2) n.fail("centreline_m", "needs at least two points");
  c.width_m = n.getDouble("width_m", 0.8, 50.0);
  c.wall_thickness_m = n.getDouble("wall_thickness_m", 0.05, 5.0);
  c.height_m = n.getDouble("height_m", 0.5, 100.0);
  c.clutter_count = n.getInt("clutter_count", 0, 10000);
  c.clutter_depth_max_m = n.getDouble("clutter_depth_max_m", 0.05, 10.0);
  const auto length = n.getDoubleList("clutter_length_m", 2, 0.05, 50.0);
  c.clutter_length_min_m = length[0];
  c.clutter_length_max_m = length[1];
  c.clutter_height_m = n.getDouble("clutter_height_m", 0.05, 100.0);
  if (c.clutter_depth_max_m > 0.45 * c.width_m)
    n.fail("clutter_depth_max_m", "must leave at least 10 % of the width free");
  n.finish();
  return c;
}

/// An optional [min, max] range with min <= max, each in [lo, hi].
void rangeOr(const ConfigNode& n, const std::string& key, double lo, double hi, double& min_out, double& max_out) {
  if (!n.has(key)) return;
  const auto r = n.getDoubleList(key, 2, lo, hi);
  if (r[1] < r[0]) n.fail(key, "a range is [min, max] with min <= max");
  min_out = r[0];
  max_out = r[1];
}

/// person.random_path.behaviours: every key optional (defaults in scenario.hpp, PathBehaviours).
PathBehaviours parseBehaviours(const ConfigNode& n) {
  PathBehaviours b;
  b.sprint_probability = n.getDoubleOr("sprint_probability", 0.0, 0.0, 1.0);
  rangeOr(n, "sprint_speed_mps", 0.1, 6.0, b.sprint_speed_min_mps, b.sprint_speed_max_mps);
  b.sprint_accel_mps2 = n.getDoubleOr("sprint_accel_mps2", 0.0, 0.1, 10.0);
  b.speed_change_probability = n.getDoubleOr("speed_change_probability", 0.0, 0.0, 1.0);
  rangeOr(n, "speed_change_mps", 0.1, 6.0, b.speed_change_min_mps, b.speed_change_max_mps);
  b.pause_probability = n.getDoubleOr("pause_probability", 0.0, 0.0, 1.0);
  rangeOr(n, "pause_s", 0.0, 600.0, b.pause_min_s, b.pause_max_s);
  b.reversal_probability = n.getDoubleOr("reversal_probability", 0.0, 0.0, 1.0);
  rangeOr(n, "reversal_m", 0.5, 1000.0, b.reversal_min_m, b.reversal_max_m);
  b.backwards_probability = n.getDoubleOr("backwards_probability", 0.0, 0.0, 1.0);
  rangeOr(n, "backwards_speed_mps", 0.1, 3.0, b.backwards_speed_min_mps, b.backwards_speed_max_mps);
  n.finish();
  return b;
}

RandomPathGenerator parseRandomPath(const ConfigNode& n) {
  RandomPathGenerator g;
  parseRegion(n, g.region_min_m, g.region_max_m);
  g.legs = n.getInt("legs", 1, 1000);
  const auto leg = n.getDoubleList("leg_m", 2, 0.5, 1000.0);
  g.leg_min_m = leg[0];
  g.leg_max_m = leg[1];
  g.max_turn_rad = n.getDouble("max_turn_rad", 0.0, M_PI);
  const auto speed = n.getDoubleList("speed_mps", 2, 0.0, 20.0);
  g.speed_min_mps = speed[0];
  g.speed_max_mps = speed[1];
  if (g.leg_max_m < g.leg_min_m || g.speed_max_mps < g.speed_min_mps) n.fail("leg_m", "ranges are [min, max]");
  if (n.has("behaviours")) g.behaviours = parseBehaviours(n.child("behaviours"));
  n.finish();
  return g;
}

/// person: the optional speed-profile keys (defaults and sources in walking_person.hpp, PersonParams).
void parsePersonMotion(const ConfigNode& n, PersonParams& p) {
  p.max_accel_mps2 = n.getDoubleOr("max_accel_mps2", p.max_accel_mps2, 0.1, 10.0);
  p.corner_radius_m = n.getDoubleOr("corner_radius_m", p.corner_radius_m, 0.0, 10.0);
  p.max_lateral_accel_mps2 = n.getDoubleOr("max_lateral_accel_mps2", p.max_lateral_accel_mps2, 0.1, 20.0);
  p.max_yaw_rate_radps = n.getDoubleOr("max_yaw_rate_radps", p.max_yaw_rate_radps, 0.1, 20.0);
  p.wide_corners = n.getBoolOr("wide_corners", p.wide_corners);
  p.max_corner_cut_m = n.getDoubleOr("max_corner_cut_m", p.max_corner_cut_m, 0.0, 10.0);
  p.max_backward_speed_mps = n.getDoubleOr("max_backward_speed_mps", p.max_backward_speed_mps, 0.1, 3.0);
}

void parsePerson(const ConfigNode& n, ScenarioSpec& s) {
  s.person.height_m = n.getDouble("height_m", 1.0, 2.5);
  s.person.torso_m = n.getDouble("torso_m", 0.2, 1.0);
  s.person_start_delay_s = n.getDouble("start_delay_s", 0.0, 600.0);
  parsePersonMotion(n, s.person);
  if (n.has("path")) {
    for (const ConfigNode& p : n.childList("path")) {
      PathPoint point;
      point.p_W_m = vec2(p, "p_m");
      point.speed_mps = p.getDouble("speed_mps", 0.0, 20.0);
      point.pause_s = p.getDoubleOr("pause_s", 0.0, 0.0, 3600.0);
      point.backwards = p.getBoolOr("backwards", false);
      point.accel_mps2 = p.getDoubleOr("accel_mps2", 0.0, 0.1, 10.0);
      if (point.backwards && point.speed_mps > s.person.max_backward_speed_mps)
        p.fail("speed_mps", "a backward leg's speed must not exceed person.max_backward_speed_mps (" +
                                std::to_string(s.person.max_backward_speed_mps) + ")");
      p.finish();
      s.path.push_back(point);
    }
  }
  if (n.has("random_path")) s.random_path = parseRandomPath(n.child("random_path"));
  if (s.path.empty() == !s.random_path.has_value())
    n.fail("path", "give exactly one of path (waypoints) or random_path (generator)");
  if (!s.path.empty() && s.path.size() < 2) n.fail("path", "needs at least two points");
  n.finish();
}

/// The person walks on the ground: a waypoint inside a listed box or cylinder, or a leg through
/// one, is a scenario that cannot happen (checked at the height of the shins, like a bystander's).
/// Generated obstacles are kept clear of the path by their generators.
void checkPersonPath(const ConfigNode& person, const ScenarioSpec& s) {
  if (s.path.empty()) return;
  auto world = ObstacleWorld::create(s.boxes, s.cylinders);
  if (!world) person.fail("path", "the listed obstacles are invalid: " + world.error().message);
  constexpr double kCheckHeightM = 0.3;
  const std::vector<ConfigNode> points = person.childList("path");
  for (std::size_t i = 0; i < s.path.size(); ++i) {
    const Eigen::Vector3d here(s.path[i].p_W_m.x(), s.path[i].p_W_m.y(), kCheckHeightM);
    if (world->distance(here) <= 0.0) points[i].fail("p_m", "lies inside an obstacle");
    if (i == 0) continue;
    const Eigen::Vector3d prev(s.path[i - 1].p_W_m.x(), s.path[i - 1].p_W_m.y(), kCheckHeightM);
    if (!world->segmentClear(prev, here)) points[i].fail("p_m", "the leg to this point passes through an obstacle");
  }
}

/// sensors.odometry.drift: every key optional (default 0: no drift).
OdometryDriftSpec parseOdometryDrift(const ConfigNode& n) {
  OdometryDriftSpec d;
  d.position_m_per_sqrt_m = n.getDoubleOr("position_m_per_sqrt_m", 0.0, 0.0, 10.0);
  d.z_m_per_sqrt_m = n.getDoubleOr("z_m_per_sqrt_m", 0.0, 0.0, 10.0);
  d.yaw_rad_per_sqrt_m = n.getDoubleOr("yaw_rad_per_sqrt_m", 0.0, 0.0, 1.0);
  d.position_m_per_sqrt_s = n.getDoubleOr("position_m_per_sqrt_s", 0.0, 0.0, 10.0);
  d.yaw_rad_per_sqrt_s = n.getDoubleOr("yaw_rad_per_sqrt_s", 0.0, 0.0, 1.0);
  if (n.has("jumps")) {
    for (const ConfigNode& j : n.childList("jumps")) {
      OdometryJump jump;
      jump.t_s = j.getDouble("t_s", 0.0, 24.0 * 3600.0);
      jump.dp_m = vec3(j, "dp_m", -100.0, 100.0);
      jump.dyaw_rad = j.getDoubleOr("dyaw_rad", 0.0, -M_PI, M_PI);
      j.finish();
      if (!d.jumps.empty() && jump.t_s < d.jumps.back().t_s) j.fail("t_s", "jumps must be listed in time order");
      d.jumps.push_back(jump);
    }
  }
  if (n.has("random_jumps")) {
    const ConfigNode r = n.child("random_jumps");
    d.random_jumps_per_min = r.getDouble("rate_per_min", 0.0, 60.0);
    d.random_jump_position_m = r.getDouble("position_m", 0.0, 100.0);
    d.random_jump_yaw_rad = r.getDoubleOr("yaw_rad", 0.0, 0.0, M_PI);
    r.finish();
  }
  n.finish();
  return d;
}

/// The top-level wind section: mean_mps required, the rest optional.
WindSpec parseWind(const ConfigNode& n) {
  WindSpec w;
  w.mean_W_mps = vec3(n, "mean_mps", -50.0, 50.0);
  if (n.has("gust_sigma_mps")) w.gust_sigma_mps = vec3(n, "gust_sigma_mps", 0.0, 20.0);
  if (n.has("gust_time_constant_s")) w.gust_time_constant_s = vec3(n, "gust_time_constant_s", 0.01, 1000.0);
  w.body_cd_area_m2 = n.getDoubleOr("body_cd_area_m2", 0.0, 0.0, 10.0);
  w.air_density_kgpm3 = n.getDoubleOr("air_density_kgpm3", w.air_density_kgpm3, 0.1, 2.0);
  n.finish();
  return w;
}

void parseSensors(const ConfigNode& n, ScenarioSpec& s) {
  if (n.has("gimbal_camera")) {
    const ConfigNode c = n.child("gimbal_camera");
    GimbalCameraSpec& g = s.gimbal_camera;
    // Optional: keypoints (the detector's output, default) or image (rendered frames).
    if (c.has("mode")) {
      g.mode = c.getEnum("mode", {"keypoints", "image"}) == "image" ? GimbalCameraMode::kImage
                                                                    : GimbalCameraMode::kKeypoints;
    }
    // Optional: the people image mode draws (a cast file, relative to the scenario's folder) and the
    // target among them (default: the cast's first).
    if (c.has("people")) {
      const std::string file = c.getString("people");
      const std::filesystem::path path = std::filesystem::path(file).is_absolute()
                                             ? std::filesystem::path(file)
                                             : std::filesystem::path(s.source).parent_path() / file;
      auto cast = loadCastFile(path.lexically_normal().string());
      if (!cast) c.fail("people", cast.error().message);
      g.cast = std::move(cast.value());
    }
    if (c.has("target_person")) {
      const auto found = findPerson(g.cast, c.getString("target_person"));
      if (!found) c.fail("target_person", found.error().message);
      g.target_person = found.value();
    }
    g.rate_hz = c.getDouble("rate_hz", 1.0, 240.0);
    g.latency_s = c.getDouble("latency_s", 0.0, 1.0);
    g.mount_B_m = vec3Or(c, "mount_m", g.mount_B_m);
    const int width = c.getInt("width_px", 32, 8192);
    const int height = c.getInt("height_px", 32, 8192);
    const double hfov_rad = c.getDouble("hfov_deg", 10.0, 170.0) * M_PI / 180.0;
    g.camera.intrinsics.width_px = width;
    g.camera.intrinsics.height_px = height;
    g.camera.intrinsics.fx_px = 0.5 * width / std::tan(0.5 * hfov_rad);
    g.camera.intrinsics.fy_px = g.camera.intrinsics.fx_px;
    g.camera.intrinsics.cx_px = 0.5 * width;
    g.camera.intrinsics.cy_px = 0.5 * height;
    g.camera.pixel_noise_torso_fraction = c.getDouble("pixel_noise_torso_fraction", 0.0, 1.0);
    g.camera.keypoint_miss_probability = c.getDouble("keypoint_miss_probability", 0.0, 1.0);
    c.finish();
  }
  if (n.has("depth_camera")) {
    const ConfigNode c = n.child("depth_camera");
    DepthCameraSpec& d = s.depth_camera;
    d.rate_hz = c.getDouble("rate_hz", 1.0, 90.0);
    d.mount_B_m = vec3Or(c, "mount_m", d.mount_B_m);
    d.camera.width_px = c.getInt("width_px", 8, 1280);
    d.camera.height_px = c.getInt("height_px", 6, 720);
    d.camera.hfov_deg = c.getDouble("hfov_deg", 10.0, 170.0);
    d.camera.vfov_deg = c.getDouble("vfov_deg", 10.0, 170.0);
    d.camera.min_range_m = c.getDouble("min_range_m", 0.0, 10.0);
    d.camera.max_range_m = c.getDouble("max_range_m", 0.5, 100.0);
    d.camera.noise_coeff_per_m = c.getDouble("noise_coeff_per_m", 0.0, 1.0);
    d.camera.dropout_probability = c.getDouble("dropout_probability", 0.0, 1.0);
    if (d.camera.max_range_m <= d.camera.min_range_m) c.fail("max_range_m", "must exceed min_range_m");
    c.finish();
  }
  if (n.has("odometry")) {
    const ConfigNode c = n.child("odometry");
    OdometrySpec& o = s.odometry;
    o.rate_hz = c.getDouble("rate_hz", 1.0, 1000.0);
    o.latency_s = c.getDouble("latency_s", 0.0, 1.0);
    o.position_noise_m = c.getDouble("position_noise_m", 0.0, 10.0);
    o.velocity_noise_mps = c.getDouble("velocity_noise_mps", 0.0, 10.0);
    o.yaw_noise_rad = c.getDouble("yaw_noise_rad", 0.0, 1.0);
    if (c.has("drift")) o.drift = parseOdometryDrift(c.child("drift"));
    c.finish();
  }
  if (n.has("gimbal")) {
    const ConfigNode c = n.child("gimbal");
    GimbalSpec& g = s.gimbal;
    g.max_rate_radps = c.getDouble("max_rate_radps", 0.1, 100.0);
    g.time_constant_s = c.getDouble("time_constant_s", 0.001, 5.0);
    g.encoder_resolution_rad = c.getDouble("encoder_resolution_rad", 0.0, 0.1);
    g.angle_gain_per_s = c.getDouble("angle_gain_per_s", 0.1, 100.0);
    c.finish();
  }
  n.finish();
}

ScenarioSpec parseRoot(const ConfigNode& root) {
  ScenarioSpec s;
  s.source = root.sourceName();
  s.name = root.getString("name");
  // The name becomes a folder and file names of the results: a word, never a path.
  if (s.name.empty() || s.name.size() > 64 || s.name.front() == '.' ||
      !std::all_of(s.name.begin(), s.name.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '-' || c == '.';
      }))
    root.fail("name", "must be 1-64 letters, digits, '_', '-' or '.', not starting with '.' (it names output files)");
  s.end_margin_s = root.getDouble("end_margin_s", 0.0, 3600.0);
  s.max_duration_s = root.getDouble("max_duration_s", 1.0, rt::limits::kMaxRunS);

  const ConfigNode world = root.child("world");
  s.bounds_min_m = vec3(world, "bounds_min_m");
  s.bounds_max_m = vec3(world, "bounds_max_m");
  if ((s.bounds_max_m.array() <= s.bounds_min_m.array()).any()) world.fail("bounds_max_m", "must exceed bounds_min_m");
  s.boxes = parseBoxes(world);
  s.cylinders = parseCylinders(world);
  if (world.has("forest")) s.forest = parseForest(world.child("forest"));
  if (world.has("corridor")) s.corridor = parseCorridor(world.child("corridor"));
  world.finish();

  parsePerson(root.child("person"), s);
  checkPersonPath(root.child("person"), s);

  const ConfigNode drone = root.child("drone");
  s.drone.start_m = vec3(drone, "start_m");
  s.drone.start_yaw_rad = drone.getDouble("start_yaw_rad", -10.0, 10.0);
  if (drone.has("start_behind_person_m"))
    s.drone.start_behind_person_m = drone.getDouble("start_behind_person_m", 0.0, 100.0);
  s.drone.radius_m = drone.getDouble("radius_m", 0.05, 2.0);
  s.drone.mass_kg = drone.getDouble("mass_kg", 0.05, 50.0);
  s.drone.thrust_to_weight = drone.getDouble("thrust_to_weight", 1.1, 10.0);
  drone.finish();

  if (root.has("randomize")) {
    const ConfigNode r = root.child("randomize");
    s.randomize.obstacle_jitter_m = r.getDouble("obstacle_jitter_m", 0.0, 10.0);
    s.randomize.mirror_y = r.getBool("mirror_y");
    s.randomize.speed_jitter_fraction = r.getDouble("speed_jitter_fraction", 0.0, 0.9);
    r.finish();
  }
  if (root.has("sensors")) parseSensors(root.child("sensors"), s);
  if (root.has("wind")) s.wind = parseWind(root.child("wind"));

  const ConfigNode success = root.child("success");
  s.success.tracking_distance_m = success.getDouble("tracking_distance_m", 0.5, 50.0);
  s.success.final_distance_factor = success.getDouble("final_distance_factor", 1.0, 100.0);
  s.success.max_loss_s = success.getDoubleOr("max_loss_s", s.success.max_loss_s, 0.1, 600.0);
  s.success.max_distance_m = success.getDoubleOr("max_distance_m", 0.0, 0.5, 1000.0);
  if (s.success.max_distance_m > 0.0 && s.success.max_distance_m <= s.success.tracking_distance_m)
    success.fail("max_distance_m", "must be greater than tracking_distance_m (" +
                                       rt::formatConfigNumber(s.success.tracking_distance_m) + " m)");
  success.finish();
  if (root.has("bystanders")) s.bystanders = parseBystanders(root.child("bystanders"), s.boxes, s.cylinders);
  if (root.has("supervisor")) {  // overrides of the config's supervisor section
    const ConfigNode supervisor = root.child("supervisor");
    s.search_timeout_s = supervisor.getDouble("search_timeout_s", 0.0, 3600.0);
    supervisor.finish();
  }
  root.finish();
  return s;
}

rt::Expected<ScenarioSpec> parseFrom(rt::Expected<ConfigNode> root) {
  if (!root) return root.error();
  return rt::parseConfig<ScenarioSpec>([&] { return parseRoot(*root); });
}

}  // namespace

rt::Expected<ScenarioSpec> loadScenarioSpec(const std::string& path) {
  return parseFrom(ConfigNode::loadFile(path));
}

rt::Expected<ScenarioSpec> parseScenarioSpec(const std::string& yaml_text, const std::string& source_name) {
  return parseFrom(ConfigNode::fromString(yaml_text, source_name));
}

}  // namespace aerotrack::hal::sim
