// A bystander track whose colour is learnt from a few frames does not lose the person's look-alike to the followed
// track on colour (young_look_samples, issue 22 item 2). Against ground truth: the person stands 5 m ahead of a
// hovering drone; a look-alike walks up beside them at the same distance, seen from the side beside the person for
// 3 frames (both detected: the look-alike gets a track whose colour is their side view), then the network returns
// only the look-alike, now facing the camera (the person's colour), for 6 frames, and both again after. The
// measurements scatter as the network's do, so the followed track's gate is as wide as in image mode. As traced in the
// image-mode crowd (seed 80): the look-alike 0.05 from the followed person's colour and 0.23 from their own young
// track's, at d2 11.65 to the followed track and 0.84 to their own, was given to the followed track. No depth camera:
// the regression ranges both right.
#include <gtest/gtest.h>

#include "aerotrack/estimation/target_task.hpp"
#include "support/require.hpp"
#include "target_task_test_util.hpp"

namespace aerotrack::estimation {
namespace young_look_test {
namespace {

constexpr double kRateHz = test::kFrameRateHz;
constexpr double kPersonXM = 5.0;
constexpr double kFirstSeenYM = 1.0;  ///< where the look-alike is first detected, beside the person
constexpr double kSpeedMps = 0.6;     ///< the look-alike's walk towards the person (-y)
constexpr int kBesideFrames = 3;      ///< both detected: the look-alike's side view
constexpr int kMissedFrames = 6;      ///< then only the look-alike, facing the camera: 9 colours on their track
constexpr int kAfterFrames = 15;      ///< both again
constexpr int kColourBin = 3;
constexpr double kNetworkNoiseStdM = 0.01;
constexpr double kNetworkNoiseStdPerM = 0.05;
constexpr int kOtherBin = 5;

double lookAlikeY(double t_s) {
  return kFirstSeenYM - kSpeedMps * t_s;
}

/// The look-alike seen from the side: most of the torso in the person's colour and a fifth in another; or, dressed
/// otherwise (side_bin another bin), most in that bin and a fifth in the person's.
void drawFromTheSide(hal::PersonDetection& person, double x_m, double y_m, int side_bin) {
  test::drawPersonInColour(person, x_m, y_m, kColourBin);
  if (side_bin == kColourBin) {  // the person's colour, a fifth in another bin
    person.appearance[kColourBin] = 0.8F;
    person.appearance[kOtherBin] = 0.2F;
  } else {
    person.appearance[kColourBin] = 0.2F;
    person.appearance[side_bin] = 0.8F;
  }
}

struct Scene {
  int look_alike_given = 0;  ///< frames with the person missed whose followed person was the look-alike
  int missed_frames = 0;
  int person_given_after = 0;  ///< frames after the miss whose followed person was the person
  int frames_after = 0;
  TargetEstimate estimate;
};

Scene run(int young_look_samples, int side_bin = kColourBin) {
  TargetTaskParams params;
  params.localization = test::pinholeLocalization();
  // The network's single-frame scatter, as fitted on rendered frames (config/localization_image.yaml: 0.27 m at
  // 5 m): the followed track's gate is as wide as in image mode.
  params.localization.noise_std_m = kNetworkNoiseStdM;
  params.localization.noise_std_per_m = kNetworkNoiseStdPerM;
  params.young_look_samples = young_look_samples;
  rt::LatestSlot<hal::DetectionFrame> followed;
  test::TaskRig rig(params);
  auto& [detections, odometry, gimbal, out, task] = rig;
  task.publishFollowedTo(followed);
  Scene scene;
  const int lock_frames = static_cast<int>(kRateHz);  // the person alone for a second: the track and their colour
  const int frames = lock_frames + kBesideFrames + kMissedFrames + kAfterFrames;
  for (int i = 0; i <= frames; ++i) {
    const double t_s = i / kRateHz;
    const rt::TimeNs t_ns = rt::secondsToNs(t_s);
    test::pushHover(odometry, gimbal, t_ns);
    const int since = i - lock_frames;  // frames since the look-alike was first seen
    const double y_m = lookAlikeY(since / kRateHz);
    const bool missed = since >= kBesideFrames && since < kBesideFrames + kMissedFrames;
    const bool after = since >= kBesideFrames + kMissedFrames;
    hal::DetectionFrame frame = test::emptyFrame(i, t_ns);
    if (since < 0) {
      frame.person_count = 1;
      test::drawPersonInColour(frame.persons[0], kPersonXM, 0.0, kColourBin);
    } else if (missed) {
      frame.person_count = 1;
      test::drawPersonInColour(frame.persons[0], kPersonXM, y_m, kColourBin);
    } else {
      frame.person_count = 2;
      test::drawPersonInColour(frame.persons[0], kPersonXM, 0.0, kColourBin);
      drawFromTheSide(frame.persons[1], kPersonXM, y_m, side_bin);
    }
    frame.target_index = 0;
    detections.try_push(frame);
    task.step(t_ns + 1);
    scene.missed_frames += missed ? 1 : 0;
    scene.frames_after += after ? 1 : 0;
    const auto f = followed.read();
    if (!f || f->sequence != frame.sequence || f->target_index < 0) continue;
    if (missed) ++scene.look_alike_given;
    if (after && f->target_index == 0) ++scene.person_given_after;
  }
  scene.estimate = aerotrack::test::require(out.read(), "an estimate");
  return scene;
}

TEST(TargetTaskYoungLook, GivenALookAlikeOnAYoungTrackBesideAMissedPerson_ThenTheirTrackKeepsThem) {
  const Scene by_colour = run(0);
  const Scene by_place = run(10);
  EXPECT_EQ(by_place.missed_frames, kMissedFrames);
  // Judged by the young track's colour, the followed track takes the look-alike once its coasting gate holds them.
  EXPECT_GT(by_colour.look_alike_given, 0) << "of " << by_colour.missed_frames;
  // Judged by where they are, never: they fit their own track far better.
  EXPECT_EQ(by_place.look_alike_given, 0);
  // The person is taken again in every frame after, and the estimate stays on them.
  EXPECT_EQ(by_place.person_given_after, by_place.frames_after);
  ASSERT_TRUE(by_place.estimate.initialised && !by_place.estimate.lost);
  EXPECT_NEAR(by_place.estimate.p_WT_m.x(), kPersonXM, 0.1);
  EXPECT_NEAR(by_place.estimate.p_WT_m.y(), 0.0, 0.1);
}

TEST(TargetTaskYoungLook, GivenSomeoneDressedOtherwiseOnAYoungTrack_ThenTheirColourStillCounts) {
  // Seen from the side in another colour, their young track's colour lies outside the person's colour gate: the
  // rule leaves it alone, and the frames go as without it.
  const Scene by_colour = run(0, kOtherBin);
  const Scene by_place = run(10, kOtherBin);
  EXPECT_GT(by_colour.look_alike_given, 0);  // (the frames where the rule, had it applied, would have kept them)
  EXPECT_EQ(by_place.look_alike_given, by_colour.look_alike_given);
  EXPECT_EQ(by_place.person_given_after, by_colour.person_given_after);
}

}  // namespace
}  // namespace young_look_test
}  // namespace aerotrack::estimation
