// Tests of the goals the kinodynamic search can reach (issue 21 item 6, the planning tail): a goal beyond the
// grid's window clipped to it (clipGoalToWindow), and a goal velocity over the per-axis limit scaled into it.
// Before these, a drone far behind a runner searched every cycle for a goal it could never reach and spent
// the whole expansion budget each time.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "aerotrack/planning/kinodynamic_search.hpp"
#include "search_test_util.hpp"
#include "support/require.hpp"

namespace aerotrack::planning {
namespace {

using test::makeBoxGrid;

KinematicState stateAt(const Eigen::Vector3d& p_W_m, const Eigen::Vector3d& v_W_mps = Eigen::Vector3d::Zero()) {
  KinematicState s;
  s.p_W_m = p_W_m;
  s.v_W_mps = v_W_mps;
  return s;
}

// A 20 x 20 x 5 m window centred on (0, 0, 1.5): x, y in [-10, 10), z in [-1, 4).
mapping::LocalGrid emptyWindow() {
  return makeBoxGrid(Eigen::Vector3d(20.0, 20.0, 5.0), Eigen::Vector3d(0.0, 0.0, 1.5), {});
}

// Distance from p to the line through a and b.
double offLine(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return (p - a).cross((b - a).normalized()).norm();
}

TEST(ClipGoalToWindow, AGoalInsideTheShrunkWindowIsLeftAlone) {
  const mapping::LocalGrid grid = emptyWindow();
  KinematicState goal = stateAt(Eigen::Vector3d(8.0, -7.5, 1.5), Eigen::Vector3d(2.0, 0.0, 0.0));
  const KinematicState before = goal;
  EXPECT_FALSE(clipGoalToWindow(grid, Eigen::Vector3d::Zero(), 1.2, goal));
  EXPECT_EQ(goal.p_W_m, before.p_W_m);
  EXPECT_EQ(goal.v_W_mps, before.v_W_mps);
}

TEST(ClipGoalToWindow, AGoalBeyondTheWindowMovesAlongTheLineFromTheDroneToTheMarginHorizontally) {
  const mapping::LocalGrid grid = emptyWindow();
  const Eigen::Vector3d from(1.0, 2.0, 1.5);
  for (const Eigen::Vector3d& target :
       {Eigen::Vector3d(25.0, 5.0, 1.5), Eigen::Vector3d(-14.0, -30.0, 1.5), Eigen::Vector3d(12.0, 12.0, 1.5)}) {
    KinematicState goal = stateAt(target, Eigen::Vector3d(4.5, 1.0, 0.0));
    ASSERT_TRUE(clipGoalToWindow(grid, from, 1.2, goal)) << target.transpose();
    EXPECT_LT(offLine(goal.p_W_m, from, target), 1e-9) << "direction kept";
    EXPECT_LT((goal.p_W_m - from).norm(), (target - from).norm());
    // On the shrunk window's boundary: 1.2 m inside the nearest crossed face, inside the other.
    const double inset_m = std::min(10.0 - std::abs(goal.p_W_m.x()), 10.0 - std::abs(goal.p_W_m.y()));
    EXPECT_NEAR(inset_m, 1.2, 1e-9) << goal.p_W_m.transpose();
    EXPECT_DOUBLE_EQ(goal.p_W_m.z(), 1.5) << "the flight altitude is not a horizontal margin's business";
    EXPECT_EQ(goal.v_W_mps, Eigen::Vector3d(4.5, 1.0, 0.0)) << "velocity kept";
  }
}

TEST(ClipGoalToWindow, AClippedPointInAnObstacleStepsBackToTheFirstFreePointOnTheLine) {
  // A wall across x in [8, 9] (inflated by 0.25 m), where the line from the centre to (20, 0) leaves the
  // shrunk window at x = 8.8.
  const mapping::LocalGrid grid = makeBoxGrid(Eigen::Vector3d(20.0, 20.0, 5.0), Eigen::Vector3d(0.0, 0.0, 1.5),
                                              {{Eigen::Vector3d(8.0, -10.0, -1.0), Eigen::Vector3d(9.0, 10.0, 4.0)}});
  KinematicState goal = stateAt(Eigen::Vector3d(20.0, 0.0, 1.5));
  ASSERT_TRUE(clipGoalToWindow(grid, Eigen::Vector3d(0.0, 0.0, 1.5), 1.2, goal));
  EXPECT_FALSE(grid.isOccupied(goal.p_W_m));
  EXPECT_NEAR(goal.p_W_m.y(), 0.0, 1e-12);
  // The inflated wall begins at x = 7.8 (the cells whose centres lie within 0.25 m of the wall's cells' centres).
  EXPECT_LT(goal.p_W_m.x(), 7.8 + 1e-9);
  EXPECT_GT(goal.p_W_m.x(), 7.8 - 0.2) << "the first free point, a cell or so before the inflated wall";
}

TEST(ClipGoalToWindow, ADroneOutsideTheShrunkWindowClampsTheGoalPerAxisAndBadInputIsLeftAlone) {
  const mapping::LocalGrid grid = emptyWindow();
  KinematicState goal = stateAt(Eigen::Vector3d(30.0, -3.0, 1.5));
  ASSERT_TRUE(clipGoalToWindow(grid, Eigen::Vector3d(9.5, 0.0, 1.5), 1.2, goal));
  EXPECT_NEAR(goal.p_W_m.x(), 8.8, 1e-9);
  EXPECT_DOUBLE_EQ(goal.p_W_m.y(), -3.0);

  KinematicState nan_goal = stateAt(Eigen::Vector3d(std::nan(""), 0.0, 1.5));
  EXPECT_FALSE(clipGoalToWindow(grid, Eigen::Vector3d::Zero(), 1.2, nan_goal));
  KinematicState far_goal = stateAt(Eigen::Vector3d(30.0, 0.0, 1.5));
  const Eigen::Vector3d inf_from(std::numeric_limits<double>::infinity(), 0.0, 1.5);
  EXPECT_FALSE(clipGoalToWindow(grid, inf_from, 1.2, far_goal));
  EXPECT_DOUBLE_EQ(far_goal.p_W_m.x(), 30.0);
  // A margin wider than the window leaves its centre, not an empty box.
  KinematicState wide = stateAt(Eigen::Vector3d(30.0, 0.0, 1.5));
  ASSERT_TRUE(clipGoalToWindow(grid, Eigen::Vector3d(0.0, 0.0, 1.5), 50.0, wide));
  EXPECT_NEAR(wide.p_W_m.x(), 0.0, 1e-9);
}

KinodynamicSearch makeSearch() {
  return aerotrack::test::require(KinodynamicSearch::create(KinodynamicSearchParams{}), "KinodynamicSearch::create");
}

TEST(SearchGoal, AGoalBeyondTheWindowIsNeverReachedButItsClippedGoalIsInAFewExpansions) {
  const mapping::LocalGrid grid = emptyWindow();
  KinodynamicSearch search = makeSearch();
  const KinematicState start = stateAt(Eigen::Vector3d(0.0, 0.0, 1.5), Eigen::Vector3d(0.0, 3.0, 0.0));
  const KinematicState far_goal = stateAt(Eigen::Vector3d(0.0, 13.0, 1.5), Eigen::Vector3d(0.0, 3.0, 0.0));
  SearchPath path;
  EXPECT_EQ(search.search(grid, start, far_goal, 0.0, {}, path), SearchStatus::kPartial);
  EXPECT_EQ(path.expansions, search.params().max_expansions) << "the whole budget, every cycle";

  KinematicState goal = far_goal;
  ASSERT_TRUE(clipGoalToWindow(grid, start.p_W_m, 1.2, goal));
  ASSERT_EQ(search.search(grid, start, goal, 0.0, {}, path), SearchStatus::kReachedGoal);
  EXPECT_LT(path.expansions, 30);
  EXPECT_LT((path.stateAt(path.duration_s).p_W_m - goal.p_W_m).norm(), 1e-6);
}

TEST(SearchGoal, AGoalFasterThanThePerAxisLimitIsReachedAtTheLimitInItsDirection) {
  const mapping::LocalGrid grid = emptyWindow();
  KinodynamicSearch search = makeSearch();
  const double v_max = search.params().max_velocity_mps;
  const KinematicState start = stateAt(Eigen::Vector3d(0.0, -3.0, 1.5), Eigen::Vector3d(0.0, 2.5, 0.0));
  // A runner at 5 m/s, mostly along y: no path could end with that y velocity.
  const Eigen::Vector3d v_goal(1.0, 5.0, 0.0);
  const KinematicState goal = stateAt(Eigen::Vector3d(0.0, 4.0, 1.5), v_goal);
  SearchPath path;
  ASSERT_EQ(search.search(grid, start, goal, 0.0, {}, path), SearchStatus::kReachedGoal);
  EXPECT_LT(path.expansions, search.params().max_expansions);
  const KinematicState end = path.stateAt(path.duration_s);
  EXPECT_LT((end.p_W_m - goal.p_W_m).norm(), 1e-6);
  const Eigen::Vector3d expected = v_goal * (v_max / 5.0);
  EXPECT_LT((end.v_W_mps - expected).cwiseAbs().maxCoeff(), search.params().goal_velocity_tolerance_mps + 1e-9)
      << end.v_W_mps.transpose();
  for (double t = 0.0; t <= path.duration_s; t += 0.01)
    EXPECT_LE(path.stateAt(t).v_W_mps.cwiseAbs().maxCoeff(), v_max + 1e-6) << t;
}

}  // namespace
}  // namespace aerotrack::planning
