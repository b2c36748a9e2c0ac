// Unit tests of the input transform (letterbox, tracking crop, blob filling) and the torso features,
// with hand-computed expectations.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "aerotrack/perception/detector.hpp"
#include "aerotrack/perception/input_transform.hpp"
#include "aerotrack/perception/torso_features.hpp"

namespace aerotrack::perception {
namespace {

using hal::CocoKeypoint;
using hal::index;
using Keypoints = std::array<hal::Keypoint2D, hal::kNumKeypoints>;

TEST(Letterbox, GivenA640x480Frame_WhenLetterboxedTo192_ThenItIsCentredWithBarsAboveAndBelow) {
  const InputTransform t = letterbox(640, 480, 192);
  EXPECT_DOUBLE_EQ(t.region_side_px, 640.0);
  EXPECT_DOUBLE_EQ(t.region_u0_px, 0.0);
  EXPECT_DOUBLE_EQ(t.region_v0_px, -80.0);
  EXPECT_DOUBLE_EQ(t.scale(), 0.3);
  // The network's centre is the image's centre; its corners are the square's corners.
  EXPECT_DOUBLE_EQ(t.toImageU(96.0), 320.0);
  EXPECT_DOUBLE_EQ(t.toImageV(96.0), 240.0);
  EXPECT_DOUBLE_EQ(t.toImageV(0.0), -80.0);
  EXPECT_DOUBLE_EQ(t.toImageU(192.0), 640.0);
}

TEST(FillInputBlob, GivenAnImageOfTheInputSize_WhenFilled_ThenPixelsPassUnchangedInRgbPlanes) {
  cv::Mat bgr(4, 4, CV_8UC3);
  cv::randu(bgr, 0, 256);
  TransformScratch scratch;
  cv::Mat blob = makeInputBlob(4);
  fillInputBlob(bgr, letterbox(4, 4, 4), scratch, blob);
  const float* p = blob.ptr<float>();
  for (int v = 0; v < 4; ++v)
    for (int u = 0; u < 4; ++u) {
      const cv::Vec3b px = bgr.at<cv::Vec3b>(v, u);
      EXPECT_EQ(p[0 * 16 + v * 4 + u], px[2]);  // R
      EXPECT_EQ(p[1 * 16 + v * 4 + u], px[1]);  // G
      EXPECT_EQ(p[2 * 16 + v * 4 + u], px[0]);  // B
    }
}

TEST(FillInputBlob, GivenAWideFrame_WhenLetterboxed_ThenTheBarsAreBlackAndTheCentreKeepsItsColour) {
  cv::Mat bgr(50, 100, CV_8UC3, cv::Scalar(10, 20, 200));
  TransformScratch scratch;
  cv::Mat blob = makeInputBlob(100);
  fillInputBlob(bgr, letterbox(100, 50, 100), scratch, blob);
  const float* r = blob.ptr<float>();
  EXPECT_EQ(r[10 * 100 + 50], 0.0F);    // row 10: inside the top bar (rows 0..24)
  EXPECT_EQ(r[50 * 100 + 50], 200.0F);  // centre: the image
  EXPECT_EQ(r[90 * 100 + 50], 0.0F);    // bottom bar
}

Keypoints standingPerson(double hip_u, double hip_v, double torso_px, double score) {
  Keypoints k{};
  for (auto& p : k) p = {hip_u, hip_v - 0.5 * torso_px, score};
  k[index(CocoKeypoint::kLeftShoulder)] = {hip_u + 0.2 * torso_px, hip_v - torso_px, score};
  k[index(CocoKeypoint::kRightShoulder)] = {hip_u - 0.2 * torso_px, hip_v - torso_px, score};
  k[index(CocoKeypoint::kLeftHip)] = {hip_u + 0.15 * torso_px, hip_v, score};
  k[index(CocoKeypoint::kRightHip)] = {hip_u - 0.15 * torso_px, hip_v, score};
  k[index(CocoKeypoint::kNose)] = {hip_u, hip_v - 1.4 * torso_px, score};
  k[index(CocoKeypoint::kLeftAnkle)] = {hip_u + 0.1 * torso_px, hip_v + 1.6 * torso_px, score};
  k[index(CocoKeypoint::kRightAnkle)] = {hip_u - 0.1 * torso_px, hip_v + 1.6 * torso_px, score};
  return k;
}

TEST(CropAroundPerson, GivenAConfidentPerson_WhenCropped_ThenTheSquareIsCentredOnTheHipsAndHoldsTheBody) {
  const Keypoints k = standingPerson(300.0, 250.0, 50.0, 0.9);
  InputTransform t;
  ASSERT_TRUE(cropAroundPerson(k, 640, 480, 192, CropParams{}, t));
  // Largest torso-joint range: the shoulders, 50 px above the hip centre -> 1.9 x 50 = 95 px;
  // largest body range: the ankles, 80 px below -> 1.2 x 80 = 96 px; half side 96 px.
  EXPECT_DOUBLE_EQ(t.region_side_px, 192.0);
  EXPECT_DOUBLE_EQ(t.region_u0_px, 300.0 - 96.0);
  EXPECT_DOUBLE_EQ(t.region_v0_px, 250.0 - 96.0);
}

TEST(CropAroundPerson, GivenNoConfidentHips_WhenCropped_ThenThereIsNoCrop) {
  Keypoints k = standingPerson(300.0, 250.0, 50.0, 0.9);
  k[index(CocoKeypoint::kLeftHip)].score = 0.1;
  k[index(CocoKeypoint::kRightHip)].score = 0.1;
  InputTransform t;
  EXPECT_FALSE(cropAroundPerson(k, 640, 480, 192, CropParams{}, t));
}

TEST(CropAroundPerson, GivenAPersonFillingTheFrame_WhenCropped_ThenTheWholeFrameIsUsed) {
  const Keypoints k = standingPerson(320.0, 240.0, 200.0, 0.9);
  InputTransform t;
  ASSERT_TRUE(cropAroundPerson(k, 640, 480, 192, CropParams{}, t));
  EXPECT_DOUBLE_EQ(t.region_side_px, 640.0);
}

hal::PersonDetection boxAt(double u0_px, double v0_px, double w_px, double h_px) {
  hal::PersonDetection p;
  p.bbox_u_px = u0_px;
  p.bbox_v_px = v0_px;
  p.bbox_w_px = w_px;
  p.bbox_h_px = h_px;
  return p;
}

TEST(SomeoneNearRegion, GivenPeopleAroundACrop_WhenTheMarginGrows_ThenThoseWithinItAreNear) {
  // The crop: the square [100, 300) x [100, 300), side 200; margin 0.5 sides: [0, 400) x [0, 400).
  const InputTransform crop = squareRegion(200.0, 200.0, 200.0, 192);
  const std::array<hal::PersonDetection, 3> people = {boxAt(150.0, 120.0, 60.0, 150.0),   // the target
                                                      boxAt(380.0, 150.0, 40.0, 100.0),   // 80 px right of it
                                                      boxAt(600.0, 150.0, 40.0, 100.0)};  // far right
  EXPECT_TRUE(someoneNearRegion(std::span(people), 0, crop, 0.5));
  EXPECT_FALSE(someoneNearRegion(std::span(people), 0, crop, 0.3));   // the crop grown to [40, 360)
  EXPECT_FALSE(someoneNearRegion(std::span(people), 0, crop, -1.0));  // never
  // The target alone never counts, however large the margin; nor does an empty box.
  EXPECT_FALSE(someoneNearRegion(std::span(people).first(1), 0, crop, 10.0));
  const std::array<hal::PersonDetection, 2> empty_box = {people[0], boxAt(200.0, 200.0, 0.0, 0.0)};
  EXPECT_FALSE(someoneNearRegion(std::span(empty_box), 0, crop, 1.0));
  // Someone inside the crop itself is near at any margin >= 0.
  const std::array<hal::PersonDetection, 2> inside = {people[0], boxAt(250.0, 130.0, 30.0, 90.0)};
  EXPECT_TRUE(someoneNearRegion(std::span(inside), 0, crop, 0.0));
}

DetectedPerson personAt(double hip_u, double hip_v, double torso_px, double score = 0.9) {
  DetectedPerson p;
  p.detection.keypoints = standingPerson(hip_u, hip_v, torso_px, score);
  // The box of the joints (nose to ankles, 3 torso lengths), as the decoders make it.
  p.detection.bbox_u_px = hip_u - 0.3 * torso_px;
  p.detection.bbox_v_px = hip_v - 1.4 * torso_px;
  p.detection.bbox_w_px = 0.6 * torso_px;
  p.detection.bbox_h_px = 3.0 * torso_px;
  return p;
}

TEST(AddOthersBesideCrop, GivenTheCropsPersonAndTwoOthersInTheWholeFrame_WhenAdded_ThenOnlyTheOthersAreAdded) {
  DetectorOutput crop;
  crop.persons[0] = personAt(300.0, 250.0, 60.0);
  crop.count = 1;
  crop.target = 0;
  DetectorOutput whole;
  // The crop's person again, as the whole frame's coarser network places them (a few pixels off)...
  whole.persons[0] = personAt(304.0, 247.0, 57.0);
  // ... someone half hidden beside them (a shoulder's width to the side: 0.8 torso lengths), not the crop's person's
  // nearest in the whole frame, and someone far.
  whole.persons[1] = personAt(348.0, 252.0, 58.0);
  whole.persons[2] = personAt(560.0, 200.0, 30.0);
  whole.count = 3;
  EXPECT_EQ(addOthersBesideCrop(crop, whole, 0.2), 2U);
  ASSERT_EQ(crop.count, 3U);
  EXPECT_EQ(crop.target, std::optional<std::size_t>(0));  // the crop's own people keep their places
  EXPECT_DOUBLE_EQ(crop.persons[0].detection.bbox_u_px, 300.0 - 18.0);
  EXPECT_DOUBLE_EQ(crop.persons[1].detection.keypoints[index(CocoKeypoint::kLeftHip)].u_px, 348.0 + 0.15 * 58.0);
  EXPECT_DOUBLE_EQ(crop.persons[2].detection.keypoints[index(CocoKeypoint::kLeftHip)].u_px, 560.0 + 0.15 * 30.0);
}

TEST(AddOthersBesideCrop, GivenTheWholeFrameMissedTheCropsPerson_WhenAdded_ThenOnlySomeoneAtTheirPlaceIsTakenForThem) {
  DetectorOutput crop;
  crop.persons[0] = personAt(300.0, 250.0, 60.0);
  crop.count = 1;
  // Someone a shoulder's width aside (0.27 box heights) is nearest and near enough: taken for the crop's person, whom
  // the coarser whole frame may place that far off. Someone 1.2 torso lengths aside (0.4 box heights) is not.
  DetectorOutput beside;
  beside.persons[0] = personAt(348.0, 250.0, 60.0);
  beside.count = 1;
  EXPECT_EQ(addOthersBesideCrop(crop, beside, 0.2), 0U);
  DetectorOutput farther;
  farther.persons[0] = personAt(372.0, 250.0, 60.0);
  farther.count = 1;
  EXPECT_EQ(addOthersBesideCrop(crop, farther, 0.2), 1U);
  EXPECT_EQ(crop.count, 2U);
}

TEST(AddOthersBesideCrop, GivenJointsTooUnsureToCompare_WhenAdded_ThenTheBoxesOverlapDecides) {
  DetectorOutput crop;
  crop.persons[0] = personAt(300.0, 250.0, 60.0);
  crop.count = 1;
  DetectorOutput whole;
  whole.persons[0] = personAt(302.0, 251.0, 60.0, /*score=*/0.1);  // the same box, no sure joint
  whole.persons[1] = personAt(330.0, 250.0, 60.0, /*score=*/0.1);  // a box overlapping it by 17 %
  whole.count = 2;
  EXPECT_EQ(addOthersBesideCrop(crop, whole, 0.2), 1U);
  ASSERT_EQ(crop.count, 2U);
  EXPECT_DOUBLE_EQ(crop.persons[1].detection.bbox_u_px, 330.0 - 18.0);
}

TEST(AddOthersBesideCrop, GivenMoreThanAFrameHolds_WhenAdded_ThenItStopsAtTheMostPersons) {
  DetectorOutput crop;
  crop.persons[0] = personAt(40.0, 250.0, 20.0);
  crop.count = 1;
  DetectorOutput whole;
  for (std::size_t i = 0; i < hal::kMaxPersons; ++i)
    whole.persons[i] = personAt(100.0 + 80.0 * static_cast<double>(i), 250.0, 20.0);
  whole.count = hal::kMaxPersons;
  EXPECT_EQ(addOthersBesideCrop(crop, whole, 0.2), hal::kMaxPersons - 1);
  EXPECT_EQ(crop.count, hal::kMaxPersons);
  // An empty whole frame adds nobody.
  DetectorOutput alone;
  alone.persons[0] = crop.persons[0];
  alone.count = 1;
  EXPECT_EQ(addOthersBesideCrop(alone, DetectorOutput{}, 0.2), 0U);
  EXPECT_EQ(alone.count, 1U);
}

TEST(TorsoFeatures, GivenAConfidentTorso_WhenMeasured_ThenLengthAndCentreComeFromNeckAndMidHip) {
  const Keypoints k = standingPerson(300.0, 250.0, 80.0, 0.9);
  const TorsoFeatures f = torsoFeatures(k, 640, 480, TorsoFeatureParams{});
  EXPECT_TRUE(f.reliable);
  EXPECT_EQ(f.reason, TorsoReason::kOk);
  EXPECT_DOUBLE_EQ(f.torso_px, 80.0);
  EXPECT_DOUBLE_EQ(f.u_px, 300.0);
  EXPECT_DOUBLE_EQ(f.v_px, 210.0);
}

TEST(TorsoFeatures, GivenAWeakHip_WhenMeasured_ThenItIsUnreliableForALowScoreOfThatHip) {
  Keypoints k = standingPerson(300.0, 250.0, 80.0, 0.9);
  k[index(CocoKeypoint::kRightHip)].score = 0.29;
  const TorsoFeatures f = torsoFeatures(k, 640, 480, TorsoFeatureParams{});
  EXPECT_FALSE(f.reliable);
  EXPECT_EQ(f.reason, TorsoReason::kLowScore);
  EXPECT_EQ(f.culprit, CocoKeypoint::kRightHip);
}

TEST(TorsoFeatures, GivenHipsCutOffByTheBottomEdge_WhenMeasured_ThenItIsUnreliableOnTheBorder) {
  // MoveNet clamps the hips of a person cut off by the frame to the last rows.
  Keypoints k = standingPerson(300.0, 478.0, 80.0, 0.9);
  const TorsoFeatures f = torsoFeatures(k, 640, 480, TorsoFeatureParams{});
  EXPECT_FALSE(f.reliable);
  EXPECT_EQ(f.reason, TorsoReason::kOnBorder);
  EXPECT_EQ(toString(f.reason), "on_border");
  EXPECT_EQ(keypointName(f.culprit), "left_hip");
}

TEST(TorsoFeatures, GivenKeypointsMovedElsewhere_WhenRemeasured_ThenTheVerdictsStayAndTheLengthsAreTheMovedOnes) {
  // A torso with whole shoulders and hips cut at the bottom edge (a bearing from the shoulders), then the same
  // joints moved (as into a level camera's image): 60 px further right and stretched to 100 px.
  Keypoints k = standingPerson(300.0, 480.0 - 0.45 * 80.0, 80.0, 0.9);
  k[index(CocoKeypoint::kLeftHip)].score = 0.4;
  k[index(CocoKeypoint::kRightHip)].score = 0.4;
  const TorsoFeatures seen = torsoFeatures(k, 640, 480, TorsoFeatureParams{});
  ASSERT_FALSE(seen.reliable);
  ASSERT_TRUE(seen.bearing_ok && seen.bearing_from_shoulders);
  const Keypoints moved = standingPerson(360.0, 300.0, 100.0, 0.9);
  const TorsoFeatures f = remeasured(seen, moved);
  EXPECT_FALSE(f.reliable);
  EXPECT_EQ(f.reason, seen.reason);
  EXPECT_TRUE(f.bearing_ok);
  EXPECT_DOUBLE_EQ(f.torso_px, 100.0);
  EXPECT_DOUBLE_EQ(f.u_px, 360.0);
  EXPECT_DOUBLE_EQ(f.v_px, 250.0);
  EXPECT_DOUBLE_EQ(f.bearing_u_px, 360.0);  // the moved shoulders' midpoint
}

/// The hips (or shoulders) of `k` given a guess's score, as MoveNet scores the joints of a cut-off body.
Keypoints guessed(Keypoints k, CocoKeypoint a, CocoKeypoint b) {
  k[index(a)].score = 0.4;
  k[index(b)].score = 0.4;
  return k;
}

// A torso with no distance (on a 640 x 480 image's border) whose whole shoulders or hips still give a bearing.
void expectOnBorderWithBearing(const Keypoints& k, double bearing_u_px) {
  const TorsoFeatures f = torsoFeatures(k, 640, 480, TorsoFeatureParams{});
  EXPECT_FALSE(f.reliable);
  EXPECT_EQ(f.reason, TorsoReason::kOnBorder);
  EXPECT_TRUE(f.bearing_ok);
  EXPECT_DOUBLE_EQ(f.bearing_u_px, bearing_u_px);
}

// Issue 22, item 4: a waist cut leaves the guessed hips a fraction of a torso inside the bottom edge.
TEST(TorsoFeatures, GivenHipsWithinHalfATorsoOfTheBottomEdge_WhenMeasured_ThenUnreliableButTheShouldersGiveABearing) {
  const Keypoints k =
      guessed(standingPerson(300.0, 480.0 - 0.45 * 80.0, 80.0, 0.9), CocoKeypoint::kLeftHip, CocoKeypoint::kRightHip);
  expectOnBorderWithBearing(k, 300.0);  // the shoulders' midpoint
}

TEST(TorsoFeatures, GivenHipsJustOverHalfATorsoAboveTheBottomEdge_WhenMeasured_ThenReliable) {
  const Keypoints k =
      guessed(standingPerson(300.0, 480.0 - 0.55 * 80.0, 80.0, 0.9), CocoKeypoint::kLeftHip, CocoKeypoint::kRightHip);
  const TorsoFeatures f = torsoFeatures(k, 640, 480, TorsoFeatureParams{});
  EXPECT_TRUE(f.reliable) << toString(f.reason);
  EXPECT_TRUE(f.bearing_ok);
}

TEST(TorsoFeatures, GivenShouldersWithinHalfATorsoOfTheTopEdge_WhenMeasured_ThenTheHipsGiveTheBearing) {
  // Shoulders 24 px below the top.
  const Keypoints k = guessed(standingPerson(250.0, 80.0 + 0.3 * 80.0, 80.0, 0.9), CocoKeypoint::kLeftShoulder,
                              CocoKeypoint::kRightShoulder);
  expectOnBorderWithBearing(k, 250.0);  // the hips' midpoint
}

TEST(TorsoFeatures, GivenACutAtTheChest_WhenShouldersAndHipsAreAllGuessedNearTheBottom_ThenTheWidthsKeepTheMargin) {
  // The whole torso below the frame: shoulders 20 px and hips 12 px above the bottom edge, a few pixels
  // apart (a "torso" of 8 px), the shoulders 60 px wide as seen.
  Keypoints k = standingPerson(300.0, 468.0, 150.0, 0.4);
  k[index(CocoKeypoint::kLeftShoulder)] = {330.0, 460.0, 0.4};
  k[index(CocoKeypoint::kRightShoulder)] = {270.0, 460.0, 0.4};
  const TorsoFeatures f = torsoFeatures(k, 640, 480, TorsoFeatureParams{});
  EXPECT_NEAR(f.torso_px, 8.0, 1e-9);
  EXPECT_FALSE(f.reliable);
  EXPECT_EQ(f.reason, TorsoReason::kOnBorder);
  EXPECT_FALSE(f.bearing_ok);
}

TEST(TorsoFeatures, GivenAShoulderTenPixelsFromTheSideEdge_WhenMeasured_ThenTheSideKeepsThePixelMargin) {
  // Sideways, a cut shows as joints on the border (clamped); a whole torso near the side is fine.
  const Keypoints k = standingPerson(10.0 + 0.2 * 80.0, 250.0, 80.0, 0.9);
  const TorsoFeatures f = torsoFeatures(k, 640, 480, TorsoFeatureParams{});
  EXPECT_TRUE(f.reliable) << toString(f.reason);
}

TEST(TorsoFeatures, GivenBothPairsWeak_WhenMeasured_ThenThereIsNoBearing) {
  Keypoints k = standingPerson(300.0, 250.0, 80.0, 0.9);
  k[index(CocoKeypoint::kLeftShoulder)].score = 0.1;
  k[index(CocoKeypoint::kRightHip)].score = 0.1;
  const TorsoFeatures f = torsoFeatures(k, 640, 480, TorsoFeatureParams{});
  EXPECT_FALSE(f.reliable);
  EXPECT_FALSE(f.bearing_ok);
}

TEST(TorsoFeatures, GivenConfidentShouldersNearTheTop_WhenMeasured_ThenTheyAreTakenWhereTheNetworkPutsThem) {
  // A person standing close to a camera on the ground: shoulders 24 px below the top, scored 0.9.
  const Keypoints k = standingPerson(250.0, 80.0 + 0.3 * 80.0, 80.0, 0.9);
  const TorsoFeatures f = torsoFeatures(k, 640, 480, TorsoFeatureParams{});
  EXPECT_TRUE(f.reliable) << toString(f.reason);
}

TEST(TorsoFeatures, GivenTheFractionZero_WhenHipsAreTwentyPixelsAboveTheEdge_ThenThePixelMarginAloneDecides) {
  const Keypoints k = guessed(standingPerson(300.0, 460.0, 80.0, 0.9), CocoKeypoint::kLeftHip, CocoKeypoint::kRightHip);
  TorsoFeatureParams params;
  params.edge_margin_torso_fraction = 0.0;
  EXPECT_TRUE(torsoFeatures(k, 640, 480, params).reliable);
  params.edge_margin_torso_fraction = 0.5;
  EXPECT_FALSE(torsoFeatures(k, 640, 480, params).reliable);
}

}  // namespace
}  // namespace aerotrack::perception
