// The tracking planner and its task as their tests build them: the search's per-axis limits of the issue-8 tests (2
// m/s, 2.5 m/s^2) and a 5 cm corridor margin; every other parameter its default.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <limits>
#include <memory>
#include <utility>

#include "aerotrack/planning/planning_task.hpp"
#include "aerotrack/planning/tracking_planner.hpp"
#include "aerotrack/rt/clock.hpp"

namespace aerotrack::planning::test {

inline TrackingPlannerParams defaultParams() {
  TrackingPlannerParams p;
  p.search.max_velocity_mps = 2.0;
  p.search.max_acceleration_mps2 = 2.5;
  p.optimizer.corridor_margin_m = 0.05;
  return p;
}

inline TrackingPlanner makePlanner(const TrackingPlannerParams& params = defaultParams()) {
  auto planner = TrackingPlanner::create(params);
  EXPECT_TRUE(planner.has_value()) << (planner ? "" : planner.error().message);
  return std::move(planner).value();
}

/// The smallest horizontal distance between `trajectory` (held at its end; empty: the origin) and someone at
/// p_W_m walking at v_W_mps when the cycle runs (t = 0), extrapolated as the planner does (constant velocity for
/// prediction.horizon_s, then held), over the check's horizon from start_ns.
inline double closestApproachM(const PolynomialTrajectory& trajectory, const Eigen::Vector3d& p_W_m,
                               const Eigen::Vector3d& v_W_mps, rt::TimeNs start_ns,
                               const TrackingPlannerParams& params) {
  double min_m = std::numeric_limits<double>::infinity();
  for (double t = 0.0; t <= params.check.horizon_s; t += 0.01) {
    const double ahead_s = std::min(t + rt::nsToSeconds(start_ns), params.prediction.horizon_s);
    const Eigen::Vector3d person = p_W_m + ahead_s * v_W_mps;
    const Eigen::Vector3d drone = trajectory.durationS() > 0.0 ? trajectory.sample(t).p_W_m : Eigen::Vector3d::Zero();
    min_m = std::min(min_m, (drone - person).head<2>().norm());
  }
  return min_m;
}

/// A start state at rest at p.
inline StatePva restAt(const Eigen::Vector3d& p_W_m) {
  StatePva s = StatePva::Zero();
  s.col(0) = p_W_m;
  return s;
}

/// A live person estimate at p, with velocity v, stamped (and last accepted) at stamp_ns.
inline estimation::TargetEstimate personAt(const Eigen::Vector3d& p, rt::TimeNs stamp_ns,
                                           const Eigen::Vector3d& v = Eigen::Vector3d::Zero()) {
  estimation::TargetEstimate e;
  e.stamp_ns = stamp_ns;
  e.initialised = true;
  e.lost = false;
  e.p_WT_m = p;
  e.v_WT_mps = v;
  e.last_accepted_ns = stamp_ns;
  return e;
}

/// One planning cycle's inputs as a test owns them: a grid, the drone's odometry, the person's estimate.
struct PlanCase {
  mapping::LocalGrid grid;
  hal::OdometrySample odometry;
  estimation::TargetEstimate person;
  PlanInputs inputs() const {
    PlanInputs in;
    in.odometry = &odometry;
    in.target = &person;
    in.grid = &grid;
    return in;
  }
};

/// The planning task's channels and stats clock, as a test owns them.
struct TaskChannels {
  rt::LatestSlot<hal::OdometrySample> odometry;
  rt::LatestSlot<estimation::TargetEstimate> target;
  rt::SharedSlot<mapping::LocalGrid> grid;
  rt::SharedSlot<octomap::OcTree> octree;
  rt::SharedSlot<trajectory_server::TimedTrajectory> trajectories;
  rt::ManualClock clock{0};

  PlanningChannels channels(const rt::LatestSlot<supervisor::SupervisorState>* modes = nullptr) {
    return PlanningChannels{odometry, target, grid, octree, trajectories, modes};
  }
};

/// One planning-task cycle at t = 0 on `grid`, `odometry` and `target`, the failures-in-a-row channel starting
/// at 7 (a streak under way); then check(task, rig, failures after the cycle).
template <typename Check>
void stepTaskOnce(const mapping::LocalGrid& grid, const hal::OdometrySample& odometry,
                  const estimation::TargetEstimate& target, Check&& check) {
  TaskChannels rig;
  std::atomic<int> failures{7};
  PlanningChannels channels = rig.channels();
  channels.failures_in_a_row = &failures;
  PlanningTask task(makePlanner(), channels, rig.clock);
  rig.grid.write(std::make_shared<const mapping::LocalGrid>(grid));
  rig.odometry.write(odometry);
  rig.target.write(target);
  task.step(0);
  check(task, rig, failures.load());
}

}  // namespace aerotrack::planning::test
