// Random corridors for the optimiser's tests and benchmark: a chain of overlapping boxes around a random
// walk, with the waypoints and durations of a valid initial guess.
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include "aerotrack/planning/trajectory_optimizer.hpp"

namespace aerotrack::planning::test {

struct RandomCorridor {
  std::vector<CorridorBox> boxes;
  std::vector<Eigen::Vector3d> waypoints;
  std::vector<double> durations;
  StatePva start = StatePva::Zero();
  StatePva end = StatePva::Zero();
  TrajectoryProblem problem() const { return {start, end, boxes, waypoints, durations}; }
};

// A random walk P_0..P_M (steps of 1-3 m, turning up to 90 degrees, gentle climbs); box i is the
// bounding box of P_i and P_{i+1} grown by 0.25-0.6 m (tight boxes: the walls are close, as in clutter),
// so waypoint P_{i+1} lies strictly inside boxes i and i+1.
RandomCorridor randomCorridor(int m, std::mt19937& rng, double speed_mps = 1.5) {
  std::uniform_real_distribution<double> step(1.0, 3.0);
  std::uniform_real_distribution<double> turn(-1.5, 1.5);
  std::uniform_real_distribution<double> climb(-0.3, 0.3);
  std::uniform_real_distribution<double> grow(0.25, 0.6);
  RandomCorridor c;
  std::vector<Eigen::Vector3d> points{Eigen::Vector3d(0.0, 0.0, 1.5)};
  double heading = 0.0;
  for (int i = 0; i < m; ++i) {
    heading += turn(rng);
    const double d = step(rng);
    points.push_back(points.back() + Eigen::Vector3d(d * std::cos(heading), d * std::sin(heading), climb(rng)));
  }
  for (int i = 0; i < m; ++i) {
    const Eigen::Vector3d lo = points[i].cwiseMin(points[i + 1]);
    const Eigen::Vector3d hi = points[i].cwiseMax(points[i + 1]);
    CorridorBox box;
    box.lo_W_m = lo - Eigen::Vector3d(grow(rng), grow(rng), grow(rng));
    box.hi_W_m = hi + Eigen::Vector3d(grow(rng), grow(rng), grow(rng));
    c.boxes.push_back(box);
    c.durations.push_back((points[i + 1] - points[i]).norm() / speed_mps);
    if (i + 1 < m) c.waypoints.push_back(points[i + 1]);
  }
  c.start.col(0) = points.front();
  c.start.col(1) = Eigen::Vector3d(0.5, 0.0, 0.0);
  c.end.col(0) = points.back();
  return c;
}

}  // namespace aerotrack::planning::test
