// The paper's verdict (followed_all_the_way), the identity metrics and the person's measured speed
// (issue 20 items 1 and 5) against synthetic runs whose answers are known by construction.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "aerotrack/hal/sim/metrics.hpp"

namespace aerotrack::hal::sim {
namespace {

constexpr double kDtS = 0.02;  // the simulation's 50 Hz metrics period

ScenarioSpec verdictSpec() {
  ScenarioSpec s;
  s.drone.radius_m = 0.25;
  s.success.tracking_distance_m = 2.5;
  s.success.final_distance_factor = 2.0;
  s.success.max_loss_s = 3.0;
  return s;
}

/// Sample i of a run at 50 Hz: the drone 2.5 m from the person (or distance_m), tracking from 0.
MetricsSample verdictSample(int i, Sight sight, double distance_m = 2.5) {
  MetricsSample s;
  s.t_s = kDtS * i;
  s.dt_s = kDtS;
  s.drone_m = Eigen::Vector3d(distance_m, 0.0, 1.5);
  s.person_m = Eigen::Vector3d::Zero();
  s.clearance_m = 5.0;
  s.sight = sight;
  s.tracking = true;
  return s;
}

/// A 20 s run, visible but for [5 s, 5 s + hidden_s).
SimMetrics runWithLoss(double hidden_s) {
  SimMetrics m(verdictSpec());
  const int first = 250, end = 250 + static_cast<int>(std::lround(hidden_s / kDtS));
  for (int i = 0; i < 1000; ++i) m.record(verdictSample(i, i >= first && i < end ? Sight::kOccluded : Sight::kVisible));
  return m;
}

TEST(ClosestApproach, GivenBystandersComingNearerAndFartherThenTheClosestWhileTrackingIsKept) {
  SimMetrics m(verdictSpec());
  EXPECT_FALSE(std::isfinite(m.closestBystanderM()));  // nobody yet
  EXPECT_FALSE(std::isfinite(m.closestLookAlikeM()));
  for (int i = 0; i < 100; ++i) {
    MetricsSample s = verdictSample(i, Sight::kVisible);
    s.tracking = i >= 10;                                   // before the person starts, nothing counts
    s.nearest_bystander_m = 0.2 + std::abs(i - 50) * 0.05;  // nearest at i = 50: 0.2
    if (i < 10) s.nearest_bystander_m = 0.01;               // someone at their start beside the person: not counted
    if (i >= 60) s.nearest_look_alike_m = 3.0 - 0.01 * i;   // nearest at the end: 2.01
    m.record(s);
  }
  EXPECT_DOUBLE_EQ(m.closestBystanderM(), 0.2);
  EXPECT_NEAR(m.closestLookAlikeM(), 2.01, 1e-12);
}

TEST(FollowedAllTheWay, GivenLossOf2_9sThenFollowedAndOf3_1sThenNot) {
  const SimMetrics short_loss = runWithLoss(2.9);
  EXPECT_NEAR(short_loss.longestLossS(), 2.9, 1e-9);
  EXPECT_TRUE(short_loss.followedAllTheWay()) << short_loss.followFailureReason();
  EXPECT_TRUE(short_loss.success());

  const SimMetrics long_loss = runWithLoss(3.1);
  EXPECT_NEAR(long_loss.longestLossS(), 3.1, 1e-9);
  EXPECT_FALSE(long_loss.followedAllTheWay());
  EXPECT_NE(long_loss.followFailureReason().find("sight lost for 3.10 s from t = 5.0 s (occluded)"), std::string::npos)
      << long_loss.followFailureReason();
  EXPECT_TRUE(long_loss.success()) << "our lenient verdict: the person was re-acquired";
}

TEST(FollowedAllTheWay, GivenLossRunningToTheEndThenItsLengthCounts) {
  SimMetrics m(verdictSpec());
  for (int i = 0; i < 400; ++i) m.record(verdictSample(i, i < 200 ? Sight::kVisible : Sight::kOutOfImage));
  // Hidden from t = 4.0 s to the last sample at 7.98 s.
  EXPECT_FALSE(m.followedAllTheWay());
  EXPECT_NE(m.followFailureReason().find("3.98 s"), std::string::npos) << m.followFailureReason();
}

TEST(FollowedAllTheWay, GivenDistanceExcursionThenDefaultLimitIsFactorTimesTrackingDistance) {
  // Default limit: final_distance_factor 2 x tracking distance 2.5 m = 5 m. 6 m away for 2.9 s, then 3.1 s.
  for (const auto& [far_s, followed] : {std::pair{2.9, true}, std::pair{3.1, false}}) {
    SimMetrics m(verdictSpec());
    EXPECT_DOUBLE_EQ(m.maxDistanceM(), 5.0);
    const int end = 100 + static_cast<int>(std::lround(far_s / kDtS));
    for (int i = 0; i < 600; ++i) m.record(verdictSample(i, Sight::kVisible, i >= 100 && i < end ? 6.0 : 2.5));
    EXPECT_NEAR(m.longestExcursionS(), far_s, 1e-9);
    EXPECT_EQ(m.followedAllTheWay(), followed) << m.followFailureReason();
    EXPECT_TRUE(m.success()) << "ours looks at the final distance only";
    if (!followed) {
      EXPECT_NE(m.followFailureReason().find("farther than 5.0 m for 3.10 s from t = 2.0 s"), std::string::npos);
    }
  }
}

TEST(FollowedAllTheWay, GivenExplicitMaxDistanceThenItApplies) {
  ScenarioSpec spec = verdictSpec();
  spec.success.max_distance_m = 7.0;
  SimMetrics m(spec);
  for (int i = 0; i < 600; ++i) m.record(verdictSample(i, Sight::kVisible, 6.0));  // 6 m < 7 m all along
  EXPECT_DOUBLE_EQ(m.maxDistanceM(), 7.0);
  EXPECT_DOUBLE_EQ(m.longestExcursionS(), 0.0);
  EXPECT_TRUE(m.followedAllTheWay());
  EXPECT_FALSE(m.success()) << "final distance 6 m > 5 m";
}

TEST(FollowedAllTheWay, GivenCollisionThenNot) {
  SimMetrics m(verdictSpec());
  MetricsSample s = verdictSample(0, Sight::kVisible);
  s.clearance_m = 0.1;  // < the drone's 0.25 m radius
  m.record(s);
  EXPECT_FALSE(m.followedAllTheWay());
  EXPECT_NE(m.followFailureReason().find("1 collision(s)"), std::string::npos);
}

TEST(IdentityMetrics, GivenSwitchesAcrossNoDetectionGapsThenCountsChangesOfPersonOnly) {
  SimMetrics m(verdictSpec());
  // 0, -1, 0: no switch. 0 -> 2: one. 2, -1, -1, 1: one. 1 -> 0: one.
  for (int id : {0, 0, -1, 0, 0, 2, 2, -1, -1, 1, 1, 0, -1}) m.recordFollowed(0.0, id);
  EXPECT_EQ(m.identitySwitches(), 3);
  EXPECT_EQ(m.followedFrames(), 13);
}

TEST(IdentityMetrics, GivenNoPersonEverMatchedThenNoSwitch) {
  SimMetrics m(verdictSpec());
  for (int id : {-1, -1, 3, -1, 3}) m.recordFollowed(0.0, id);
  EXPECT_EQ(m.identitySwitches(), 0);
}

TEST(IdentityMetrics, GivenFollowedBystanderThenTimeOnWrongPersonIsItsTrackedTime) {
  SimMetrics m(verdictSpec());
  // Detection frames at 10 Hz (every 5th metrics sample): the target for 1 s, bystander 1 for 0.5 s,
  // no detection for 0.3 s (not wrong: following nobody), bystander 2 for 0.2 s, then the target.
  auto idAt = [](int frame) {
    if (frame < 10) return 0;
    if (frame < 15) return 1;
    if (frame < 18) return -1;
    if (frame < 20) return 2;
    return 0;
  };
  for (int i = 0; i < 150; ++i) {
    if (i % 5 == 0) m.recordFollowed(kDtS * i, idAt(i / 5));
    m.record(verdictSample(i, Sight::kVisible));
  }
  EXPECT_NEAR(m.timeOnWrongPersonS(), 0.7, 1e-9);
  EXPECT_EQ(m.identitySwitches(), 3);  // 0 -> 1 -> (gap) 2 -> 0
}

TEST(PersonSpeed, GivenSpeedsThenTopIsTheMaxAndMeanCoversTheWalkPausesIncluded) {
  SimMetrics m(verdictSpec());
  // Standing (not walking) at 0 for 1 s, walking: 1 s at 2 m/s, 1 s paused, 1 s at 4 m/s; then standing.
  for (int i = 0; i < 250; ++i) {
    MetricsSample s = verdictSample(i, Sight::kVisible);
    s.person_walking = i >= 50 && i < 200;
    s.person_speed_mps = i < 50 ? 0.0 : i < 100 ? 2.0 : i < 150 ? 0.0 : i < 200 ? 4.0 : 0.0;
    m.record(s);
  }
  EXPECT_DOUBLE_EQ(m.personTopSpeedMps(), 4.0);
  EXPECT_NEAR(m.personMeanSpeedMps(), 2.0, 1e-9);  // 6 m in 3 s
}

/// sharp_turn.yaml with extra lines under `success:`.
rt::Expected<ScenarioSpec> sharpTurnWithSuccess(const std::string& extra) {
  std::ifstream in(AEROTRACK_SOURCE_DIR "/config/scenarios/sharp_turn.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const std::string anchor = "  final_distance_factor: 2.0\n";
  yaml.replace(yaml.find(anchor), anchor.size(), anchor + extra);
  return parseScenarioSpec(yaml, "s.yaml");
}

TEST(FollowedAllTheWayKeys, GivenAbsentThenDefaultsAndGivenPresentThenRead) {
  const auto defaults = sharpTurnWithSuccess("");
  ASSERT_TRUE(defaults) << defaults.error().message;
  EXPECT_DOUBLE_EQ(defaults->success.max_loss_s, 3.0);
  EXPECT_DOUBLE_EQ(defaults->success.max_distance_m, 0.0);  // 0: factor x tracking distance
  EXPECT_DOUBLE_EQ(SimMetrics(*defaults).maxDistanceM(), 5.0);
  const auto set = sharpTurnWithSuccess("  max_loss_s: 2.0\n  max_distance_m: 6.5\n");
  ASSERT_TRUE(set) << set.error().message;
  EXPECT_DOUBLE_EQ(set->success.max_loss_s, 2.0);
  EXPECT_DOUBLE_EQ(SimMetrics(*set).maxDistanceM(), 6.5);
}

TEST(FollowedAllTheWayKeys, GivenOutOfRangeThenOneLineNamingFileLineAndKey) {
  for (const auto& [extra, expected] :
       {std::pair<std::string, std::string>{"  max_loss_s: 0\n", "success.max_loss_s: 0 is out of range"},
        {"  max_loss_s: -1\n", "success.max_loss_s: -1 is out of range"},
        {"  max_distance_m: 0.1\n", "success.max_distance_m: 0.1 is out of range"},
        {"  max_distance_m: 2.0\n", "success.max_distance_m: must be greater than tracking_distance_m (2.5 m)"}}) {
    const auto spec = sharpTurnWithSuccess(extra);
    ASSERT_FALSE(spec) << extra;
    EXPECT_NE(spec.error().message.find("s.yaml:"), std::string::npos) << spec.error().message;
    EXPECT_NE(spec.error().message.find(expected), std::string::npos) << spec.error().message;
  }
}

}  // namespace
}  // namespace aerotrack::hal::sim
