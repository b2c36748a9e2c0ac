// Scenario parsing: see scenario.hpp.
#include "scenario.hpp"

#include "aerotrack/rt/config_node.hpp"

namespace aerotrack::app {
namespace {

Eigen::Vector3d toVector3(const std::vector<double>& v) {
  return {v[0], v[1], v[2]};
}

Scenario parseRoot(const rt::ConfigNode& root) {
  Scenario s;
  s.source = root.sourceName();
  s.name = root.getString("name");
  s.duration_s = root.getDouble("duration_s", 0.01, 24.0 * 3600.0);
  const rt::ConfigNode drone = root.child("drone");
  s.drone_start_m = toVector3(drone.getDoubleList("start_m", 3, -1e4, 1e4));
  s.drone_start_yaw_rad = drone.getDouble("start_yaw_rad", -10.0, 10.0);
  drone.finish();
  const rt::ConfigNode tour = root.child("tour");
  s.tour_start_delay_s = tour.getDouble("start_delay_s", 0.0, 3600.0);
  s.tour_max_speed_mps = tour.getDouble("max_speed_mps", 0.1, 30.0);
  s.tour_max_accel_mps2 = tour.getDouble("max_accel_mps2", 0.1, 30.0);
  for (const auto& row : tour.getDoubleRows("waypoints_m", 3, -1e4, 1e4)) s.tour_waypoints_m.push_back(toVector3(row));
  if (s.tour_waypoints_m.empty()) tour.fail("waypoints_m", "needs at least one waypoint");
  tour.finish();
  root.finish();
  return s;
}

rt::Expected<Scenario> parseFrom(rt::Expected<rt::ConfigNode> root) {
  if (!root) return root.error();
  return rt::parseConfig<Scenario>([&] { return parseRoot(*root); });
}

}  // namespace

rt::Expected<Scenario> loadScenario(const std::string& path) {
  return parseFrom(rt::ConfigNode::loadFile(path));
}

rt::Expected<Scenario> parseScenario(const std::string& yaml_text, const std::string& source_name) {
  return parseFrom(rt::ConfigNode::fromString(yaml_text, source_name));
}

}  // namespace aerotrack::app
