// The followed person's own scale, learnt from the depth camera (depth_range.scale_rate, issue 22 item 2). Against
// ground truth: the person, whose torso is 15 % longer than the regression's fit assumes, walks straight away from
// the hovering drone at 1 m/s, from 3 m to 7 m. The regression places them 15 % too near in every frame. The depth
// camera (rendered from their body) sees them for the first 2 s and then no more (they left its narrower view),
// as the closed loop's drone loses them from its body-fixed depth camera while the gimbal keeps them in the image
// (traced: image-mode crowd seed 1, 0.5 s unseen, the track 0.3-0.5 m short and slowed from 1.0 to 0.3 m/s). A
// bystander of the fit's own build stands aside: their track keeps the fit's scale.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "aerotrack/estimation/target_task.hpp"
#include "target_task_depth_util.hpp"
#include "target_task_test_util.hpp"

namespace aerotrack::estimation {
namespace {

constexpr double kBodyRadiusM = 0.25;
constexpr double kScale = 1.15;  // the person's torso against the fit's average
constexpr double kStartXM = 3.0;
constexpr double kSpeedMps = 1.0;
constexpr double kSeenS = 2.0;
constexpr double kDurationS = 4.0;

struct Walk {
  /// The bystander track's distance from the bystander at the end (infinite: none near them).
  double bystander_error_m = std::numeric_limits<double>::infinity();
  double error_seen_m = 0.0;   ///< The estimate's distance from the truth when the depth camera last saw them...
  double error_end_m = 0.0;    ///< ... and after 2 s unseen.
  double speed_end_mps = 0.0;  ///< The estimate's speed at the end.
  TargetTaskStats stats;
};

/// A bystander stands still 4 m ahead and 2 m aside, of the fit's own build (the regression places them right).
constexpr double kBystanderXM = 4.0;
constexpr double kBystanderYM = 2.0;

Walk walkAway(double scale_rate) {
  TargetTaskParams params = test::rangedParams(kBodyRadiusM, 0, false);
  params.depth_range.scale_rate = scale_rate;
  test::RangedRig ranged(params);
  Walk walk;
  const int frames = static_cast<int>(kDurationS * test::kFrameRateHz);
  for (int i = 0; i <= frames; ++i) {
    const double t_s = i / test::kFrameRateHz;
    const double x_m = kStartXM + kSpeedMps * t_s;
    // A torso kScale times the fit's, at x_m: the image of the fit's torso at x_m / kScale.
    const TargetEstimate e = test::stepRanged(ranged, i, rt::secondsToNs(t_s), t_s < kSeenS,
                                              {Eigen::Vector2d(x_m, 0.0), Eigen::Vector2d(kBystanderXM, kBystanderYM)},
                                              kBodyRadiusM, {{x_m / kScale, 0.0, 3}, {kBystanderXM, kBystanderYM, 7}});
    const double error_m = (e.p_WT_m.head<2>() - Eigen::Vector2d(x_m, 0.0)).norm();
    if (t_s < kSeenS) walk.error_seen_m = error_m;
    walk.error_end_m = error_m;
    walk.speed_end_mps = e.v_WT_mps.head<2>().norm();
    walk.bystander_error_m = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < e.other_count; ++k)
      walk.bystander_error_m = std::min(
          walk.bystander_error_m, (e.others[k].p_W_m.head<2>() - Eigen::Vector2d(kBystanderXM, kBystanderYM)).norm());
  }
  walk.stats = ranged.rig.task.stats();
  return walk;
}

TEST(TargetTaskScale,
     GivenAPersonLargerThanTheFitWalkingOutOfTheDepthCamerasView_ThenTheLearntScaleKeepsTheirDistance) {
  const Walk off = walkAway(0.0);
  const Walk on = walkAway(0.05);
  // Off: the depth camera's ranges, 15 % beyond the track, are too sharp for its gate, and the regression's form of
  // each is taken; the track carries the regression's error (13 % of the distance) and speed, ranged or not.
  EXPECT_EQ(off.stats.scale_samples, 0U);
  EXPECT_EQ(off.stats.range_scale, 1.0);
  EXPECT_GT(off.stats.depth_ranged, 30U);
  EXPECT_GT(off.error_seen_m, 0.5);
  EXPECT_GT(off.error_end_m, 0.7);
  EXPECT_NEAR(off.speed_end_mps, kSpeedMps / kScale, 0.05);
  // On: every ranged frame teaches the scale, which ends at the person's own; the depth camera's ranges then pass
  // the gate, and the 2 s without them keep the distance and the speed.
  EXPECT_GT(on.stats.scale_samples, 30U);
  EXPECT_NEAR(on.stats.range_scale, kScale, 0.01);
  EXPECT_LT(on.error_seen_m, 0.05);
  EXPECT_LT(on.error_end_m, 0.05);
  EXPECT_NEAR(on.speed_end_mps, kSpeedMps, 0.05);
  // The scale is the followed person's: the bystander's track keeps the fit's own, which places them right.
  EXPECT_LT(off.bystander_error_m, 0.05);
  EXPECT_LT(on.bystander_error_m, 0.05);
}

TEST(TargetTaskScale, GivenAFactorBeyondTheDepthRangesBound_ThenNothingIsLearnt) {
  // max_ratio 1.1: the depth camera's range, 15 % beyond the regression's, is not the person's (rangeByDepth), and
  // no frame is ranged or learnt from.
  TargetTaskParams params = test::rangedParams(kBodyRadiusM, 0, false);
  params.depth_range.scale_rate = 0.05;
  params.depth_range.max_ratio = 1.1;
  test::RangedRig ranged(params);
  for (int i = 0; i <= 30; ++i)
    test::stepRanged(ranged, i, rt::secondsToNs(i / test::kFrameRateHz), true, {Eigen::Vector2d(kStartXM, 0.0)},
                     kBodyRadiusM, {{kStartXM / kScale, 0.0, 3}});
  const TargetTask& task = ranged.rig.task;
  EXPECT_GT(task.stats().depth_disagreed, 20U);
  EXPECT_EQ(task.stats().scale_samples, 0U);
  EXPECT_EQ(task.stats().range_scale, 1.0);
}

}  // namespace
}  // namespace aerotrack::estimation
