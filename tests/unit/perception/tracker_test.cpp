// Unit tests of the lock-on (person_tracker.hpp) and its appearance cue: a bystander does not steal
// the track, the track is lost after the configured time, and after a loss only the person whose
// clothing matches is re-acquired.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "aerotrack/perception/appearance.hpp"
#include "aerotrack/perception/person_tracker.hpp"

namespace aerotrack::perception {
namespace {

using hal::CocoKeypoint;
using hal::index;

constexpr rt::TimeNs kFrameNs = rt::kNsPerSecond / 30;

/// A histogram with all mass in one bin (a shirt of one colour).
Appearance shirt(int bin) {
  Appearance a;
  a.histogram[static_cast<std::size_t>(bin)] = 1.0F;
  a.valid = true;
  return a;
}

TrackCandidate person(double u_px, double torso_px, const Appearance& appearance, double score = 0.8) {
  TrackCandidate c;
  c.torso.u_px = u_px;
  c.torso.v_px = 240.0;
  c.torso.torso_px = torso_px;
  c.torso.reliable = true;
  c.appearance = appearance;
  c.score = score;
  return c;
}

TEST(PersonTracker, GivenALockedTarget_WhenABystanderWalksPastCloserAndMoreConfident_ThenTheTargetIsKept) {
  PersonTracker tracker(TrackerParams{});
  const Appearance red = shirt(0), blue = shirt(20);
  // Target walks right at 60 px/s; a bystander in blue walks left through the same place.
  for (int i = 0; i < 90; ++i) {
    const rt::TimeNs t = i * kFrameNs;
    const double target_u = 200.0 + 2.0 * i;
    const double bystander_u = 500.0 - 3.0 * i;
    const std::array<TrackCandidate, 2> candidates = {person(bystander_u, 90.0, blue, 0.95),
                                                      person(target_u, 80.0, red, 0.7)};
    if (i == 0) {
      // The target alone in the first frame is the one locked on.
      ASSERT_TRUE(tracker.update(t, std::span(candidates).subspan(1)).has_value());
      continue;
    }
    const auto chosen = tracker.update(t, candidates);
    ASSERT_TRUE(chosen.has_value()) << i;
    EXPECT_EQ(*chosen, 1U) << "frame " << i;
  }
}

TEST(PersonTracker, GivenNoLock_WhenSeveralPeopleAreSeen_ThenTheMostConfidentLargestIsAcquired) {
  PersonTracker tracker(TrackerParams{});
  const std::array<TrackCandidate, 3> candidates = {
      person(100.0, 40.0, shirt(1), 0.6), person(300.0, 90.0, shirt(2), 0.8), person(500.0, 60.0, shirt(3), 0.8)};
  const auto chosen = tracker.update(0, candidates);
  ASSERT_TRUE(chosen.has_value());
  EXPECT_EQ(*chosen, 1U);
  EXPECT_TRUE(tracker.locked(0));
}

TEST(PersonTracker, GivenTheTargetDisappears_WhenLostAfterSecondsPass_ThenTheTrackIsLost) {
  TrackerParams params;
  params.lost_after_s = 0.5;
  PersonTracker tracker(params);
  const std::array<TrackCandidate, 1> target = {person(300.0, 80.0, shirt(0))};
  ASSERT_TRUE(tracker.update(0, target).has_value());
  EXPECT_TRUE(tracker.update(rt::secondsToNs(0.3), std::span<const TrackCandidate>{}) == std::nullopt);
  EXPECT_TRUE(tracker.locked(rt::secondsToNs(0.5)));
  EXPECT_FALSE(tracker.locked(rt::secondsToNs(0.51)));
}

TEST(PersonTracker, GivenALostTarget_WhenOnlyAStrangerIsSeen_ThenNothingIsAcquiredUntilTheTargetReturns) {
  PersonTracker tracker(TrackerParams{});
  const Appearance red = shirt(0), blue = shirt(20);
  const std::array<TrackCandidate, 1> target = {person(300.0, 80.0, red)};
  ASSERT_TRUE(tracker.update(0, target).has_value());
  const std::array<TrackCandidate, 1> stranger = {person(320.0, 80.0, blue)};
  EXPECT_FALSE(tracker.update(rt::secondsToNs(2.0), stranger).has_value());
  const std::array<TrackCandidate, 2> both = {person(100.0, 60.0, blue), person(500.0, 60.0, red)};
  const auto chosen = tracker.update(rt::secondsToNs(3.0), both);
  ASSERT_TRUE(chosen.has_value());
  EXPECT_EQ(*chosen, 1U);
}

TEST(PersonTracker, GivenATargetThatJumpsAcrossTheImage_WhenLocked_ThenOnlyItsAppearanceCanClaimIt) {
  PersonTracker tracker(TrackerParams{});
  const std::array<TrackCandidate, 1> here = {person(200.0, 50.0, shirt(0))};
  ASSERT_TRUE(tracker.update(0, here).has_value());
  // 400 px in one frame is 8 torso lengths, outside the motion gate: someone in another shirt there
  // is not the target ...
  const std::array<TrackCandidate, 1> other = {person(600.0, 50.0, shirt(20))};
  EXPECT_FALSE(tracker.update(kFrameNs, other).has_value());
  // ... but the target's own look is re-identified at once (a fast gimbal turn moves the image so;
  // waiting for the track to time out would drop a visible target for lost_after_s).
  const std::array<TrackCandidate, 1> same = {person(600.0, 50.0, shirt(0))};
  EXPECT_TRUE(tracker.update(2 * kFrameNs, same).has_value());
}

TEST(PersonTracker, GivenNoReferenceAppearance_WhenNothingPassesTheGate_ThenNobodyIsTakenUntilTheTrackIsLost) {
  PersonTracker tracker(TrackerParams{});
  const std::array<TrackCandidate, 1> here = {person(200.0, 50.0, Appearance{})};
  ASSERT_TRUE(tracker.update(0, here).has_value());
  const std::array<TrackCandidate, 1> there = {person(600.0, 50.0, Appearance{})};
  EXPECT_FALSE(tracker.update(kFrameNs, there).has_value());
  const auto after_loss = static_cast<rt::TimeNs>(1.5 * static_cast<double>(rt::kNsPerSecond));
  EXPECT_TRUE(tracker.update(after_loss, there).has_value());
}

TEST(PersonTracker, GivenAnExternalPrediction_WhenTheImageMovedByGimbalRotation_ThenThePredictionGates) {
  PersonTracker tracker(TrackerParams{});
  const std::array<TrackCandidate, 1> here = {person(200.0, 50.0, shirt(0))};
  ASSERT_TRUE(tracker.update(0, here).has_value());
  // The gimbal turned: the estimator projects the person to u = 450; the detector finds them there.
  const std::array<TrackCandidate, 1> there = {person(455.0, 50.0, shirt(0))};
  const auto chosen = tracker.update(kFrameNs, there, ImagePrediction{450.0, 240.0, 50.0});
  ASSERT_TRUE(chosen.has_value());
}

TEST(Appearance, GivenTwoShirtColours_WhenMeasuredFromImages_ThenSameIsNearAndDifferentIsFar) {
  const auto torso_keypoints = [] {
    std::array<hal::Keypoint2D, hal::kNumKeypoints> k{};
    k[index(CocoKeypoint::kLeftShoulder)] = {60.0, 20.0, 0.9};
    k[index(CocoKeypoint::kRightShoulder)] = {20.0, 20.0, 0.9};
    k[index(CocoKeypoint::kLeftHip)] = {55.0, 80.0, 0.9};
    k[index(CocoKeypoint::kRightHip)] = {25.0, 80.0, 0.9};
    return k;
  }();
  cv::Mat red(100, 80, CV_8UC3, cv::Scalar(30, 30, 200));
  cv::Mat red_noisy = red.clone();
  cv::Mat noise(red.size(), CV_8UC3);
  cv::randu(noise, 0, 20);
  red_noisy += noise;
  cv::Mat blue(100, 80, CV_8UC3, cv::Scalar(200, 60, 30));
  const Appearance a = torsoAppearance(red, torso_keypoints);
  const Appearance b = torsoAppearance(red_noisy, torso_keypoints);
  const Appearance c = torsoAppearance(blue, torso_keypoints);
  ASSERT_TRUE(a.valid && b.valid && c.valid);
  EXPECT_LT(appearanceDistance(a, b), 0.2);
  EXPECT_GT(appearanceDistance(a, c), 0.9);
}

TEST(Appearance, GivenATorsoOutsideTheImage_WhenMeasured_ThenItIsInvalid) {
  std::array<hal::Keypoint2D, hal::kNumKeypoints> k{};
  for (auto& p : k) p = {500.0, 500.0, 0.9};
  cv::Mat img(100, 80, CV_8UC3, cv::Scalar(0, 0, 0));
  EXPECT_FALSE(torsoAppearance(img, k).valid);
}

}  // namespace
}  // namespace aerotrack::perception
