// The other people (issue 21 item 5: 0 collisions in the crowd). The target task tracks everyone it sees
// (TargetEstimate::others); the planner keeps min_bystander_distance_m from each one's constant-velocity path in
// its final check, also where the map does not show them yet, and moves out of the way of someone walking at
// a drone that hovers at its goal or would only brake. Off (0), they play no part.
#include <gtest/gtest.h>

#include <cmath>

#include "aerotrack/planning/tracking_planner.hpp"
#include "planner_test_util.hpp"
#include "search_test_util.hpp"

namespace aerotrack::planning {
namespace {

using test::defaultParams;
using test::makePlanner;

mapping::LocalGrid openGround() {
  return test::makeBoxGrid(Eigen::Vector3d(20, 20, 5), Eigen::Vector3d(0, 0, 1.5), {{{-10, -10, -0.2}, {10, 10, 0.0}}});
}

// The followed person standing at (x_m, 0), with `others` around them.
test::PlanCase personAt(double x_m, std::initializer_list<estimation::OtherPerson> others) {
  test::PlanCase c{openGround(), {}, {}};
  c.odometry.p_WB_m = Eigen::Vector3d(0, 0, 1.5);
  c.person.initialised = true;
  c.person.lost = false;
  c.person.p_WT_m = Eigen::Vector3d(x_m, 0.0, 1.0);
  for (const estimation::OtherPerson& other : others) c.person.others[c.person.other_count++] = other;
  return c;
}

// The closest `trajectory` comes to `other` on the path the planner predicts for them.
double closestApproachM(const PolynomialTrajectory& trajectory, const estimation::OtherPerson& other,
                        rt::TimeNs start_ns, const TrackingPlannerParams& params) {
  return test::closestApproachM(trajectory, other.p_W_m, other.v_W_mps, start_ns, params);
}

TEST(Bystanders, SomeoneWalkingAtADroneHoveringAtItsGoalIsSteppedAwayFrom) {
  const TrackingPlannerParams params = defaultParams();
  // The person stands at the tracking distance: the drone is at its goal, nothing to fly.
  {
    TrackingPlanner planner = makePlanner(params);
    const test::PlanCase alone = personAt(params.goal.tracking_distance_m, {});
    PolynomialTrajectory out;
    EXPECT_EQ(planner.plan(alone.inputs(), out).status, PlanStatus::kAtGoal);
  }
  // A passer-by 2 m to the side walks at it at 1.5 m/s: through the drone 1.3 s later.
  const estimation::OtherPerson walker{Eigen::Vector3d(0.0, 2.0, 1.0), Eigen::Vector3d(0.0, -1.5, 0.0)};
  TrackingPlanner planner = makePlanner(params);
  const test::PlanCase c = personAt(params.goal.tracking_distance_m, {walker});
  PolynomialTrajectory out;
  const PlanReport report = planner.plan(c.inputs(), out);
  ASSERT_EQ(report.status, PlanStatus::kEvading) << toString(report.status);
  EXPECT_LT(closestApproachM(PolynomialTrajectory(), walker, report.start_ns, params), 0.1);  // hovering on
  EXPECT_GE(closestApproachM(out, walker, report.start_ns, params), params.min_bystander_distance_m);
  EXPECT_LT(out.sample(out.durationS()).v_W_mps.norm(), 1e-6);
  const mapping::TrajectoryChecker checker = mapping::TrajectoryChecker::create(params.collision).value();
  EXPECT_EQ(checkTrajectory(out, params.check, c.grid, checker, nullptr).verdict, CheckVerdict::kOk);
}

TEST(Bystanders, APlanThroughSomeoneTheMapDoesNotShowIsRefused) {
  // The person stands 8 m ahead; someone stands on the straight way to the goal, not (yet) in the map.
  const estimation::OtherPerson standing{Eigen::Vector3d(3.0, 0.0, 1.0), Eigen::Vector3d::Zero()};
  TrackingPlannerParams params = defaultParams();
  {
    TrackingPlanner planner = makePlanner(params);
    const test::PlanCase c = personAt(8.0, {standing});
    PolynomialTrajectory out;
    const PlanReport report = planner.plan(c.inputs(), out);
    // Refused by the check; braking keeps far enough from them, so the failure stands (no evasion).
    EXPECT_EQ(report.status, PlanStatus::kCheckFailed) << toString(report.status);
    EXPECT_EQ(report.check, CheckVerdict::kTooCloseToBystander);
  }
  params.min_bystander_distance_m = 0.0;  // off: only the map counts
  TrackingPlanner planner = makePlanner(params);
  const test::PlanCase c = personAt(8.0, {standing});
  PolynomialTrajectory out;
  EXPECT_EQ(planner.plan(c.inputs(), out).status, PlanStatus::kPlanned);
}

TEST(Bystanders, SomeoneAlreadyCloseOnlyForbidsComingCloser) {
  // A person standing 0.6 m to the side (inside min_bystander_distance_m) of a drone that flies away from them
  // along +x: the plan moves no closer than it starts, so it passes.
  const estimation::OtherPerson beside{Eigen::Vector3d(-0.3, 0.6, 1.0), Eigen::Vector3d::Zero()};
  const TrackingPlannerParams params = defaultParams();
  TrackingPlanner planner = makePlanner(params);
  const test::PlanCase c = personAt(8.0, {beside});
  PolynomialTrajectory out;
  const PlanReport report = planner.plan(c.inputs(), out);
  EXPECT_EQ(report.status, PlanStatus::kPlanned) << toString(report.status) << " " << toString(report.check);
}

}  // namespace
}  // namespace aerotrack::planning
