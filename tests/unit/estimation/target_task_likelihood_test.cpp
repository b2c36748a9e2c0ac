// The association's likelihood cost (assignment_cost: likelihood, issue 22 item 2): a track of wide covariance does
// not take the followed person's measurement for fitting them at a smaller d2. Against ground truth: the person
// stands 5 m ahead of a hovering drone, measured every frame with the network's scatter (alternately 0.3 m nearer
// and farther along the line of sight, as the regression's single-frame error in image mode); a look-alike in the
// same colour, walking past 1.2 m beside them, is detected beside them for 3 frames -- a young bystander track,
// started at the regression's noise and with no velocity yet -- and then missed (hidden or scored low) while their
// track coasts and widens. As traced in the image-mode crowd (seed 85): the person's measurement at d2 0.94 to a
// young track 1.3 m away against 1.16 to the followed track was given to the young track.
#include <gtest/gtest.h>

#include "aerotrack/estimation/target_task.hpp"
#include "support/require.hpp"
#include "target_task_test_util.hpp"

namespace aerotrack::estimation {
namespace likelihood_test {
namespace {

constexpr double kRateHz = test::kFrameRateHz;
constexpr double kPersonXM = 5.0;
constexpr double kBesideYM = 1.2;  ///< where the look-alike is seen, beside the person
constexpr double kScatterM = 0.3;  ///< the network's single-frame error along the line of sight
constexpr int kLockFrames = 30;    ///< the person alone for a second: the track and their colour
constexpr int kBesideFrames = 3;   ///< both detected: the look-alike's young track
constexpr int kCoastFrames = 24;   ///< then the person alone again, the young track coasting (0.8 s)
constexpr int kColourBin = 3;

struct Scene {
  int person_given = 0;  ///< frames after the look-alike was missed whose followed person was the person
  int frames = 0;
  TargetEstimate estimate;
};

Scene run(TargetTaskParams::AssignmentCost cost) {
  TargetTaskParams params;
  params.localization = test::pinholeLocalization();
  // The network's single-frame scatter, as fitted on rendered frames (config/localization_image.yaml: 0.27 m at
  // 5 m): the followed track's gate is as wide as in image mode.
  params.localization.noise_std_m = 0.01;
  params.localization.noise_std_per_m = 0.05;
  params.assignment_cost = cost;
  rt::LatestSlot<hal::DetectionFrame> followed;
  test::TaskRig rig(params);
  auto& [detections, odometry, gimbal, out, task] = rig;
  task.publishFollowedTo(followed);
  Scene scene;
  for (int i = 0; i < kLockFrames + kBesideFrames + kCoastFrames; ++i) {
    const rt::TimeNs t_ns = rt::secondsToNs(i / kRateHz);
    test::pushHover(odometry, gimbal, t_ns);
    const double scatter_m = i % 2 == 0 ? kScatterM : -kScatterM;
    const bool beside = i >= kLockFrames && i < kLockFrames + kBesideFrames;
    const bool coasting = i >= kLockFrames + kBesideFrames;
    hal::DetectionFrame frame = test::emptyFrame(i, t_ns);
    frame.person_count = beside ? 2 : 1;
    test::drawPersonInColour(frame.persons[0], kPersonXM + scatter_m, 0.0, kColourBin);
    if (beside) test::drawPersonInColour(frame.persons[1], kPersonXM - scatter_m, kBesideYM, kColourBin);
    frame.target_index = 0;
    detections.try_push(frame);
    task.step(t_ns + 1);
    if (!coasting) continue;
    ++scene.frames;
    const auto f = followed.read();
    if (f && f->sequence == frame.sequence && f->target_index == 0) ++scene.person_given;
  }
  scene.estimate = aerotrack::test::require(out.read(), "an estimate");
  return scene;
}

TEST(TargetTaskLikelihood,
     GivenAYoungTrackWideningBesideThePerson_ThenTheLikelihoodKeepsTheirMeasurementsOnTheirTrack) {
  const Scene by_fraction = run(TargetTaskParams::AssignmentCost::kGateFraction);
  const Scene by_likelihood = run(TargetTaskParams::AssignmentCost::kLikelihood);
  ASSERT_EQ(by_fraction.frames, kCoastFrames);
  // By d2 alone the widening young track fits the person's scattered measurements as well, and takes some of them.
  EXPECT_LT(by_fraction.person_given, by_fraction.frames);
  // Charged for its width, never: every one goes to the followed track.
  EXPECT_EQ(by_likelihood.person_given, by_likelihood.frames);
  ASSERT_TRUE(by_likelihood.estimate.initialised && !by_likelihood.estimate.lost);
  EXPECT_NEAR(by_likelihood.estimate.p_WT_m.x(), kPersonXM, 0.2);
  EXPECT_NEAR(by_likelihood.estimate.p_WT_m.y(), 0.0, 0.1);
}

TEST(TargetTaskLikelihood, GivenThePersonAlone_ThenBothCostsGiveEveryFrame) {
  // With nobody else, the cost's form changes nothing: a lone person inside the gate is always taken (the miss
  // cost lies above every pair's, whatever the sign of ln|S|).
  TargetTaskParams params;
  params.localization = test::pinholeLocalization();
  params.assignment_cost = TargetTaskParams::AssignmentCost::kLikelihood;
  rt::LatestSlot<hal::DetectionFrame> followed;
  test::TaskRig rig(params);
  auto& [detections, odometry, gimbal, out, task] = rig;
  task.publishFollowedTo(followed);
  int given = 0;
  constexpr int kFrames = 60;
  for (int i = 0; i < kFrames; ++i) {
    const rt::TimeNs t_ns = rt::secondsToNs(i / kRateHz);
    test::pushHover(odometry, gimbal, t_ns);
    hal::DetectionFrame frame = test::emptyFrame(i, t_ns);
    frame.person_count = 1;
    test::drawPersonInColour(frame.persons[0], kPersonXM, 0.0, kColourBin);
    frame.target_index = 0;
    detections.try_push(frame);
    task.step(t_ns + 1);
    const auto f = followed.read();
    if (f && f->sequence == frame.sequence && f->target_index == 0) ++given;
  }
  EXPECT_EQ(given, kFrames);
}

}  // namespace
}  // namespace likelihood_test
}  // namespace aerotrack::estimation
