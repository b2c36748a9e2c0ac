// Keeping pace with a fast person (issue 21). When the goal's predicted person state x_tp is taken: at the
// prediction horizon when goal.max_lead_s is 0 (the paper's reading), else when the drone would get to the
// goal (the last complete path's duration, capped), and never beyond where the predicted path first enters
// an obstacle. The optimiser's time weight: scaled by the square of the person's speed above a walk.
#include <gtest/gtest.h>

#include "planner_test_util.hpp"
#include "search_test_util.hpp"
#include "tracking_planner_stages.hpp"

namespace aerotrack::planning {
namespace {

using test::defaultParams;
using test::makeBoxGrid;
using test::makePlanner;
using test::personAt;
using test::restAt;

TrackingPlannerParams leadParams(double predicted_weight) {
  TrackingPlannerParams params = defaultParams();
  params.goal.predicted_weight = predicted_weight;
  params.goal.max_lead_s = 3.0;
  return params;
}

// One plan() from odometry at p_WB_m moving at v_WB_mps, towards `person` in `grid`; its status.
PlanStatus planOnce(TrackingPlanner& planner, const mapping::LocalGrid& grid, const estimation::TargetEstimate& person,
                    const Eigen::Vector3d& p_WB_m, const Eigen::Vector3d& v_WB_mps = Eigen::Vector3d::Zero()) {
  hal::OdometrySample odometry;
  odometry.p_WB_m = p_WB_m;
  odometry.v_WB_mps = v_WB_mps;
  PlanInputs inputs;
  inputs.odometry = &odometry;
  inputs.target = &person;
  inputs.grid = &grid;
  PolynomialTrajectory out(24);
  return planner.plan(inputs, out).status;
}

// Open ground; with a wall across the person's way when asked.
mapping::LocalGrid leadWorld(bool wall) {
  std::vector<test::OccupiedBox> boxes = {{{-10, -10, -0.2}, {10, 10, 0.0}}};
  if (wall) boxes.push_back({{8.5, -3.0, 0.0}, {9.0, 3.0, 3.0}});
  return makeBoxGrid(Eigen::Vector3d(20, 20, 5), Eigen::Vector3d(3, 0, 1.5), boxes);
}

TEST(GoalLead, IsThePredictionHorizonWhenOffAndTheLastArrivalCappedWhenOn) {
  TrackingPlanner off = makePlanner();
  EXPECT_EQ(off.params().goal.max_lead_s, 0.0);
  EXPECT_EQ(TrackingPlannerStages(off).goalLeadS(), off.params().prediction.horizon_s);

  TrackingPlanner on = makePlanner(leadParams(1.0));
  TrackingPlannerStages stages(on);
  EXPECT_EQ(stages.goalLeadS(), 0.0);  // no path yet: the person's current state
  stages.setArrivalS(2.0);
  EXPECT_EQ(stages.goalLeadS(), 2.0);
  stages.setArrivalS(7.0);
  EXPECT_EQ(stages.goalLeadS(), 3.0);
}

TEST(GoalLead, ACompletePathToAPersonSetsTheLeadToItsDuration) {
  TrackingPlannerParams params = leadParams(1.0);
  params.search.max_expansions = 5000;
  params.search.max_nodes = 100000;
  TrackingPlanner planner = makePlanner(params);
  const mapping::LocalGrid grid = leadWorld(false);
  const estimation::TargetEstimate person = personAt(Eigen::Vector3d(7.0, 0.0, -0.3), 0);
  ASSERT_EQ(planOnce(planner, grid, person, Eigen::Vector3d(0, 0, 1.5)), PlanStatus::kPlanned);
  ASSERT_EQ(planner.searchPath().status, SearchStatus::kReachedGoal);
  EXPECT_GT(planner.searchPath().duration_s, 0.5);  // 4.5 m from rest
  EXPECT_DOUBLE_EQ(TrackingPlannerStages(planner).goalLeadS(), std::min(planner.searchPath().duration_s, 3.0));
}

TEST(GoalLead, TheGoalIsWhereThePersonWillBeWhenTheDroneGetsThere) {
  const estimation::TargetEstimate person =
      personAt(Eigen::Vector3d(7.0, 0.0, -0.3), 0, Eigen::Vector3d(2.0, 0.0, 0.0));
  const mapping::LocalGrid grid = leadWorld(false);
  const StatePva start = restAt(Eigen::Vector3d(0, 0, 1.5));
  for (const double w : {1.0, 0.5}) {
    TrackingPlanner planner = makePlanner(leadParams(w));
    TrackingPlannerStages stages(planner);
    stages.setArrivalS(1.0);
    const KinematicState goal = stages.selectGoal(grid, TrackingPlannerStages::liveMotion(planner, person), start, 0);
    // x_tp: 2 m further on after the 1 s lead; x_g: the mix with the current 7 m, held 2.5 m behind.
    EXPECT_NEAR(goal.p_W_m.x(), 7.0 + w * 2.0 - 2.5, 1e-9) << w;
    EXPECT_NEAR(goal.p_W_m.y(), 0.0, 1e-9);
    EXPECT_NEAR(goal.v_W_mps.x(), 2.0, 1e-9);  // constant velocity: the same now and then
  }
}

TEST(GoalLead, ThePredictedPathStopsWhereItFirstEntersAnObstacle) {
  const estimation::TargetEstimate person =
      personAt(Eigen::Vector3d(7.0, 0.0, -0.3), 0, Eigen::Vector3d(2.0, 0.0, 0.0));
  const StatePva start = restAt(Eigen::Vector3d(0, 0, 1.5));
  TrackingPlanner planner = makePlanner(leadParams(1.0));
  TrackingPlannerStages stages(planner);
  stages.setArrivalS(1.0);  // unchecked, x_tp would be at x = 9: inside the wall (8.5-9.0)
  const mapping::LocalGrid walled = leadWorld(true);
  const KinematicState goal = stages.selectGoal(walled, TrackingPlannerStages::liveMotion(planner, person), start, 0);
  // The last sample (every 1/30 s, 6.7 cm) before the wall's inflated face at 8.25 m (+- a 0.1 m cell).
  const double x_tp = goal.p_W_m.x() + planner.params().goal.tracking_distance_m;
  EXPECT_LT(x_tp, 8.35);
  EXPECT_GT(x_tp, 8.0);
  EXPECT_FALSE(walled.isOccupied(Eigen::Vector3d(x_tp, 0.0, planner.params().person_sight_height_m)));
}

TEST(GoalLead, APersonBeyondTheGridsWindowIsSearchedForAtItsEdgeAndKeepsTheLastLead) {
  // The drone 14 m behind a runner (the window reaches 10 m from its centre): the goal (11.5 m on) lies
  // beyond it. The search goes to the window's edge, in a few expansions, not the whole budget.
  TrackingPlanner planner = makePlanner(leadParams(1.0));
  TrackingPlannerStages stages(planner);
  stages.setArrivalS(1.2);
  const mapping::LocalGrid grid = makeBoxGrid(Eigen::Vector3d(20, 20, 5), Eigen::Vector3d(0, 0, 1.5), {});
  const estimation::TargetEstimate person =
      personAt(Eigen::Vector3d(14.0, 0.0, -0.3), 0, Eigen::Vector3d(4.0, 0.0, 0.0));
  const TrackingPlannerStages::PersonMotion motion = TrackingPlannerStages::liveMotion(planner, person);
  StatePva start = restAt(Eigen::Vector3d(0, 0, 1.5));
  start(0, 1) = 3.0;
  const KinematicState goal = stages.selectGoal(grid, motion, start, 0);
  ASSERT_FALSE(grid.inWindow(goal.p_W_m));
  ASSERT_EQ(stages.searchTrackingPath(grid, start, 0, goal, motion), SearchStatus::kReachedGoal);
  const SearchPath& path = planner.searchPath();
  EXPECT_LT(path.expansions, 30);
  const Eigen::Vector3d end = path.stateAt(path.duration_s).p_W_m;
  const double margin_m = planner.params().search.primitive_duration_s * planner.params().search.max_velocity_mps;
  const double tolerance_m = planner.params().search.goal_tolerance_m;
  EXPECT_NEAR(end.x(), grid.windowMaxM().x() - margin_m, tolerance_m);
  EXPECT_NEAR(end.y(), 0.0, tolerance_m);
  // A path to the window's edge is not the drone's arrival at the person: the lead stays.
  ASSERT_EQ(planOnce(planner, grid, person, Eigen::Vector3d(0, 0, 1.5), Eigen::Vector3d(3.0, 0, 0)),
            PlanStatus::kPlanned);
  EXPECT_EQ(planner.searchPath().status, SearchStatus::kReachedGoal);
  EXPECT_DOUBLE_EQ(stages.goalLeadS(), 1.2);
}

TEST(CameraView, TheOptimiserIsGivenTheLivePersonsTorsoAlongTheirPredictionAndNoOneElse) {
  TrackingPlanner planner = makePlanner(leadParams(1.0));
  TrackingPlannerStages stages(planner);
  const estimation::TargetEstimate person =
      personAt(Eigen::Vector3d(7.0, 0.0, -0.3), 0, Eigen::Vector3d(2.0, 0.0, 0.0));
  const TrackingPlannerStages::PersonMotion motion = TrackingPlannerStages::liveMotion(planner, person);
  stages.samplePersonTorso(motion, rt::secondsToNs(0.5));
  const std::vector<Eigen::Vector3d>& torso = stages.personTorso();
  ASSERT_GE(torso.size(), 21U);  // at least a second, every 50 ms
  for (std::size_t k = 0; k < torso.size(); ++k) {
    const double t_s = 0.5 + 0.05 * static_cast<double>(k);  // from the hand-over, at constant velocity
    EXPECT_NEAR(torso[k].x(), 7.0 + 2.0 * t_s, 1e-9) << k;
    EXPECT_NEAR(torso[k].z(), planner.params().person_sight_height_m, 1e-12);
  }
  TrackingPlannerStages::PersonMotion look = motion;
  look.live = false;  // a relocation's viewpoint, not a person
  stages.samplePersonTorso(look, 0);
  EXPECT_TRUE(stages.personTorso().empty());
}

TEST(TimeWeight, ScalesWithTheSquareOfThePersonsSpeedAboveAWalkUpToItsCap) {
  TrackingPlannerParams params = defaultParams();
  params.time_weight_reference_speed_mps = 1.5;
  params.max_time_weight_scale = 10.0;
  const TrackingPlanner planner = makePlanner(params);
  EXPECT_EQ(planner.timeWeightScale(0.0), 1.0);
  EXPECT_EQ(planner.timeWeightScale(1.5), 1.0);
  EXPECT_NEAR(planner.timeWeightScale(3.0), 4.0, 1e-12);
  EXPECT_NEAR(planner.timeWeightScale(4.0), 16.0 / 2.25, 1e-12);
  EXPECT_EQ(planner.timeWeightScale(6.0), 10.0);  // 16 x, capped

  params.max_time_weight_scale = 1.0;  // off
  EXPECT_EQ(makePlanner(params).timeWeightScale(6.0), 1.0);
  params.max_time_weight_scale = 0.5;
  EXPECT_FALSE(TrackingPlanner::create(params).has_value());
  params.max_time_weight_scale = 10.0;
  params.time_weight_reference_speed_mps = 0.0;
  EXPECT_FALSE(TrackingPlanner::create(params).has_value());
}

TEST(TimeWeight, GivenAReferenceSpeedChangeThenTheLargerOfTheTwoScalesHolds) {
  TrackingPlannerParams params = defaultParams();
  params.time_weight_reference_speed_mps = 1.5;
  params.max_time_weight_scale = 10.0;
  EXPECT_EQ(makePlanner(params).timeWeightScale(0.5, 2.0), 1.0) << "off by default: the change is ignored";

  params.time_weight_reference_speed_change_mps = 0.5;
  const TrackingPlanner planner = makePlanner(params);
  EXPECT_EQ(planner.timeWeightScale(0.0, 0.3), 1.0) << "a walker's noise keeps the walker's rho_t";
  EXPECT_NEAR(planner.timeWeightScale(0.5, 1.0), 4.0, 1e-12) << "a runner setting off: the change rules";
  EXPECT_NEAR(planner.timeWeightScale(3.0, 0.5), 4.0, 1e-12) << "a steady runner: the speed rules";
  EXPECT_EQ(planner.timeWeightScale(0.0, 3.0), 10.0);  // 36 x, capped

  params.time_weight_reference_speed_change_mps = -0.1;
  EXPECT_FALSE(TrackingPlanner::create(params).has_value());
}

}  // namespace
}  // namespace aerotrack::planning
