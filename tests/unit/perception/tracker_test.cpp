// Unit tests of the lock-on (person_tracker.hpp) and its appearance cue: a bystander does not steal
// the track, the track is lost after the configured time, and after a loss only the person whose
// clothing matches is re-acquired.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <utility>

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

TEST(PersonTracker, GivenTheEstimatorJudgedAnotherPersonTheTarget_WhenReseated_ThenTheTrackGoesOnFromThem) {
  // Two people in the same shirt (the look-alike); the lock-on took the one at u = 200 walking right, the
  // estimator judged the one at u = 320 to be the person (issue 22, item 2).
  PersonTracker tracker(TrackerParams{});
  for (int i = 0; i < 10; ++i) {
    const std::array<TrackCandidate, 1> lookalike = {person(200.0 + 3.0 * i, 50.0, shirt(0))};
    ASSERT_TRUE(tracker.update(i * kFrameNs, lookalike).has_value());
  }
  TorsoFeatures judged;
  judged.u_px = 320.0;
  judged.v_px = 250.0;
  judged.torso_px = 55.0;
  tracker.reseat(9 * kFrameNs, judged);
  ASSERT_TRUE(tracker.locked(10 * kFrameNs));
  // The prediction is where the estimator's person was, not carried on with the look-alike's image velocity.
  const auto predicted = tracker.predict(12 * kFrameNs);
  ASSERT_TRUE(predicted.has_value());
  EXPECT_DOUBLE_EQ(predicted->u_px, 320.0);
  EXPECT_DOUBLE_EQ(predicted->v_px, 250.0);
  EXPECT_DOUBLE_EQ(predicted->torso_px, 55.0);
  // Both in the next frame: the lock-on now takes the estimator's person (both inside the gate; the nearer).
  const std::array<TrackCandidate, 2> both = {person(236.0, 50.0, shirt(0)), person(318.0, 55.0, shirt(0))};
  const auto chosen = tracker.update(12 * kFrameNs, both);
  ASSERT_TRUE(chosen.has_value());
  EXPECT_EQ(*chosen, 1U);
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
  const Appearance a = personAppearance(red, torso_keypoints);
  const Appearance b = personAppearance(red_noisy, torso_keypoints);
  const Appearance c = personAppearance(blue, torso_keypoints);
  ASSERT_TRUE(a.valid && b.valid && c.valid);
  EXPECT_LT(appearanceDistance(a, b), 0.2);
  EXPECT_GT(appearanceDistance(a, c), 0.9);
}

TEST(Appearance, GivenATorsoOutsideTheImage_WhenMeasured_ThenItIsInvalid) {
  std::array<hal::Keypoint2D, hal::kNumKeypoints> k{};
  for (auto& p : k) p = {500.0, 500.0, 0.9};
  cv::Mat img(100, 80, CV_8UC3, cv::Scalar(0, 0, 0));
  EXPECT_FALSE(personAppearance(img, k).valid);
}

/// A person standing upright in a 100 x 200 image: shoulders at v = 20, hips at 80, knees at 130 (knee
/// score given), a shirt above v = 80 and trousers below.
std::array<hal::Keypoint2D, hal::kNumKeypoints> standingKeypoints(double knee_score) {
  std::array<hal::Keypoint2D, hal::kNumKeypoints> k{};
  k[index(CocoKeypoint::kLeftShoulder)] = {60.0, 20.0, 0.9};
  k[index(CocoKeypoint::kRightShoulder)] = {20.0, 20.0, 0.9};
  k[index(CocoKeypoint::kLeftHip)] = {55.0, 80.0, 0.9};
  k[index(CocoKeypoint::kRightHip)] = {25.0, 80.0, 0.9};
  k[index(CocoKeypoint::kLeftKnee)] = {55.0, 130.0, knee_score};
  k[index(CocoKeypoint::kRightKnee)] = {25.0, 130.0, knee_score};
  return k;
}

cv::Mat dressed(const cv::Scalar& shirt_bgr, const cv::Scalar& trousers_bgr) {
  cv::Mat img(200, 80, CV_8UC3, shirt_bgr);
  img.rowRange(80, 200).setTo(trousers_bgr);
  return img;
}

