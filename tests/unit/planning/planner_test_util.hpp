// The tracking planner as its tests build it: the search's per-axis limits of the issue-8 tests (2 m/s,
// 2.5 m/s^2) and a 5 cm corridor margin; every other parameter its default.
#pragma once

#include <gtest/gtest.h>

#include <utility>

#include "aerotrack/planning/tracking_planner.hpp"

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

}  // namespace aerotrack::planning::test
