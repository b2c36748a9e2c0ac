// Bystanders give way to the followed person (give_way.hpp, issue 22): a walker headed through them passes two
// body radii away, drifting aside at a bounded speed; one who never comes near is untouched; a wall on the side
// away from the person sends them round the other side; the offset moves the whole body; bad parameters are
// errors. And the shipped crowd, every seed: no bystander's body ever overlaps the person's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "aerotrack/hal/sim/bystanders.hpp"
#include "aerotrack/hal/sim/give_way.hpp"
#include "aerotrack/hal/sim/scenario.hpp"
#include "support/require.hpp"

namespace aerotrack::hal::sim {
namespace {

using aerotrack::test::require;

WalkingPerson walker(const std::vector<PathPoint>& path) {
  return require(WalkingPerson::create(PersonParams{}, path), "walker");
}

ObstacleWorld emptyWorld() {
  return require(ObstacleWorld::create({}, {}), "world");
}

/// The closest the two centres come over [0, horizon_s] (5 ms steps, between the offsets' samples too).
double closestM(const WalkingPerson& person, const WalkingPerson& w, const GiveWay& g, double horizon_s) {
  double closest = 1e9;
  for (double t = 0.0; t <= horizon_s; t += 0.005) {
    const PersonState s = withOffset(w.state(t), g, t);
    closest = std::min(closest, (s.p_W_m - person.state(t).p_W_m).head<2>().norm());
  }
  return closest;
}

/// When their generated walks come closest (the walker starts from rest, so not at distance / speed).
double meetingS(const WalkingPerson& person, double person_delay_s, const WalkingPerson& w, double walker_delay_s,
                double horizon_s) {
  double best_t = 0.0, best = 1e9;
  for (double t = 0.0; t <= horizon_s; t += 0.005) {
    const double d = (w.state(t - walker_delay_s).p_W_m - person.state(t - person_delay_s).p_W_m).head<2>().norm();
    if (d < best) best = d, best_t = t;
  }
  return best_t;
}

TEST(GiveWay, GivenAWalkerHeadedStraightThroughAStandingPerson_WhenTheyGiveWay_ThenTheyPassTwoBodyRadiiAway) {
  const WalkingPerson person = walker({{{5.0, 0.0}, 1.0, 0.0}});
  const WalkingPerson w = walker({{{0.0, 0.0}, 1.2, 0.0}, {{10.0, 0.0}, 0.0, 0.0}});
  GiveWayParams params;
  params.horizon_s = 15.0;
  const GiveWay g = require(GiveWay::compute(person, 0.0, w, 0.0, emptyWorld(), params), "compute");
  EXPECT_EQ(g.encounters(), 1);
  EXPECT_GE(closestM(person, w, g, params.horizon_s), params.min_distance_m - 0.01);
  // Untouched far from the meeting: at the start and at the end of the walk.
  EXPECT_LT(g.offsetM(0.0).norm(), 1e-12);
  EXPECT_LT(g.offsetM(14.0).norm(), 1e-12);
  // A side-step, never a jump: the offset changes at most at step_speed_mps, and the velocity carries it.
  double fastest = 0.0;
  for (double t = 0.0; t < params.horizon_s; t += 0.01) fastest = std::max(fastest, g.rateMps(t).norm());
  EXPECT_LE(fastest, params.step_speed_mps + 1e-9);
  EXPECT_GT(fastest, 0.9 * params.step_speed_mps) << "it did step aside";
  // Straight through (no side to prefer): to the walker's left, +y for a walk along +x.
  const double t_meet = meetingS(person, 0.0, w, 0.0, params.horizon_s);
  EXPECT_NEAR(g.offsetM(t_meet).x(), 0.0, 1e-9);
  EXPECT_NEAR(g.offsetM(t_meet).y(), params.min_distance_m, 0.02);
}

TEST(GiveWay, GivenAWalkerWhoPassesAMetreAway_ThenNothingChanges) {
  const WalkingPerson person = walker({{{0.0, 0.0}, 1.3, 0.0}, {{10.0, 0.0}, 0.0, 0.0}});
  const WalkingPerson w = walker({{{10.0, 1.0}, 1.3, 0.0}, {{0.0, 1.0}, 0.0, 0.0}});
  GiveWayParams params;
  params.horizon_s = 12.0;
  const GiveWay g = require(GiveWay::compute(person, 0.0, w, 0.0, emptyWorld(), params), "compute");
  EXPECT_EQ(g.encounters(), 0);
  for (double t = 0.0; t <= params.horizon_s; t += 0.1) EXPECT_EQ(g.offsetM(t), Eigen::Vector2d::Zero()) << t;
}

TEST(GiveWay, GivenAWallOnTheSideAwayFromThePerson_ThenTheWalkerGoesRoundTheOtherSide) {
  // The walker would pass 0.3 m to the person's left (+y), beside a wall from y = 0.55 m: no room for a body there.
  const WalkingPerson person = walker({{{5.0, 0.0}, 1.0, 0.0}});
  const WalkingPerson w = walker({{{0.0, 0.3}, 1.2, 0.0}, {{10.0, 0.3}, 0.0, 0.0}});
  const ObstacleWorld wall =
      require(ObstacleWorld::create({Box{Eigen::Vector3d(3.0, 0.55, 0.0), Eigen::Vector3d(7.0, 2.0, 2.0)}}, {}), "w");
  GiveWayParams params;
  params.horizon_s = 15.0;
  const GiveWay g = require(GiveWay::compute(person, 0.0, w, 0.0, wall, params), "compute");
  const double t_meet = meetingS(person, 0.0, w, 0.0, params.horizon_s);
  EXPECT_LE(0.3 + g.offsetM(t_meet).y(), -params.min_distance_m + 0.02) << "passed on the person's right";
  EXPECT_GE(closestM(person, w, g, params.horizon_s), params.min_distance_m - 0.01);
  // Without the wall: to the left, away from the person.
  const GiveWay free = require(GiveWay::compute(person, 0.0, w, 0.0, emptyWorld(), params), "compute");
  EXPECT_GE(0.3 + free.offsetM(t_meet).y(), params.min_distance_m - 0.02);
}

TEST(GiveWay, GivenStartDelays_ThenEachWalkIsTimedFromItsOwnStart) {
  // The person walks +x from x = 0 after 4 s; the walker comes the other way along the same line after 1 s:
  // they would meet about where 10 - 1.2 (t - 1) = 1.2 (t - 4), at t = 6.67 s (later: both start from rest).
  const WalkingPerson person = walker({{{0.0, 0.0}, 1.2, 0.0}, {{20.0, 0.0}, 0.0, 0.0}});
  const WalkingPerson w = walker({{{10.0, 0.0}, 1.2, 0.0}, {{-10.0, 0.0}, 0.0, 0.0}});
  GiveWayParams params;
  params.horizon_s = 20.0;
  const GiveWay g = require(GiveWay::compute(person, 4.0, w, 1.0, emptyWorld(), params), "compute");
  EXPECT_EQ(g.encounters(), 1);
  const double t_meet = meetingS(person, 4.0, w, 1.0, params.horizon_s);
  EXPECT_GT(t_meet, 6.67);
  EXPECT_LT(t_meet, 7.5);
  EXPECT_NEAR(std::abs(g.offsetM(t_meet).y()), params.min_distance_m, 0.02);
  double closest = 1e9;
  for (double t = 0.0; t <= params.horizon_s; t += 0.005)
    closest = std::min(closest, (withOffset(w.state(t - 1.0), g, t).p_W_m - person.state(t - 4.0).p_W_m).norm());
  EXPECT_GE(closest, params.min_distance_m - 0.01);
}

TEST(GiveWay, TheOffsetMovesTheWholeBodyAndItsVelocity) {
  const WalkingPerson person = walker({{{5.0, 0.0}, 1.0, 0.0}});
  const WalkingPerson w = walker({{{0.0, 0.0}, 1.2, 0.0}, {{10.0, 0.0}, 0.0, 0.0}});
  GiveWayParams params;
  params.horizon_s = 15.0;
  const GiveWay g = require(GiveWay::compute(person, 0.0, w, 0.0, emptyWorld(), params), "compute");
  const double t = meetingS(person, 0.0, w, 0.0, params.horizon_s) - 0.5;  // drifting aside
  const PersonState before = w.state(t);
  const PersonState after = withOffset(before, g, t);
  const Eigen::Vector3d shift(g.offsetM(t).x(), g.offsetM(t).y(), 0.0);
  ASSERT_GT(shift.norm(), 0.05);
  EXPECT_LT((after.p_W_m - before.p_W_m - shift).norm(), 1e-12);
  for (std::size_t i = 0; i < kNumKeypoints; ++i)
    EXPECT_LT((after.keypoints_W_m[i] - before.keypoints_W_m[i] - shift).norm(), 1e-12) << i;
  EXPECT_LT((after.v_W_mps.head<2>() - before.v_W_mps.head<2>() - g.rateMps(t)).norm(), 1e-12);
  EXPECT_EQ(after.heading_rad, before.heading_rad);
  // The rate is the offset's derivative (central difference).
  const Eigen::Vector2d numeric = (g.offsetM(t + 0.005) - g.offsetM(t - 0.005)) / 0.01;
  EXPECT_LT((numeric - g.rateMps(t)).norm(), 1e-6);
}

TEST(GiveWay, BadParametersAreErrors) {
  const WalkingPerson person = walker({{{5.0, 0.0}, 1.0, 0.0}});
  const ObstacleWorld world = emptyWorld();
  for (const auto& [field, value] : std::vector<std::pair<std::string, double>>{
           {"min_distance_m", 0.0}, {"step_speed_mps", -1.0}, {"sample_s", std::nan("")}, {"horizon_s", 1e9}}) {
    GiveWayParams params;
    if (field == "min_distance_m") params.min_distance_m = value;
    if (field == "step_speed_mps") params.step_speed_mps = value;
    if (field == "sample_s") params.sample_s = value;
    if (field == "horizon_s") params.horizon_s = value;
    const auto g = GiveWay::compute(person, 0.0, person, 0.0, world, params);
    ASSERT_FALSE(g) << field;
    EXPECT_NE(g.error().message.find("give way"), std::string::npos) << g.error().message;
  }
}

TEST(GiveWay, InTheShippedCrowdNoBystandersBodyEverOverlapsThePersons) {
  const ScenarioSpec spec =
      require(loadScenarioSpec(AEROTRACK_SOURCE_DIR "/config/scenarios/crowd.yaml"), "crowd.yaml");
  int stepped = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const ScenarioInstance trial = require(instantiate(spec, seed), "instantiate");
    const WalkingPerson person = require(WalkingPerson::create(trial.spec.person, trial.spec.path), "person");
    for (const Bystander& b : trial.bystanders.people) {
      const WalkingPerson w = require(WalkingPerson::create(b.params, b.path), b.origin);
      stepped += b.give_way.encounters();
      double closest = 1e9;
      for (double t = 0.0; t <= trial.duration_s; t += 0.01) {
        const PersonState s = withOffset(w.state(t - b.start_delay_s), b.give_way, t);
        closest =
            std::min(closest, (s.p_W_m - person.state(t - trial.spec.person_start_delay_s).p_W_m).head<2>().norm());
      }
      EXPECT_GE(closest, 2.0 * kPersonBodyRadiusM - 0.01) << "seed " << seed << " " << b.origin;
    }
  }
  EXPECT_GT(stepped, 0) << "some walker's path did run into the person";
}

}  // namespace
}  // namespace aerotrack::hal::sim
