// A tour through waypoints as rest-to-rest minimum-jerk legs: on each leg the position follows
// s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5 (tau = t / T), the closed-form minimum-jerk motion between
// two states at rest (Flash & Hogan 1985). Peak speed is 1.875 d / T and peak acceleration
// (10 / sqrt(3)) d / T^2, so each leg's duration T is the smallest that respects both limits.
// Used for take-off, landing and the foundation demo; tracking uses the optimiser (issue 8).
#pragma once

#include <vector>

#include "aerotrack/rt/expected.hpp"
#include "aerotrack/trajectory_server/trajectory.hpp"

namespace aerotrack::trajectory_server {

class MinJerkTour final : public Trajectory {
 public:
  /// Builds the tour. Error if there are fewer than two waypoints or a limit is not positive.
  static rt::Expected<MinJerkTour> create(std::vector<Eigen::Vector3d> waypoints_W_m, double max_speed_mps,
                                          double max_accel_mps2);

  double durationS() const override { return leg_start_s_.back(); }
  TrajectorySample sample(double t_s) const override;
  const std::vector<double>& legDurationsS() const { return leg_duration_s_; }

 private:
  MinJerkTour() = default;
  std::vector<Eigen::Vector3d> waypoints_W_m_;
  std::vector<double> leg_duration_s_;
  std::vector<double> leg_start_s_;  // cumulative; back() is the total duration
};

}  // namespace aerotrack::trajectory_server
