// Someone else within reach of the followed person (ambiguity_radius_m, issue 22 item 2). Against ground
// truth: the followed person walks left 5 m ahead of a hovering drone; a look-alike in the same clothes walks
// right 0.3 m behind them, so that they pass each other at 2 s. While they are more than a body apart both
// are detected; nearer, the network reports one person made of both (their keypoints between the two
// bodies), whom the truth's matcher calls the person or the look-alike in turn -- crowd seeds 2, 17 and 18
// in image mode. Without the reach the track takes such blends when they fit it better than the
// look-alike's own track; with it, the track takes nobody while someone else is that near, then the person
// again.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "aerotrack/estimation/target_task.hpp"
#include "support/require.hpp"
#include "target_task_test_util.hpp"

namespace aerotrack::estimation {
namespace ambiguity_test {
namespace {

constexpr double kRateHz = test::kFrameRateHz;
constexpr int kColour = 3;

double personY(double t_s) {
  return -1.0 + 0.5 * t_s;
}
double lookAlikeY(double t_s) {
  return 1.0 - 0.5 * t_s;
}

void drawPerson(hal::PersonDetection& person, double x_m, double y_m) {
  test::drawPersonInColour(person, x_m, y_m, kColour);
}

struct Scene {
  int look_alike_given = 0;    ///< frames whose followed person was the look-alike
  int given_in_overlap = 0;    ///< frames of the overlap (one person reported) given to the track
  int given_near = 0;          ///< frames given to the track while the two stood within 0.55 m (the reach less noise)
  int person_given_after = 0;  ///< frames from 2.6 s whose followed person was the person
  int nobody_given = 0;
  TargetEstimate estimate;
  TargetTaskStats stats;
};

/// `lone_look_alike`: in the overlap the network reports the look-alike alone (the crop held them), not a blend.
Scene run(double ambiguity_radius_m, bool lone_look_alike = false) {
  TargetTaskParams params;
  params.localization = test::pinholeLocalization();
  params.ambiguity_radius_m = ambiguity_radius_m;
  rt::LatestSlot<hal::DetectionFrame> followed;
  test::TaskRig rig(params);
  auto& [detections, odometry, gimbal, out, task] = rig;
  task.publishFollowedTo(followed);
  Scene scene;
  std::mt19937 rng(7);
  std::normal_distribution<double> range_noise_m(0.0, 0.1);  // the regression's, 2 % of 5 m
  const int frames = static_cast<int>(3.5 * kRateHz);
  for (int i = 0; i <= frames; ++i) {
    const double t_s = i / kRateHz;
    const rt::TimeNs t_ns = rt::secondsToNs(t_s);
    test::pushHover(odometry, gimbal, t_ns);
    hal::DetectionFrame frame = test::emptyFrame(i, t_ns);
    // Who each reported person is: 0 the person, 1 the look-alike.
    std::array<int, 2> truth{0, 1};
    const bool overlap = std::abs(personY(t_s) - lookAlikeY(t_s)) < 0.5;
    if (!overlap) {
      frame.person_count = 2;
      drawPerson(frame.persons[0], 5.0 + range_noise_m(rng), personY(t_s));
      drawPerson(frame.persons[1], 5.3 + range_noise_m(rng), lookAlikeY(t_s));
    } else {
      frame.person_count = 1;
      truth[0] = lone_look_alike || i % 2 == 1 ? 1 : 0;
      const double blend = lone_look_alike ? 1.0 : 0.5;
      drawPerson(frame.persons[0], 5.0 + 0.3 * blend + range_noise_m(rng),
                 (1.0 - blend) * personY(t_s) + blend * lookAlikeY(t_s));
    }
    frame.target_index = 0;
    detections.try_push(frame);
    task.step(t_ns + 1);
    const auto f = followed.read();
    if (!f || f->sequence != frame.sequence) continue;
    if (f->target_index < 0) {
      ++scene.nobody_given;
      continue;
    }
    if (overlap) ++scene.given_in_overlap;
    if (std::hypot(personY(t_s) - lookAlikeY(t_s), 0.3) < 0.55) ++scene.given_near;
    const int who = truth[static_cast<std::size_t>(f->target_index)];
    if (who == 1) ++scene.look_alike_given;
    if (who == 0 && t_s >= 2.6) ++scene.person_given_after;
  }
  scene.estimate = aerotrack::test::require(out.read(), "an estimate");
  scene.stats = task.stats();
  return scene;
}

TEST(TargetTaskAmbiguity, GivenALookAlikePassingThroughThePersonsPlace_WhenInReach_ThenTheTrackTakesNobody) {
  const Scene refused = run(0.7);
  const Scene taken = run(0.0);
  EXPECT_GT(taken.given_in_overlap, 0) << "without the reach, blends of the two are given to the track";
  EXPECT_EQ(refused.given_in_overlap, 0);
  EXPECT_EQ(refused.look_alike_given, 0);
  // Nobody given while the two stand within 0.55 m (the reach less the noise), and the refusals counted.
  EXPECT_EQ(refused.given_near, 0);
  EXPECT_GE(refused.stats.ambiguous, 6U);
  // After, the person is taken again in every frame, and the track is where they are.
  EXPECT_GE(refused.person_given_after, static_cast<int>((3.5 - 2.7) * kRateHz));
  ASSERT_TRUE(refused.estimate.initialised && !refused.estimate.lost);
  EXPECT_NEAR(refused.estimate.p_WT_m.y(), personY(3.5), 0.15);
  EXPECT_NEAR(refused.estimate.p_WT_m.x(), 5.0, 0.15);
}

TEST(TargetTaskAmbiguity, GivenOnlyTheLookAlikeInTheOverlap_WhenTheirOwnTrackIsLive_ThenTheTrackCoasts) {
  // The look-alike's own track (they were seen beside the person before) is live, and the lone detection lies
  // within reach of its prediction: nobody is given, the person's track coasts on their walk for a second
  // and takes them back after.
  const Scene refused = run(0.7, true);
  EXPECT_EQ(refused.look_alike_given, 0);
  EXPECT_EQ(refused.given_in_overlap, 0);
  EXPECT_GE(refused.person_given_after, static_cast<int>((3.5 - 2.7) * kRateHz));
  ASSERT_TRUE(refused.estimate.initialised && !refused.estimate.lost);
  EXPECT_NEAR(refused.estimate.p_WT_m.y(), personY(3.5), 0.15);
  EXPECT_NEAR(refused.estimate.p_WT_m.x(), 5.0, 0.15);
}

}  // namespace
}  // namespace ambiguity_test
}  // namespace aerotrack::estimation
