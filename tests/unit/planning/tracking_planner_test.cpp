// The replanning cycle (TrackingPlanner) and its task (PlanningTask): the start state is the current
// trajectory's state at the hand-over time; a plan around a wall is clear in the grid, within the limits
// and starts exactly at the start state; a failed cycle publishes nothing and the old trajectory goes on;
// a failed cycle whose old trajectory is blocked publishes a stop (also when the drone is already inside
// the margin of a surface seen late, and the trajectory stays in it); on the ground it takes off first.
#include "aerotrack/planning/tracking_planner.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "../malloc_counter.hpp"
#include "aerotrack/planning/planning_task.hpp"
#include "aerotrack/rt/clock.hpp"
#include "aerotrack/trajectory_server/trajectory_server.hpp"
#include "planner_test_util.hpp"
#include "search_test_util.hpp"
#include "tracking_planner_stages.hpp"

namespace aerotrack::planning {

namespace {

using test::defaultParams;
using test::makeBoxGrid;
using test::makePlanner;
using test::OccupiedBox;
using test::personAt;
using test::restAt;

hal::OdometrySample odometryAt(const Eigen::Vector3d& p, rt::TimeNs stamp_ns = 0) {
  hal::OdometrySample o;
  o.stamp_ns = stamp_ns;
  o.p_WB_m = p;
  return o;
}

// A two-piece spline through (0,0,1.5) -> (2,1,1.5) -> (4,0,1.5), moving at the start.
std::shared_ptr<PolynomialTrajectory> curvedTrajectory() {
  MinJerkSpline spline;
  StatePva start = StatePva::Zero();
  StatePva end = StatePva::Zero();
  start.col(0) = Eigen::Vector3d(0, 0, 1.5);
  start.col(1) = Eigen::Vector3d(1, 0, 0);
  end.col(0) = Eigen::Vector3d(4, 0, 1.5);
  spline.reset(start, end, 2);
  Eigen::Matrix3Xd q(3, 1);
  q.col(0) = Eigen::Vector3d(2, 1, 1.5);
  Eigen::VectorXd t(2);
  t << 1.5, 1.5;
  EXPECT_TRUE(spline.generate(q, t));
  auto traj = std::make_shared<PolynomialTrajectory>();
  traj->assign(spline);
  return traj;
}

TEST(TrackingPlanner, StartStateIsTheCurrentTrajectoryAtTheHandOver) {
  const TrackingPlanner planner = makePlanner();
  const auto traj = curvedTrajectory();
  const trajectory_server::TimedTrajectory current{traj, rt::secondsToNs(10.0)};
  const rt::TimeNs now_ns = rt::secondsToNs(11.0);
  const rt::TimeNs start_ns = now_ns + rt::secondsToNs(0.05);
  // The drone is where the trajectory wants it (within the reset distance).
  const hal::OdometrySample odometry = odometryAt(traj->sample(1.0).p_W_m + Eigen::Vector3d(0.1, 0, 0));
  PlanInputs inputs;
  inputs.now_ns = now_ns;
  inputs.odometry = &odometry;
  inputs.current = &current;
  const StatePva s = planner.startState(inputs, start_ns);
  const trajectory_server::TrajectorySample expected = traj->sample(1.05);
  EXPECT_LT((s.col(0) - expected.p_W_m).norm(), 1e-12);
  EXPECT_LT((s.col(1) - expected.v_W_mps).norm(), 1e-12);
  EXPECT_LT((s.col(2) - expected.a_W_mps2).norm(), 1e-12);

  // Strayed: odometry, at rest in acceleration.
  const hal::OdometrySample far = odometryAt(traj->sample(1.0).p_W_m + Eigen::Vector3d(0, 2.0, 0));
  inputs.odometry = &far;
  const StatePva s_far = planner.startState(inputs, start_ns);
  EXPECT_LT((s_far.col(0) - far.p_WB_m).norm(), 1e-12);
  EXPECT_EQ(s_far.col(2).norm(), 0.0);

  // After the current trajectory's end: its end, at rest (what the server holds).
  const hal::OdometrySample at_end = odometryAt(traj->sample(3.0).p_W_m);
  inputs.odometry = &at_end;
  inputs.now_ns = rt::secondsToNs(20.0);
  const StatePva s_end = planner.startState(inputs, inputs.now_ns + rt::secondsToNs(0.05));
  EXPECT_LT((s_end.col(0) - traj->sample(3.0).p_W_m).norm(), 1e-12);
  EXPECT_EQ(s_end.col(1).norm(), 0.0);
}

struct WallWorld {
  mapping::LocalGrid grid = makeBoxGrid(Eigen::Vector3d(20, 20, 5), Eigen::Vector3d(3, 0, 1.5),
                                        {{{2.5, -0.8, 0.0}, {3.0, 0.8, 3.0}},  // wall across the way
                                         {{-10, -10, -0.2}, {10, 10, 0.0}}});  // ground
};

TEST(TrackingPlanner, PlansAroundAWallWithinLimitsFromTheStartState) {
  TrackingPlannerParams params = defaultParams();
  params.search.max_expansions = 5000;  // room to find the way round, not a partial path
  params.search.max_nodes = 100000;
  TrackingPlanner planner = makePlanner(params);
  const WallWorld world;
  const hal::OdometrySample odometry = odometryAt(Eigen::Vector3d(0, 0, 1.5));
  PolynomialTrajectory out(24);
  PlanReport report;
  // Feed a standing person behind the wall for a while (the predictor needs min_samples estimates).
  for (int k = 0; k <= 10; ++k) {
    const rt::TimeNs now_ns = rt::secondsToNs(0.05 * k);
    planner.observeTarget(personAt(Eigen::Vector3d(7.0, 0.0, 1.0), now_ns));
    const estimation::TargetEstimate target = personAt(Eigen::Vector3d(7.0, 0.0, 1.0), now_ns);
    PlanInputs inputs;
    inputs.now_ns = now_ns;
    inputs.odometry = &odometry;
    inputs.target = &target;
    inputs.grid = &world.grid;
    report = planner.plan(inputs, out);
  }
  ASSERT_EQ(report.status, PlanStatus::kPlanned) << toString(report.status);
  EXPECT_EQ(report.search_status, SearchStatus::kReachedGoal)
      << toString(report.search_status) << " after " << report.search_expansions << " expansions";
  EXPECT_TRUE(report.predicted);
  EXPECT_GE(report.corridor_boxes, 2);
  // Starts exactly at the start state (no current trajectory: the odometry, at rest).
  EXPECT_LT((out.sample(0.0).p_W_m - odometry.p_WB_m).norm(), 1e-9);
  EXPECT_LT(out.sample(0.0).v_W_mps.norm(), 1e-9);
  // Dense check: clear of the inflated grid, within the check's limits, and past the wall at the end.
  for (double t = 0.0; t <= out.durationS(); t += 0.005) {
    const trajectory_server::TrajectorySample s = out.sample(t);
    EXPECT_FALSE(world.grid.isOccupied(s.p_W_m)) << "t=" << t;
    EXPECT_LE(s.v_W_mps.norm(), 3.0 * 1.05) << "t=" << t;
    EXPECT_LE(s.a_W_mps2.norm(), 4.0 * 1.05) << "t=" << t;
  }
  EXPECT_GT(out.sample(out.durationS()).p_W_m.x(), 3.0);
}

TEST(TrackingPlanner, RefusesATrajectoryThatComesTooCloseToThePerson) {
  const WallWorld world;
  const hal::OdometrySample odometry = odometryAt(Eigen::Vector3d(0, -3, 1.5));
  const estimation::TargetEstimate target = personAt(Eigen::Vector3d(6.0, -3.0, 1.0), 0);
  PlanInputs inputs;
  inputs.odometry = &odometry;
  inputs.target = &target;
  inputs.grid = &world.grid;
  PolynomialTrajectory out;
  {  // the goal is held 2.5 m away: fine with the default 1 m
    TrackingPlanner planner = makePlanner();
    EXPECT_EQ(planner.plan(inputs, out).status, PlanStatus::kPlanned);
  }
  TrackingPlannerParams params = defaultParams();
  params.min_person_distance_m = 4.0;  // closer than the tracking distance: every approach is refused
  TrackingPlanner planner = makePlanner(params);
  const PlanReport report = planner.plan(inputs, out);
  EXPECT_EQ(report.status, PlanStatus::kCheckFailed);
  EXPECT_EQ(report.check, CheckVerdict::kTooCloseToPerson);
}

TEST(TrackingPlanner, SeesThePersonAtTorsoHeightNotAtTheEstimatesGroundPlaneZ) {
  // The localization regression's z is a ground-plane constant below the ground (config: about -0.3 m
  // in W). Lines of sight to that point cross the mapped ground next to the person, so before the sight
  // height every search node was "occluded" and the occlusion term did nothing.
  TrackingPlannerParams params = defaultParams();
  params.search.max_expansions = 5000;
  params.search.max_nodes = 100000;
  TrackingPlanner planner = makePlanner(params);
  const mapping::LocalGrid open_ground =
      makeBoxGrid(Eigen::Vector3d(20, 20, 5), Eigen::Vector3d(3, 0, 1.5), {{{-10, -10, -0.2}, {10, 10, 0.0}}});
  const hal::OdometrySample odometry = odometryAt(Eigen::Vector3d(0, 0, 1.5));
  PolynomialTrajectory out(24);
  PlanReport report;
  for (int k = 0; k <= 6; ++k) {
    const estimation::TargetEstimate person = personAt(Eigen::Vector3d(6.0, 0.0, -0.3), rt::secondsToNs(0.05 * k));
    PlanInputs in;
    in.now_ns = rt::secondsToNs(0.05 * k);
    in.odometry = &odometry;
    in.target = &person;
    in.grid = &open_ground;
    report = planner.plan(in, out);
  }
  ASSERT_EQ(report.status, PlanStatus::kPlanned);
  ASSERT_GT(planner.searchPath().expansions, 0);
  EXPECT_EQ(planner.searchPath().occluded_nodes, 0);  // nothing hides the person in the open
}

TEST(TrackingPlanner, OnTheGroundItTakesOffFirst) {
  TrackingPlanner planner = makePlanner();
  const WallWorld world;
  const hal::OdometrySample odometry = odometryAt(Eigen::Vector3d(0, 0, 0.05));
  const estimation::TargetEstimate target = personAt(Eigen::Vector3d(7.0, 0.0, 1.0), 0);
  PlanInputs inputs;
  inputs.odometry = &odometry;
  inputs.target = &target;
  inputs.grid = &world.grid;
  PolynomialTrajectory out;
  const PlanReport report = planner.plan(inputs, out);
  ASSERT_EQ(report.status, PlanStatus::kTakeOff);
  const trajectory_server::TrajectorySample end = out.sample(out.durationS());
  EXPECT_NEAR(end.p_W_m.z(), planner.params().flight_altitude_m, 1e-9);
  EXPECT_NEAR(end.p_W_m.x(), 0.0, 1e-9);
  EXPECT_LT(end.v_W_mps.norm(), 1e-9);
}

// The stages of plan(), each on a crafted input.

TEST(TrackingPlannerStages, PredictionIsNothingWithoutALiveEstimateOrAPathToRelocateAlong) {
  TrackingPlanner planner = makePlanner();
  TrackingPlannerStages stages(planner);
  PlanInputs inputs;
  EXPECT_FALSE(stages.predictPerson(inputs).has_value());  // no estimate
  estimation::TargetEstimate lost = personAt(Eigen::Vector3d(7, 0, 1), 0);
  lost.lost = true;
  inputs.target = &lost;
  EXPECT_FALSE(stages.predictPerson(inputs).has_value());
  inputs.relocate = true;  // relocation without any prediction yet: nothing to fly along either
  EXPECT_FALSE(stages.predictPerson(inputs).has_value());
}

TEST(TrackingPlannerStages, PredictionIsConstantVelocityUntilThePredictorHasEnoughEstimates) {
  TrackingPlanner planner = makePlanner();
  TrackingPlannerStages stages(planner);
  const estimation::TargetEstimate walking = personAt(Eigen::Vector3d(7, 1, -0.3), 0, Eigen::Vector3d(1, 0.5, 0));
  planner.observeTarget(walking);
  PlanInputs inputs;
  inputs.target = &walking;
  const auto person = stages.predictPerson(inputs);
  ASSERT_TRUE(person.has_value());
  EXPECT_TRUE(person->live);
  EXPECT_EQ(person->prediction, nullptr);
  const double sight_m = planner.params().person_sight_height_m;
  EXPECT_EQ(person->positionAt(rt::secondsToNs(0.5)), Eigen::Vector3d(7.5, 1.25, sight_m));
  // Extrapolated at most the prediction horizon ahead.
  const double horizon_s = planner.params().prediction.horizon_s;
  EXPECT_LT((person->positionAt(rt::secondsToNs(horizon_s + 5.0)) -
             Eigen::Vector3d(7 + horizon_s, 1 + 0.5 * horizon_s, sight_m))
                .norm(),
            1e-12);
  EXPECT_EQ(person->velocityAt(rt::secondsToNs(3.0)), walking.v_WT_mps);
}

TEST(TrackingPlannerStages, PredictionIsTheBezierFitOnceWarmAndItIsFlownAlongWhenRelocating) {
  TrackingPlanner planner = makePlanner();
  TrackingPlannerStages stages(planner);
  PlanInputs inputs;
  std::optional<TrackingPlannerStages::PersonMotion> person;
  estimation::TargetEstimate walking;
  for (int k = 0; k <= 20; ++k) {  // walking along +x at 1 m/s
    const rt::TimeNs t_ns = rt::secondsToNs(0.05 * k);
    walking = personAt(Eigen::Vector3d(0.05 * k, 0, 1), t_ns, Eigen::Vector3d(1, 0, 0));
    planner.observeTarget(walking);
    inputs.now_ns = t_ns;
    inputs.target = &walking;
    person = stages.predictPerson(inputs);
  }
  ASSERT_TRUE(person.has_value());
  ASSERT_NE(person->prediction, nullptr);
  EXPECT_TRUE(person->live);
  const Eigen::Vector3d ahead = person->positionAt(inputs.now_ns + rt::secondsToNs(0.5));
  EXPECT_NEAR(ahead.x(), 1.5, 0.1);
  EXPECT_NEAR(ahead.y(), 0.0, 0.05);
  EXPECT_EQ(ahead.z(), planner.params().person_sight_height_m);
  const Eigen::Vector3d predicted_far = person->positionAt(inputs.now_ns + rt::secondsToNs(1.0));

  // Lost: with relocation the last prediction is flown along (not live), without it there is nothing.
  estimation::TargetEstimate lost = walking;
  lost.lost = true;
  planner.observeTarget(lost);
  inputs.target = &lost;
  inputs.now_ns += rt::secondsToNs(0.2);
  inputs.relocate = true;
  const auto relocating = stages.predictPerson(inputs);
  ASSERT_TRUE(relocating.has_value());
  EXPECT_FALSE(relocating->live);
  ASSERT_NE(relocating->prediction, nullptr);
  EXPECT_EQ(relocating->positionAt(inputs.now_ns + rt::secondsToNs(0.8)), predicted_far);
  inputs.relocate = false;
  EXPECT_FALSE(stages.predictPerson(inputs).has_value());
}

// A standing person at (7, 0) behind a pillar that hides them from the plain goal (4.5, 0).
struct PillarWorld {
  mapping::LocalGrid grid = makeBoxGrid(Eigen::Vector3d(20, 20, 5), Eigen::Vector3d(3, 0, 1.5),
                                        {{{5.6, -0.4, 0.0}, {6.0, 0.4, 3.0}},  // the pillar
                                         {{-10, -10, -0.2}, {10, 10, 0.0}}});  // ground
  estimation::TargetEstimate person = personAt(Eigen::Vector3d(7.0, 0.0, -0.3), 0);
  TrackingPlannerStages::PersonMotion motion(const TrackingPlanner& planner) const {
    return TrackingPlannerStages::liveMotion(planner, person);
  }
};

TEST(TrackingPlannerStages, GoalIsAtTheTrackingDistanceAndInSightOnlyInTheProposedMode) {
  TrackingPlanner planner = makePlanner();
  TrackingPlannerStages stages(planner);
  const PillarWorld world;
  const auto person = world.motion(planner);
  const StatePva start = restAt(Eigen::Vector3d(0, 0, 1.2));
  const double distance_m = planner.params().goal.tracking_distance_m;
  const Eigen::Vector3d p_person(7.0, 0.0, planner.params().person_sight_height_m);

  const KinematicState visible = stages.selectGoal(world.grid, person, start, 0);
  EXPECT_EQ(visible.p_W_m.z(), planner.params().flight_altitude_m);  // not the drone's 1.2 m
  EXPECT_NEAR((visible.p_W_m - p_person).head<2>().norm(), distance_m, 1e-9);
  EXPECT_GT(std::abs(visible.p_W_m.y()), 0.5);  // moved round the person, out of the pillar's shadow
  EXPECT_TRUE(world.grid.lineOfSight(visible.p_W_m, p_person));

  planner.setOcclusionAware(false);  // the baseline: the plain goal, hidden or not
  const KinematicState plain = stages.selectGoal(world.grid, person, start, 0);
  EXPECT_LT((plain.p_W_m - Eigen::Vector3d(7.0 - distance_m, 0.0, planner.params().flight_altitude_m)).norm(), 1e-9);
  EXPECT_FALSE(world.grid.lineOfSight(plain.p_W_m, p_person));
}

TEST(TrackingPlannerStages, SearchCorridorAndOptimisationGoRoundAWallFromTheStartToTheGoal) {
  TrackingPlannerParams params = defaultParams();
  params.search.max_expansions = 5000;
  params.search.max_nodes = 100000;
  TrackingPlanner planner = makePlanner(params);
  TrackingPlannerStages stages(planner);
  const WallWorld world;
  const estimation::TargetEstimate person = personAt(Eigen::Vector3d(7.0, 0.0, 1.0), 0);
  TrackingPlannerStages::PersonMotion motion;
  motion.estimate = &person;
  motion.live = true;
  motion.sight_height_m = params.person_sight_height_m;
  const StatePva start = restAt(Eigen::Vector3d(0, 0, 1.5));
  KinematicState goal;
  goal.p_W_m = Eigen::Vector3d(4.5, 0, 1.5);

  // Search: reaches the goal behind the wall.
  ASSERT_EQ(stages.searchTrackingPath(world.grid, start, 0, goal, motion), SearchStatus::kReachedGoal);
  const SearchPath& path = planner.searchPath();
  EXPECT_EQ(path.status, SearchStatus::kReachedGoal);
  EXPECT_EQ(path.stateAt(0.0).p_W_m, start.col(0));
  EXPECT_LT((path.stateAt(path.duration_s).p_W_m - goal.p_W_m).norm(), 0.3);

  // Corridor: a polyline from exactly the start to the path's end, inside the boxes.
  ASSERT_TRUE(stages.buildCorridor(world.grid, start));
  const std::vector<Eigen::Vector3d>& polyline = planner.polyline();
  EXPECT_EQ(polyline.front(), start.col(0));
  EXPECT_EQ(polyline.back(), path.stateAt(path.duration_s).p_W_m);
  EXPECT_GE(polyline.size(), static_cast<std::size_t>(path.duration_s / params.path_sample_step_s));
  const Corridor& corridor = planner.corridor();
  EXPECT_GE(corridor.boxes.size(), 2U);  // one box cannot see round the wall
  for (const Eigen::Vector3d& p : polyline) {
    bool inside = false;
    for (const CorridorBox& box : corridor.boxes) inside = inside || box.contains(p, -1e-9);
    EXPECT_TRUE(inside) << p.transpose();
  }

  // Optimisation: starts exactly at the start state, ends at rest past the wall, clear of the grid.
  PolynomialTrajectory out(24);
  const auto optimized = stages.optimizeTrajectory(world.grid, start, out);
  ASSERT_TRUE(optimized.has_value()) << optimized.error().message;
  EXPECT_LT((out.sample(0.0).p_W_m - start.col(0)).norm(), 1e-9);
  EXPECT_LT(out.sample(0.0).v_W_mps.norm(), 1e-9);
  const trajectory_server::TrajectorySample end = out.sample(out.durationS());
  EXPECT_LT(end.v_W_mps.norm(), 1e-3);
  EXPECT_GT(end.p_W_m.x(), 3.0);
  for (double t = 0.0; t <= out.durationS(); t += 0.01) EXPECT_FALSE(world.grid.isOccupied(out.sample(t).p_W_m));
}

TEST(TrackingPlannerStages, SearchFromInsideTheWallIsBlocked) {
  TrackingPlanner planner = makePlanner();
  TrackingPlannerStages stages(planner);
  const WallWorld world;
  const estimation::TargetEstimate person = personAt(Eigen::Vector3d(7.0, 0.0, 1.0), 0);
  TrackingPlannerStages::PersonMotion motion;
  motion.estimate = &person;
  motion.live = true;
  KinematicState goal;
  goal.p_W_m = Eigen::Vector3d(4.5, 0, 1.5);
  EXPECT_EQ(stages.searchTrackingPath(world.grid, restAt(Eigen::Vector3d(2.75, 0, 1.5)), 0, goal, motion),
            SearchStatus::kStartBlocked);
}

TEST(TrackingPlannerStages, FinalCheckRefusesTheWallAndThePersonAndPassesAClearPass) {
  TrackingPlanner planner = makePlanner();
  TrackingPlannerStages stages(planner);
  const WallWorld world;
  const estimation::TargetEstimate person = personAt(Eigen::Vector3d(7.0, 0.0, 1.0), 0);
  TrackingPlannerStages::PersonMotion motion;
  motion.estimate = &person;
  motion.live = true;
  motion.sight_height_m = planner.params().person_sight_height_m;
  auto check = [&](const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
    PolynomialTrajectory move;
    planner.makeMoveTrajectory(restAt(from), to, move);
    return stages.checkPlannedTrajectory(move, world.grid, motion, 0);
  };
  // Beside the person, 3 m off their side: clear.
  EXPECT_EQ(check({4, -3, 1.5}, {9, -3, 1.5}).verdict, CheckVerdict::kOk);
  // Up to the wall (x = 2.5, inflated) and through it (within the check's 3 s horizon).
  EXPECT_EQ(check({0, 0, 1.5}, {1.8, 0, 1.5}).verdict, CheckVerdict::kOk);
  EXPECT_EQ(check({1, 0, 1.5}, {4, 0, 1.5}).verdict, CheckVerdict::kGridBlocked);
  // Past the person 0.5 m away (they stand at x = 7): too close, from when it comes within 1 m.
  const CheckResult close = check({5.5, 0.5, 1.5}, {8.5, 0.5, 1.5});
  EXPECT_EQ(close.verdict, CheckVerdict::kTooCloseToPerson);
  EXPECT_GT(close.t_s, 0.5);
  EXPECT_LT(close.t_s, 2.0);  // the move passes x = 7 at 2 s
  // A start already closer than the limit may stay as close, not come closer.
  EXPECT_EQ(check({7, 0.5, 1.5}, {7, 0.6, 1.5}).verdict, CheckVerdict::kOk);
}

// DESIGN.md rule 4: once warm, a cycle allocates nothing of its own. The one exception is inside LBFGS++
// 0.1: its history update, add_correction(x - xp, g - gp), binds two vector expressions to
// Ref<const VectorXd> and so makes two temporaries per L-BFGS iteration (none on the last, which returns
// first). The test pins the count to exactly that, so any other allocation fails it. (FCL is not run
// here: no octree.)
TEST(TrackingPlanner, WarmCycleAllocatesOnlyLbfgsTemporaries) {
  if (!aerotrack::test::kMallocCounted) GTEST_SKIP() << "malloc belongs to the sanitizer";
  TrackingPlanner planner = makePlanner();
  const WallWorld world;
  const hal::OdometrySample odometry = odometryAt(Eigen::Vector3d(0, 0, 1.5));
  PolynomialTrajectory out(24);
  auto cycle = [&](int k) {
    const rt::TimeNs now_ns = rt::secondsToNs(0.05 * k);
    const estimation::TargetEstimate target = personAt(Eigen::Vector3d(7.0, 0.0, 1.0), now_ns);
    planner.observeTarget(target);
    PlanInputs inputs;
    inputs.now_ns = now_ns;
    inputs.odometry = &odometry;
    inputs.target = &target;
    inputs.grid = &world.grid;
    return planner.plan(inputs, out);
  };
  for (int k = 0; k < 10; ++k) (void)cycle(k);  // warm: predictor full, piece count settled
  int planned = 0;
  long lbfgs_updates = 0;
  long mallocs = 0;
  {
    const aerotrack::test::MallocCount count;
    for (int k = 10; k < 20; ++k) {
      const PlanReport report = cycle(k);
      planned += report.status == PlanStatus::kPlanned ? 1 : 0;
      if (report.optimizer_status != OptimizerStatus::kLineSearch) lbfgs_updates += report.optimizer_iterations - 1;
    }
    mallocs = count.count();
  }
  EXPECT_EQ(planned, 10);
  EXPECT_EQ(mallocs, 2 * lbfgs_updates);
}

// The task, on its channels.
struct TaskRig : test::TaskChannels {
  std::unique_ptr<PlanningTask> task;

