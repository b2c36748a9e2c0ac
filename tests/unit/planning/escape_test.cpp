// Escape from an inflation margin (issue 21 item 2): a start in an obstacle's margin is where no search can
// begin (start_blocked), and before this every later cycle failed the same way: crossing seed 18 hovered
// 30 s beside a crosser's mapped torso while the person walked 39 m away. The planner now flies a short move
// to rest at the nearest free point in plain sight, inside the final check; the next cycle plans from there.
// Boxed in (nothing free within reach), the failure stands. The planning task flies the escape and does not
// count it towards degraded.
#include <gtest/gtest.h>

#include "aerotrack/planning/planning_task.hpp"
#include "aerotrack/planning/tracking_planner.hpp"
#include "planner_test_util.hpp"
#include "search_test_util.hpp"

namespace aerotrack::planning {
namespace {

using test::defaultParams;
using test::makePlanner;

using EscapeCase = test::PlanCase;

// The drone hovers at (0, 0, 1.5); a mapped torso (x 0.1-0.5, |y| <= 0.3, z 0.9-1.8) lies 0.15 m from it,
// inside the 0.25 m inflation; the person stands 3 m behind the drone, the other way.
EscapeCase besideATorso(const std::vector<test::OccupiedBox>& extra = {}) {
  std::vector<test::OccupiedBox> boxes = extra;
  boxes.push_back({{-10, -10, -0.2}, {10, 10, 0.0}});  // the ground
  boxes.push_back({{0.1, -0.3, 0.9}, {0.5, 0.3, 1.8}});
  EscapeCase c{test::makeBoxGrid(Eigen::Vector3d(20, 20, 5), Eigen::Vector3d(0, 0, 1.5), boxes),
               {},
               test::personAt(Eigen::Vector3d(-3.0, 0.0, 1.0), 0)};
  c.odometry.p_WB_m = Eigen::Vector3d(0, 0, 1.5);
  return c;
}

TEST(Escape, AStartInAMarginMovesToTheNearestFreePointAndTheNextCyclePlansFromThere) {
  const TrackingPlannerParams params = defaultParams();
  TrackingPlanner planner = makePlanner(params);
  const EscapeCase c = besideATorso();
  ASSERT_TRUE(c.grid.isOccupied(c.odometry.p_WB_m)) << "the case starts in the margin";
  PolynomialTrajectory out;
  const PlanReport report = planner.plan(c.inputs(), out);
  ASSERT_EQ(report.status, PlanStatus::kEscaping) << toString(report.status);
  EXPECT_EQ(report.search_status, SearchStatus::kStartBlocked);

  // To rest at a free point within reach, away from the torso, never through it, within the dynamic limits.
  const trajectory_server::TrajectorySample end = out.sample(out.durationS());
  EXPECT_FALSE(c.grid.isOccupied(end.p_W_m)) << end.p_W_m.transpose();
  EXPECT_LT(end.v_W_mps.norm(), 1e-6);
  EXPECT_LE((end.p_W_m - c.odometry.p_WB_m).norm(), 1.0);
  EXPECT_LT(end.p_W_m.x(), 0.0) << "away from the torso";
  EXPECT_GE(end.p_W_m.z(), params.min_altitude_m - 0.05);
  for (double t = 0.0; t <= out.durationS(); t += 0.005) {
    EXPECT_NE(c.grid.state(out.sample(t).p_W_m), mapping::CellState::kOccupied) << t;
  }
  TrajectoryCheckParams check = params.check;
  check.margin_escape_s = out.durationS();
  const mapping::TrajectoryChecker checker = mapping::TrajectoryChecker::create(params.collision).value();
  EXPECT_EQ(checkTrajectory(out, check, c.grid, checker, nullptr).verdict, CheckVerdict::kOk);

  // The next cycle, from the escape's end: a plan as usual.
  EscapeCase after = besideATorso();
  after.odometry.p_WB_m = end.p_W_m;
  EXPECT_EQ(planner.plan(after.inputs(), out).status, PlanStatus::kPlanned);
}

TEST(Escape, BoxedInWithNothingFreeWithinReachTheFailureStands) {
  // A closed box of walls 0.15-0.4 m from the drone on every side, above and below: every cell inside is in
  // their margin, and the free cells within 1 m lie behind a wall.
  const std::vector<test::OccupiedBox> walls = {
      {{-0.4, -0.4, 1.1}, {-0.15, 0.4, 1.9}}, {{0.15, -0.4, 1.1}, {0.4, 0.4, 1.9}},
      {{-0.4, -0.4, 1.1}, {0.4, -0.15, 1.9}}, {{-0.4, 0.15, 1.1}, {0.4, 0.4, 1.9}},
      {{-0.4, -0.4, 1.1}, {0.4, 0.4, 1.35}},  {{-0.4, -0.4, 1.65}, {0.4, 0.4, 1.9}},
  };
  TrackingPlanner planner = makePlanner();
  const EscapeCase c = besideATorso(walls);
  PolynomialTrajectory out;
  const PlanReport report = planner.plan(c.inputs(), out);
  EXPECT_EQ(report.status, PlanStatus::kSearchFailed) << toString(report.status);
  EXPECT_EQ(report.search_status, SearchStatus::kStartBlocked);
}

TEST(Escape, PlanningTaskFliesTheEscapeAndDoesNotCountItAsAFailure) {
  const EscapeCase c = besideATorso();
  test::stepTaskOnce(c.grid, c.odometry, c.person, [](const PlanningTask& task, test::TaskChannels& rig, int failures) {
    EXPECT_EQ(task.count(PlanStatus::kEscaping), 1U);
    ASSERT_TRUE(task.lastPublished().trajectory);
    EXPECT_EQ(rig.trajectories.version(), 1U);
    EXPECT_EQ(failures, 0);
  });
}

}  // namespace
}  // namespace aerotrack::planning