TEST(Appearance, GivenBlackGreyAndWhiteShirts_WhenMeasured_ThenTheirBrightnessTellsThemApart) {
  // The first descriptor's one grey bin put every achromatic shirt at distance 0 (issue 22 item 2).
  const auto k = standingKeypoints(0.0);
  const cv::Scalar trousers(40, 40, 40);
  const Appearance black = personAppearance(dressed(cv::Scalar(15, 15, 15), trousers), k);
  const Appearance grey = personAppearance(dressed(cv::Scalar(110, 110, 110), trousers), k);
  const Appearance white = personAppearance(dressed(cv::Scalar(235, 235, 235), trousers), k);
  cv::Mat noisy = dressed(cv::Scalar(15, 15, 15), trousers);
  cv::Mat noise(noisy.size(), CV_8UC3);
  cv::randu(noise, 0, 20);
  noisy += noise;
  const Appearance black_noisy = personAppearance(noisy, k);
  ASSERT_TRUE(black.valid && grey.valid && white.valid && black_noisy.valid);
  EXPECT_LT(appearanceDistance(black, black_noisy), 0.3);
  EXPECT_GT(appearanceDistance(black, grey), 0.6);
  EXPECT_GT(appearanceDistance(grey, white), 0.6);
  EXPECT_GT(appearanceDistance(black, white), 0.9);
}

TEST(Appearance, GivenTheSameShirtOverOtherTrousers_WhenTheKneesAreSeen_ThenTheLegsTellThemApart) {
  const cv::Scalar shirt(30, 30, 200);
  const cv::Mat jeans = dressed(shirt, cv::Scalar(140, 80, 40));
  const cv::Mat khaki = dressed(shirt, cv::Scalar(120, 180, 200));
  const Appearance a = personAppearance(jeans, standingKeypoints(0.8));
  const Appearance b = personAppearance(khaki, standingKeypoints(0.8));
  ASSERT_TRUE(a.valid && b.valid);
  EXPECT_GT(hal::regionSum(a.histogram, hal::SignatureRegion::kLegs), 0.99);
  EXPECT_GT(appearanceDistance(a, b), 0.6);
  // Knees guessed (scores under kLegsMinKeypointScore): the legs are not measured, and the shirt alone
  // makes them the same person -- also against a signature that has legs (only common regions count).
  const Appearance a_no_legs = personAppearance(jeans, standingKeypoints(0.2));
  const Appearance b_no_legs = personAppearance(khaki, standingKeypoints(0.2));
  EXPECT_DOUBLE_EQ(hal::regionSum(a_no_legs.histogram, hal::SignatureRegion::kLegs), 0.0);
  EXPECT_LT(appearanceDistance(a_no_legs, b_no_legs), 1e-6);
  EXPECT_LT(appearanceDistance(a_no_legs, b), 1e-6);
}

TEST(Appearance, GivenRandomPixels_WhenMeasured_ThenTheHistogramMatchesOpenCvsHsvConversion) {
  // Independent reference: OpenCV's own BGR -> HSV (float images: hue in degrees, S and V in [0, 1])
  // voted through hal::colourVote, pixel by pixel.
  cv::Mat img(200, 80, CV_8UC3);
  cv::RNG rng(7);
  rng.fill(img, cv::RNG::UNIFORM, 0, 256);
  const auto k = standingKeypoints(0.9);
  const Appearance measured = personAppearance(img, k);
  ASSERT_TRUE(measured.valid);
  cv::Mat hsv;
  img.convertTo(hsv, CV_32FC3, 1.0 / 255.0);
  cv::cvtColor(hsv, hsv, cv::COLOR_BGR2HSV);
  const auto reference = [&](int u0, int u1, int v0, int v1, hal::SignatureRegion region) {
    std::array<double, hal::kSignatureRegionBins> counts{};
    for (int v = v0; v < v1; ++v)
      for (int u = u0; u < u1; ++u) {
        const cv::Vec3f p = hsv.at<cv::Vec3f>(v, u);
        const hal::ColourVote vote =
            hal::colourVote(static_cast<double>(p[0]), static_cast<double>(p[1]), static_cast<double>(p[2]));
        counts[vote.bin[0]] += vote.share[0];
        counts[vote.bin[1]] += vote.share[1];
      }
    const double n = static_cast<double>((u1 - u0) * (v1 - v0));
    for (std::size_t i = 0; i < counts.size(); ++i)
      EXPECT_NEAR(measured.histogram[hal::regionOffset(region) + i], counts[i] / n, 1e-5) << "bin " << i;
  };
  // The torso box: u in [20, 60] shrunk by 8 px each side, v in [20, 80] shrunk by 9 px.
  reference(28, 52, 29, 71, hal::SignatureRegion::kTorso);
}