  explicit TaskRig(const TrackingPlannerParams& params = defaultParams(),
                   const rt::LatestSlot<supervisor::SupervisorState>* modes = nullptr) {
    task = std::make_unique<PlanningTask>(makePlanner(params), channels(modes), clock);
  }
  void step(double t_s) { task->step(rt::secondsToNs(t_s)); }

  /// One cycle at t = 0 from (0, 0, 1.5) towards a person standing behind WallWorld's wall: what it
  /// published (empty if it did not plan).
  trajectory_server::TimedTrajectory planOnceAroundTheWall() {
    const WallWorld world;
    grid.write(std::make_shared<const mapping::LocalGrid>(world.grid));
    odometry.write(odometryAt(Eigen::Vector3d(0, 0, 1.5)));
    target.write(personAt(Eigen::Vector3d(7.0, 0.0, 1.0), 0));
    step(0.0);
    return task->count(PlanStatus::kPlanned) == 1U ? task->lastPublished() : trajectory_server::TimedTrajectory{};
  }
  /// A cycle at t_s with the drone at p and the person lost (the cycle fails).
  void loseThePersonAt(double t_s, const Eigen::Vector3d& p) {
    odometry.write(odometryAt(p, rt::secondsToNs(t_s)));
    estimation::TargetEstimate lost = personAt(Eigen::Vector3d(7.0, 0.0, 1.0), rt::secondsToNs(t_s));
    lost.lost = true;
    target.write(lost);
    step(t_s);
  }
};

TEST(PlanningTask, FailedCycleKeepsTheOldTrajectory) {
  TaskRig rig;
  const WallWorld world;
  rig.grid.write(std::make_shared<const mapping::LocalGrid>(world.grid));
  rig.odometry.write(odometryAt(Eigen::Vector3d(0, 0, 1.5)));
  for (int k = 0; k <= 6; ++k) {
    rig.target.write(personAt(Eigen::Vector3d(7.0, 0.0, 1.0), rt::secondsToNs(0.05 * k)));
    rig.step(0.05 * k);
  }
  ASSERT_GE(rig.task->count(PlanStatus::kPlanned), 1U);
  const std::uint64_t version = rig.trajectories.version();
  const trajectory_server::TimedTrajectory before = rig.task->lastPublished();
  ASSERT_TRUE(before.trajectory);

  // The person is lost: nothing new is published, the old trajectory stands.
  estimation::TargetEstimate lost = personAt(Eigen::Vector3d(7.0, 0.0, 1.0), rt::secondsToNs(0.35));
  lost.lost = true;
  rig.target.write(lost);
  rig.step(0.35);
  EXPECT_EQ(rig.task->count(PlanStatus::kNoTarget), 1U);
  EXPECT_EQ(rig.trajectories.version(), version);
  EXPECT_EQ(rig.task->lastPublished().trajectory, before.trajectory);
}

TEST(PlanningTask, EnteringDegradedBrakesOnceAndThenEveryCyclePlansAgain) {
  // Issue 21: degraded (failed plans in a row, the person seen) is a hover that keeps planning.
  rt::LatestSlot<supervisor::SupervisorState> modes;
  supervisor::SupervisorState state;
  state.mode = supervisor::Mode::kTrack;
  modes.write(state);
  TaskRig rig(defaultParams(), &modes);
  const trajectory_server::TimedTrajectory first = rig.planOnceAroundTheWall();
  ASSERT_TRUE(first.trajectory);

  state.mode = supervisor::Mode::kDegraded;
  modes.write(state);
  rig.odometry.write(odometryAt(first.trajectory->sample(0.05).p_W_m, rt::secondsToNs(0.05)));
  rig.target.write(personAt(Eigen::Vector3d(7.0, 0.0, 1.0), rt::secondsToNs(0.05)));
  rig.step(0.05);
  EXPECT_EQ(rig.task->degradedBrakes(), 1U);
  EXPECT_EQ(rig.task->count(PlanStatus::kPlanned), 1U);  // this cycle only braked
  const trajectory_server::TimedTrajectory brake = rig.task->lastPublished();
  ASSERT_TRUE(brake.trajectory);
  EXPECT_NE(brake.trajectory, first.trajectory);
  EXPECT_LT(brake.trajectory->sample(brake.trajectory->durationS()).v_W_mps.norm(), 1e-6);  // to rest

  rig.odometry.write(odometryAt(brake.trajectory->sample(0.05).p_W_m, rt::secondsToNs(0.1)));
  rig.target.write(personAt(Eigen::Vector3d(7.0, 0.0, 1.0), rt::secondsToNs(0.1)));
  rig.step(0.1);  // still degraded: it plans again
  EXPECT_EQ(rig.task->degradedBrakes(), 1U);
  EXPECT_EQ(rig.task->count(PlanStatus::kPlanned), 2U);
  EXPECT_NE(rig.task->lastPublished().trajectory, brake.trajectory);
}

TEST(PlanningTask, FailedCheckKeepsTheOldTrajectory) {
  // The final check's limits are far below what the optimiser flies: every plan fails the check.
  TrackingPlannerParams params = defaultParams();
  TaskRig rig(params);
  const WallWorld world;
  rig.grid.write(std::make_shared<const mapping::LocalGrid>(world.grid));
  rig.odometry.write(odometryAt(Eigen::Vector3d(0, 0, 1.5)));
  rig.target.write(personAt(Eigen::Vector3d(7.0, 0.0, 1.0), 0));
  rig.step(0.0);
  ASSERT_EQ(rig.task->count(PlanStatus::kPlanned), 1U);
  const auto first = rig.task->lastPublished().trajectory;

  params.check.max_velocity_mps = 0.1;    // the lowest the config allows (trajectoryCheckFields())
  params.check.max_repair_stretch = 1.0;  // no repair
  TaskRig strict(params);
  strict.grid.write(std::make_shared<const mapping::LocalGrid>(world.grid));
  strict.odometry.write(odometryAt(Eigen::Vector3d(0, 0, 1.5)));
  strict.target.write(personAt(Eigen::Vector3d(7.0, 0.0, 1.0), 0));
  strict.step(0.0);
  EXPECT_EQ(strict.task->count(PlanStatus::kCheckFailed), 1U);
  EXPECT_EQ(strict.trajectories.version(), 0U);  // nothing was published
  EXPECT_FALSE(strict.task->lastPublished().trajectory);
  EXPECT_TRUE(first);
}

TEST(PlanningTask, FailedCycleWithBlockedOldTrajectoryStops) {
  TrackingPlannerParams params = defaultParams();
  params.stop_check_horizon_s = 2.0;
  TaskRig rig(params);
  const trajectory_server::TimedTrajectory first = rig.planOnceAroundTheWall();
  ASSERT_TRUE(first.trajectory);
  // An obstacle appears across the old trajectory 1.7 s ahead, and in the same cycle the person is lost
  // (the cycle fails): the old trajectory must not be flown into it.
  const Eigen::Vector3d p = first.trajectory->sample(1.8).p_W_m;
  rig.grid.write(std::make_shared<const mapping::LocalGrid>(
      makeBoxGrid(Eigen::Vector3d(20, 20, 5), Eigen::Vector3d(3, 0, 1.5),
                  {{p - Eigen::Vector3d(0.1, 1.0, 1.0), p + Eigen::Vector3d(0.1, 1.0, 1.0)}})));
  rig.loseThePersonAt(0.1, first.trajectory->sample(0.1).p_W_m);
  ASSERT_EQ(rig.task->count(PlanStatus::kStopped), 1U)
      << "no_target " << rig.task->count(PlanStatus::kNoTarget) << " duration " << first.trajectory->durationS()
      << " p " << p.transpose();
  const trajectory_server::TimedTrajectory stop = rig.task->lastPublished();
  ASSERT_NE(stop.trajectory, first.trajectory);
  // The stop starts where the old trajectory is at the hand-over and ends at rest.
  const double handover_s = rt::nsToSeconds(stop.start_ns - first.start_ns);
  EXPECT_LT((stop.trajectory->sample(0.0).p_W_m - first.trajectory->sample(handover_s).p_W_m).norm(), 1e-9);
  EXPECT_LT(stop.trajectory->sample(stop.trajectory->durationS()).v_W_mps.norm(), 1e-9);
}

// The task in closed loop with readers that hold what it publishes as the real ones do: the trajectory
// server (the real one: copies of the current and pending trajectories, by value) and the output
// recorder (the newest wrapper handle). The drone flies the served trajectory perfectly; the person
// walks along +x at 1 m/s on open ground.
struct FollowRig {
  const mapping::LocalGrid open_ground =
      makeBoxGrid(Eigen::Vector3d(30, 20, 5), Eigen::Vector3d(8, 0, 1.5), {{{-10, -10, -0.2}, {20, 10, 0.0}}});
  TaskRig rig;
  trajectory_server::TrajectoryServer server{trajectory_server::TrajectoryServerParams{}};
  std::shared_ptr<const trajectory_server::TimedTrajectory> recorder_holds;
  std::uint64_t seen_version = 0;
  hal::OdometrySample odometry = odometryAt(Eigen::Vector3d(0, 0, 1.5));
  int k = 0;

