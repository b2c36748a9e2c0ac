// The foundation's scenario file (config/scenarios/*.yaml): how long to fly, where the drone
// starts, and a tour of waypoints that stands in for the person until the full simulator (issue 3)
// brings obstacles, the walking person and the sensors.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::app {

struct Scenario {
  std::string name;
  std::string source;
  double duration_s = 0.0;
  Eigen::Vector3d drone_start_m = Eigen::Vector3d::Zero();
  double drone_start_yaw_rad = 0.0;
  double tour_start_delay_s = 0.0;
  double tour_max_speed_mps = 0.0;
  double tour_max_accel_mps2 = 0.0;
  std::vector<Eigen::Vector3d> tour_waypoints_m;
};

rt::Expected<Scenario> loadScenario(const std::string& path);
rt::Expected<Scenario> parseScenario(const std::string& yaml_text, const std::string& source_name);

}  // namespace aerotrack::app