TEST(Appearance, GivenAWalkerInStride_WhenTheLegsAreMeasured_ThenTheGroundBetweenThemIsNotCounted) {
  // The thighs as bands on grass: hips at (30, 80) and (50, 80), knees spread to (15, 130) and (65, 130). A
  // box between hips and knees would be mostly grass (measured in image mode: a walker's legs 0.3-0.6 from
  // their own reference); bands along the thighs see the trousers.
  std::array<hal::Keypoint2D, hal::kNumKeypoints> k = standingKeypoints(0.9);
  k[index(CocoKeypoint::kLeftHip)] = {50.0, 80.0, 0.9};
  k[index(CocoKeypoint::kRightHip)] = {30.0, 80.0, 0.9};
  k[index(CocoKeypoint::kLeftKnee)] = {65.0, 130.0, 0.9};
  k[index(CocoKeypoint::kRightKnee)] = {15.0, 130.0, 0.9};
  const cv::Scalar jeans(140, 80, 40), grass(40, 160, 60);
  cv::Mat stride(200, 80, CV_8UC3, grass);
  stride.rowRange(0, 80).setTo(cv::Scalar(30, 30, 200));
  for (const auto& [hip, knee] : {std::pair{k[index(CocoKeypoint::kLeftHip)], k[index(CocoKeypoint::kLeftKnee)]},
                                  std::pair{k[index(CocoKeypoint::kRightHip)], k[index(CocoKeypoint::kRightKnee)]}})
    cv::line(stride, cv::Point(static_cast<int>(hip.u_px), static_cast<int>(hip.v_px)),
             cv::Point(static_cast<int>(knee.u_px), static_cast<int>(knee.v_px)), jeans, 14);
  const Appearance walker = personAppearance(stride, k);
  const Appearance standing = personAppearance(dressed(cv::Scalar(30, 30, 200), jeans), standingKeypoints(0.9));
  ASSERT_TRUE(walker.valid && standing.valid);
  hal::AppearanceHistogram walker_legs{}, standing_legs{};
  for (std::size_t i = hal::regionOffset(hal::SignatureRegion::kLegs); i < hal::kAppearanceSignatureBins; ++i) {
    walker_legs[i] = walker.histogram[i];
    standing_legs[i] = standing.histogram[i];
  }
  EXPECT_LT(hal::signatureDistance(walker_legs, standing_legs), 0.1);
}

TEST(Appearance, GivenAReferenceWithoutLegs_WhenBlendedWithOneWithLegs_ThenTheLegsAreTakenAsTheyAre) {
  const Appearance torso_only =
      personAppearance(dressed(cv::Scalar(30, 30, 200), cv::Scalar(140, 80, 40)), standingKeypoints(0.1));
  const Appearance whole =
      personAppearance(dressed(cv::Scalar(30, 30, 200), cv::Scalar(140, 80, 40)), standingKeypoints(0.9));
  Appearance reference = torso_only;
  blendAppearance(reference, whole, 0.1);
  EXPECT_NEAR(hal::regionSum(reference.histogram, hal::SignatureRegion::kLegs), 1.0, 1e-5);
  EXPECT_LT(appearanceDistance(reference, whole), 1e-3);
  Appearance empty;
  blendAppearance(empty, torso_only, 0.1);
  EXPECT_TRUE(empty.valid);
  EXPECT_LT(appearanceDistance(empty, torso_only), 1e-6);
}

}  // namespace
}  // namespace aerotrack::perception