  FollowRig() { rig.grid.write(std::make_shared<const mapping::LocalGrid>(open_ground)); }

  /// One 20 Hz cycle: the sensors, the planner, then the readers and the drone.
  void cycle() {
    const rt::TimeNs now_ns = rt::secondsToNs(0.05 * k++);
    odometry.stamp_ns = now_ns;
    rig.odometry.write(odometry);
    const double t_s = rt::nsToSeconds(now_ns);
    rig.target.write(personAt(Eigen::Vector3d(5.0 + t_s, 0.0, 1.0), now_ns, Eigen::Vector3d(1, 0, 0)));
    rig.task->step(now_ns);
    if (rig.trajectories.version() != seen_version) {
      seen_version = rig.trajectories.version();
      recorder_holds = rig.trajectories.read();
      server.setTrajectory(*recorder_holds);
    }
    if (const std::optional<hal::Setpoint> sp = server.sample(now_ns + rt::secondsToNs(0.05))) {
      odometry.p_WB_m = sp->p_W_m;
      odometry.v_WB_mps = sp->v_W_mps;
    }
  }
};

// Samples of a trajectory, bit for bit, to see whether anyone rewrote it.
std::vector<double> samplesOf(const trajectory_server::Trajectory& trajectory) {
  std::vector<double> out;
  for (double t = 0.0; t <= trajectory.durationS() + 0.1; t += 0.1) {
    const trajectory_server::TrajectorySample s = trajectory.sample(t);
    out.insert(out.end(), {s.p_W_m.x(), s.p_W_m.y(), s.p_W_m.z(), s.v_W_mps.x(), s.v_W_mps.y(), s.a_W_mps2.x()});
  }
  out.push_back(trajectory.durationS());
  return out;
}

// DESIGN.md rule 4 for the task: once warm, a cycle allocates exactly what the planner's own cycle does
// (the LBFGS++ temporaries, see WarmCycleAllocatesOnlyLbfgsTemporaries), so publishing a trajectory
// allocates nothing: it is lent from the task's pools and comes back when the readers let it go.
TEST(PlanningTask, SteadyStateCycleAllocatesOnlyTheOptimizersTemporaries) {
  if (!aerotrack::test::kMallocCounted) GTEST_SKIP() << "malloc belongs to the sanitizer";
  ASSERT_GE(aerotrack::test::mallocsOfAHeapBuffer(), 1);
  FollowRig follow;
  // Warm: the predictor full, the pools filled, and the drone caught up (one corridor box from then on:
  // the optimiser's piece count, and so its scratch size, no longer changes).
  for (int i = 0; i < 60; ++i) follow.cycle();
  ASSERT_GE(follow.rig.task->count(PlanStatus::kPlanned), 50U);
  const std::uint64_t growths = follow.rig.task->poolGrowths();
  const std::uint64_t version = follow.rig.trajectories.version();
  constexpr int kCycles = 40;
  const int boxes = follow.rig.task->lastReport().corridor_boxes;
  int planned = 0;
  int same_boxes = 0;
  long lbfgs_updates = 0;
  long mallocs = 0;
  {
    const aerotrack::test::MallocCount count;
    for (int i = 0; i < kCycles; ++i) {
      follow.cycle();
      const PlanReport& report = follow.rig.task->lastReport();
      planned += report.status == PlanStatus::kPlanned ? 1 : 0;
      same_boxes += report.corridor_boxes == boxes ? 1 : 0;
      if (report.status == PlanStatus::kPlanned && report.optimizer_status != OptimizerStatus::kLineSearch)
        lbfgs_updates += report.optimizer_iterations - 1;  // two temporaries per L-BFGS update
    }
    mallocs = count.count();
  }
  ASSERT_EQ(planned, kCycles);     // every cycle published (and the count above is exact)
  ASSERT_EQ(same_boxes, kCycles);  // the piece count (the optimiser's scratch size) never changed
  EXPECT_EQ(follow.rig.trajectories.version(), version + kCycles);
  EXPECT_EQ(mallocs, 2 * lbfgs_updates);
  EXPECT_EQ(follow.rig.task->poolGrowths(), growths);  // the pools stopped growing after warm-up
}

TEST(PlanningTask, ATrajectoryAReaderStillHoldsIsNeverRewritten) {
  FollowRig follow;
  for (int i = 0; i < 20; ++i) follow.cycle();
  // The server's way: a copy of the wrapper (the inner handle only); the recorder's way: the wrapper.
  const trajectory_server::TimedTrajectory server_copy = *follow.rig.trajectories.read();
  for (int i = 0; i < 3; ++i) follow.cycle();
  const std::shared_ptr<const trajectory_server::TimedTrajectory> recorder_handle = follow.rig.trajectories.read();
  ASSERT_TRUE(server_copy.trajectory);
  ASSERT_TRUE(recorder_handle && recorder_handle->trajectory);
  ASSERT_NE(server_copy.trajectory, recorder_handle->trajectory);
  const std::vector<double> server_before = samplesOf(*server_copy.trajectory);
  const std::vector<double> recorder_before = samplesOf(*recorder_handle->trajectory);
  const trajectory_server::TimedTrajectory recorder_wrapper_before = *recorder_handle;
  const std::uint64_t planned_before = follow.rig.task->count(PlanStatus::kPlanned);

  // Many cycles: every pooled object is lent again several times over.
  constexpr int kCycles = 3 * static_cast<int>(PlanningTask::kTrajectoryPoolSize + PlanningTask::kTimedPoolSize);
  for (int i = 0; i < kCycles; ++i) follow.cycle();
  ASSERT_EQ(follow.rig.task->count(PlanStatus::kPlanned), planned_before + kCycles);

  EXPECT_EQ(samplesOf(*server_copy.trajectory), server_before);
  EXPECT_EQ(samplesOf(*recorder_handle->trajectory), recorder_before);
  EXPECT_EQ(recorder_handle->trajectory, recorder_wrapper_before.trajectory);
  EXPECT_EQ(recorder_handle->start_ns, recorder_wrapper_before.start_ns);
  EXPECT_EQ(recorder_handle->source_capture_ns, recorder_wrapper_before.source_capture_ns);
  // Neither held object is what the planner publishes now.
  const auto newest = follow.rig.trajectories.read();
  EXPECT_NE(newest.get(), recorder_handle.get());
  EXPECT_NE(newest->trajectory, server_copy.trajectory);
  EXPECT_NE(newest->trajectory, recorder_handle->trajectory);
}

TEST(MarginWalk, AStartInTheMarginMayOnlyBeLeftQuickly) {
  MarginWalk leaving(0.3);  // in the margin for 0.2 s, then clear: fine
  for (double t = 0.0; t < 0.2; t += 0.02) EXPECT_FALSE(leaving.blocked(t, true)) << t;
  for (double t = 0.2; t < 1.0; t += 0.02) EXPECT_FALSE(leaving.blocked(t, false)) << t;
  EXPECT_TRUE(leaving.blocked(1.0, true));  // back in after clear: a collision ahead

  MarginWalk staying(0.3);  // never leaves: blocked once the escape time is over
  double first_blocked_s = -1.0;
  for (double t = 0.0; t < 1.0 && first_blocked_s < 0.0; t += 0.02)
    if (staying.blocked(t, true)) first_blocked_s = t;
  EXPECT_NEAR(first_blocked_s, 0.32, 0.011);
}

TEST(PlanningTask, FailedCycleAlongASurfaceSeenBesideTheDroneStops) {
  TrackingPlannerParams params = defaultParams();
  TaskRig rig(params);
  const trajectory_server::TimedTrajectory first = rig.planOnceAroundTheWall();
  ASSERT_TRUE(first.trajectory);
  // A surface is seen right beside the drone (the far face of a corner rounded in unknown space): its
  // inflation margin covers the drone and the old trajectory ahead, which never leaves it. The old rule
  // (only a margin entered after a clear sample counts) would have flown on along it.
  const Eigen::Vector3d a = first.trajectory->sample(0.1).p_W_m;
  Eigen::Vector3d lo = a, hi = a;
  for (double t = 0.1; t <= 1.5; t += 0.02) {
    lo = lo.cwiseMin(first.trajectory->sample(t).p_W_m);
    hi = hi.cwiseMax(first.trajectory->sample(t).p_W_m);
  }
  rig.grid.write(std::make_shared<const mapping::LocalGrid>(
      makeBoxGrid(Eigen::Vector3d(20, 20, 5), Eigen::Vector3d(3, 0, 1.5),
                  {{lo - Eigen::Vector3d(0.05, 0.05, 0.05), hi + Eigen::Vector3d(0.05, 0.05, 0.05)}})));
  ASSERT_TRUE(rig.grid.read()->isOccupied(a));
  rig.loseThePersonAt(0.1, a);
  EXPECT_EQ(rig.task->count(PlanStatus::kStopped), 1U);
  EXPECT_NE(rig.task->lastPublished().trajectory, first.trajectory);
}

// --- Issue 21: one set of limits, and the repair of a trajectory over them by re-timing. ---

// Three quintic pieces from rest at the origin, through two waypoints with a turn, to rest: fast enough
// (2.2 s for about 5 m) to have large velocity, acceleration and jerk.
PolynomialTrajectory fastTurn() {
  MinJerkSpline spline;
  spline.reset(restAt(Eigen::Vector3d(0, 0, 1.5)), restAt(Eigen::Vector3d(3, 2, 1.5)), 3);
  Eigen::Matrix3Xd waypoints(3, 2);
  waypoints << 1.0, 2.5, 0.0, 0.5, 1.5, 1.5;
  Eigen::VectorXd durations(3);
  durations << 0.8, 0.6, 0.8;
  EXPECT_TRUE(spline.generate(waypoints, durations));
  PolynomialTrajectory out;
  out.assign(spline);
  return out;
}

// The reference: peak norms of derivative `order`, densely sampled (1 ms).
double densePeak(const PolynomialTrajectory& trajectory, int order) {
  double peak = 0.0;
  for (double t = 0.0; t <= trajectory.durationS(); t += 1e-3)
    peak = std::max(peak, trajectory.derivative(order, t).norm());
  return peak;
}

TEST(TrajectoryRepair, OptimiserLimitsAreDerivedFromTheChecksByTheStatedFraction) {
  TrackingPlannerParams params = defaultParams();
  params.optimizer.max_velocity_mps = 99.0;  // ignored: not a config key, overwritten by create()
  params.optimizer_limit_fraction = 0.9;
  const TrackingPlanner planner = makePlanner(params);
  EXPECT_DOUBLE_EQ(planner.params().optimizer.max_velocity_mps, 0.9 * params.check.max_velocity_mps);
  EXPECT_DOUBLE_EQ(planner.params().optimizer.max_acceleration_mps2, 0.9 * params.check.max_acceleration_mps2);
  EXPECT_DOUBLE_EQ(planner.params().optimizer.max_jerk_mps3, 0.9 * params.check.max_jerk_mps3);
}

TEST(TrajectoryRepair, StretchDividesEachDerivativeByItsPowerAndKeepsThePath) {
  const PolynomialTrajectory original = fastTurn();
  PolynomialTrajectory stretched = original;
  constexpr double kFactor = 1.7;
  stretched.stretchTime(kFactor);
  EXPECT_NEAR(stretched.durationS(), kFactor * original.durationS(), 1e-12);
  for (double t = 0.0; t <= original.durationS(); t += 0.01) {
    // Same place at the stretched time: the geometry is unchanged.
    EXPECT_LT((stretched.derivative(0, kFactor * t) - original.derivative(0, t)).norm(), 1e-9) << t;
    for (int order = 1; order <= 3; ++order) {
      const Eigen::Vector3d expected = original.derivative(order, t) / std::pow(kFactor, order);
      EXPECT_LT((stretched.derivative(order, kFactor * t) - expected).norm(), 1e-8) << order << " " << t;
    }
  }
}

// A trajectory over one limit by a known factor (the others loose): the stretch factor is that factor (a
// power's root of it), and the stretched trajectory is within every limit, densely sampled.
TEST(TrajectoryRepair, StretchFactorBringsAViolationByAKnownFactorWithinTheLimits) {
  const PolynomialTrajectory original = fastTurn();
  const double v_peak = densePeak(original, 1);
  const double a_peak = densePeak(original, 2);
  const double j_peak = densePeak(original, 3);
  constexpr double kOver = 1.5;  // the limit is exceeded by this factor
  struct Case {
    double v_limit, a_limit, j_limit, expected_factor;
  };
  for (const Case& c : {Case{v_peak / kOver, 10 * a_peak, 10 * j_peak, kOver},
                        Case{10 * v_peak, a_peak / kOver, 10 * j_peak, std::sqrt(kOver)},
                        Case{10 * v_peak, 10 * a_peak, j_peak / kOver, std::cbrt(kOver)}}) {
    TrajectoryCheckParams params;
    params.max_velocity_mps = c.v_limit;
    params.max_acceleration_mps2 = c.a_limit;
    params.max_jerk_mps3 = c.j_limit;
    params.horizon_s = 10.0;  // the whole trajectory
    params.sample_step_s = 0.005;
    const double k = dynamicStretchFactor(original, params);
    EXPECT_NEAR(k, c.expected_factor, 2e-3 * c.expected_factor);
    PolynomialTrajectory repaired = original;
    repaired.stretchTime(k);
    EXPECT_LE(densePeak(repaired, 1), c.v_limit * 1.002);
    EXPECT_LE(densePeak(repaired, 2), c.a_limit * 1.002);
    EXPECT_LE(densePeak(repaired, 3), c.j_limit * 1.002);
    EXPECT_NEAR(dynamicStretchFactor(repaired, params), 1.0, 2e-3);
  }
}

TEST(TrajectoryRepair, RetimingKeepsTheStartStateAndTheJunctions) {
  const PolynomialTrajectory original = fastTurn();
  StatePva start;
  const trajectory_server::TrajectorySample s0 = original.sample(0.0);
  start << s0.p_W_m, Eigen::Vector3d(0.3, 0.1, 0.0), Eigen::Vector3d(0.5, 0, 0);  // moving at the hand-over
  MinJerkSpline scratch;
  PolynomialTrajectory retimed;
  ASSERT_TRUE(retimeKeepingStart(original, start, 1.4, scratch, retimed));
  ASSERT_EQ(retimed.pieces(), original.pieces());
  const trajectory_server::TrajectorySample r0 = retimed.sample(0.0);
  EXPECT_LT((r0.p_W_m - start.col(0)).norm(), 1e-9);
  EXPECT_LT((r0.v_W_mps - start.col(1)).norm(), 1e-9);
  EXPECT_LT((r0.a_W_mps2 - start.col(2)).norm(), 1e-9);
  double t_original = 0.0;
  double t_retimed = 0.0;
  for (int i = 0; i < original.pieces(); ++i) {
    EXPECT_NEAR(retimed.pieceDurationS(i), 1.4 * original.pieceDurationS(i), 1e-12);
    t_original += original.pieceDurationS(i);
    t_retimed += retimed.pieceDurationS(i);
    EXPECT_LT((retimed.derivative(0, t_retimed) - original.derivative(0, t_original)).norm(), 1e-9) << i;
  }
}

TEST(TrajectoryRepair, PlannerRepairsAnAccelerationViolationAndRefusesACollision) {
  TrackingPlannerParams params = defaultParams();
  params.min_person_distance_m = 0.0;  // the person plays no part here
  const PolynomialTrajectory fast = fastTurn();
  // Limits the fast turn exceeds in acceleration only, by 1.3.
  params.check.max_velocity_mps = 2.0 * densePeak(fast, 1);
  params.check.max_acceleration_mps2 = densePeak(fast, 2) / 1.3;
  params.check.max_jerk_mps3 = 2.0 * densePeak(fast, 3);
  TrackingPlanner planner = makePlanner(params);
  TrackingPlannerStages stages(planner);
  const TrackingPlannerStages::PersonMotion person;
  const StatePva start = restAt(Eigen::Vector3d(0, 0, 1.5));

  // Open space: the first check fails on acceleration; the repair re-times it within every limit.
  const mapping::LocalGrid open = makeBoxGrid(Eigen::Vector3d(20, 20, 5), Eigen::Vector3d(0, 0, 1.5), {});
  PolynomialTrajectory out = fast;
  const CheckResult first = stages.checkPlannedTrajectory(out, open, person, 0);
  ASSERT_EQ(first.verdict, CheckVerdict::kAcceleration);
  double stretch = 0.0;
  EXPECT_EQ(stages.repairPlannedTrajectory(first, start, out, open, person, stretch).verdict, CheckVerdict::kOk);
  EXPECT_GT(stretch, 1.0);
  EXPECT_LE(stretch, params.check.max_repair_stretch);
  const double tolerance = 1.0 + params.check.tolerance;
  EXPECT_LE(densePeak(out, 2), params.check.max_acceleration_mps2 * tolerance);
  EXPECT_LE(densePeak(out, 1), params.check.max_velocity_mps * tolerance);
  EXPECT_LE(densePeak(out, 3), params.check.max_jerk_mps3 * tolerance);
  EXPECT_NEAR(out.durationS(), stretch * fast.durationS(), 1e-9);

  // A box on the path (around the second waypoint): blocked whatever the timing. A first verdict of
  // collision is not repaired at all; one of acceleration is re-timed, then refused on the grid.
  const mapping::LocalGrid blocked =
      makeBoxGrid(Eigen::Vector3d(20, 20, 5), Eigen::Vector3d(0, 0, 1.5), {{{2.3, 1.3, 1.0}, {2.7, 1.7, 2.0}}});
  PolynomialTrajectory through = fast;
  stretch = 0.0;
  const CheckResult grid_first{CheckVerdict::kGridBlocked, 1.0};
  EXPECT_EQ(stages.repairPlannedTrajectory(grid_first, start, through, blocked, person, stretch).verdict,
            CheckVerdict::kGridBlocked);
  EXPECT_EQ(stretch, 1.0);
  EXPECT_NEAR(through.durationS(), fast.durationS(), 1e-12);  // untouched
  const CheckResult accel_first = stages.checkPlannedTrajectory(through, blocked, person, 0);
  ASSERT_EQ(accel_first.verdict, CheckVerdict::kAcceleration);  // the acceleration peak comes first
  EXPECT_EQ(stages.repairPlannedTrajectory(accel_first, start, through, blocked, person, stretch).verdict,
            CheckVerdict::kGridBlocked);
}

// The task counts the final check's verdicts: passed first time, repaired (by the first verdict), rejected.
TEST(PlanningTask, CountsChecksPassedRepairedAndRejected) {
  // Default limits: passed first time.
  TaskRig rig;
  ASSERT_TRUE(rig.planOnceAroundTheWall().trajectory);
  EXPECT_EQ(rig.task->checksRun(), 1U);
  EXPECT_EQ(rig.task->checksPassedFirstTime(), 1U);
  EXPECT_EQ(rig.task->checksRejected(), 0U);

  // The optimiser aims at the limits themselves and the check allows no tolerance: its soft penalties let
  // its output exceed them a little, and the repair re-times it.
  TrackingPlannerParams params = defaultParams();
  params.optimizer_limit_fraction = 1.0;
  params.check.tolerance = 0.0;
  params.check.max_acceleration_mps2 = 1.0;
  TaskRig repairing(params);
  ASSERT_TRUE(repairing.planOnceAroundTheWall().trajectory);
  EXPECT_EQ(repairing.task->checksRun(), 1U);
  EXPECT_EQ(repairing.task->checksPassedFirstTime(), 0U);
  std::uint64_t repaired = 0;
  for (const CheckVerdict v : {CheckVerdict::kVelocity, CheckVerdict::kAcceleration, CheckVerdict::kJerk})
    repaired += repairing.task->checkRepairs(v);
  EXPECT_EQ(repaired, 1U);
  EXPECT_GT(repairing.task->maxRepairStretch(), 1.0);

  // Repair off (a stretch of at most 1) and limits far below the plan: rejected, by the verdict.
  params = defaultParams();
  params.check.max_velocity_mps = 0.1;
  params.check.max_repair_stretch = 1.0;
  TaskRig strict(params);
  EXPECT_FALSE(strict.planOnceAroundTheWall().trajectory);
  EXPECT_EQ(strict.task->checksRun(), 1U);
  EXPECT_EQ(strict.task->checksRejected(), 1U);
  EXPECT_EQ(strict.task->checkFailures(CheckVerdict::kVelocity), 1U);
  EXPECT_EQ(strict.task->checkRepairFailures(CheckVerdict::kVelocity), 1U);
}

}  // namespace
}  // namespace aerotrack::planning
