// The real network on real photos (Debian's opencv-doc): MoveNet converted by scripts/models, run
// by OpenCV's DNN and decoded in C++. Checks what a person would check by eye: a person where
// there is one, with a plausible torso and joints on the body; two people in basketball1 with the
// close-up (cut off by the frame) flagged unreliable; several pedestrians in vtest.avi; nobody in
// photos without people; and the tracking loop keeping one pedestrian across video frames.
// Needs models/ (scripts/setup.sh provisions it) and opencv-doc (scripts/deps/debian-dev.txt).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "aerotrack/perception/detector.hpp"
#include "support/require.hpp"

namespace aerotrack::perception {
namespace {

using hal::CocoKeypoint;
using hal::index;

const std::string kData = "/usr/share/doc/opencv-doc/examples/data/";

cv::Mat load(const std::string& name) {
  const cv::Mat image = cv::imread(kData + name, cv::IMREAD_COLOR);
  EXPECT_FALSE(image.empty()) << kData + name << " is missing: install opencv-doc (scripts/setup.sh --dev)";
  return image;
}

Detector makeDetector(const std::string& search_model = "multipose") {
  DetectorParams params;
  params.model_dir = std::string(AEROTRACK_SOURCE_DIR) + "/models";
  params.search_model = search_model;
  return aerotrack::test::require(Detector::create(params), "Detector::create");
}

bool inside(const hal::Keypoint2D& k, const hal::PersonDetection& d) {
  return k.u_px >= d.bbox_u_px && k.u_px <= d.bbox_u_px + d.bbox_w_px && k.v_px >= d.bbox_v_px &&
         k.v_px <= d.bbox_v_px + d.bbox_h_px;
}

TEST(DetectorOnPhotos, GivenMessi_WhenLightningRuns_ThenOnePersonWithATorsoOfAbout114PxIsFound) {
  Detector detector = makeDetector();
  const cv::Mat image = load("messi5.jpg");
  const auto out = detector.detectFrame(image, "lightning");
  ASSERT_TRUE(out.has_value()) << out.error().message;
  ASSERT_EQ(out->count, 1U);
  const DetectedPerson& p = out->persons[0];
  EXPECT_GT(p.detection.score, 0.4);
  EXPECT_NEAR(p.torso.torso_px, 114.0, 12.0);
  EXPECT_TRUE(p.torso.reliable) << toString(p.torso.reason);
  const auto& k = p.detection.keypoints;
  // Shoulders above hips, both on the player (he stands in the left half of the 548 x 342 photo).
  for (CocoKeypoint j :
       {CocoKeypoint::kLeftShoulder, CocoKeypoint::kRightShoulder, CocoKeypoint::kLeftHip, CocoKeypoint::kRightHip}) {
    EXPECT_GT(k[index(j)].score, 0.3) << keypointName(j);
    EXPECT_TRUE(inside(k[index(j)], p.detection)) << keypointName(j);
  }
  EXPECT_LT(k[index(CocoKeypoint::kLeftShoulder)].v_px, k[index(CocoKeypoint::kLeftHip)].v_px);
  EXPECT_LT(k[index(CocoKeypoint::kRightShoulder)].v_px, k[index(CocoKeypoint::kRightHip)].v_px);
}

// Issue 22, item 4: Messi cut off at the waist. The network guesses the hips just above the new bottom
// edge with middling scores, so the torso comes out short (a distance too far); the edge rule must call
// it unreliable, while the whole shoulders still give his bearing.
TEST(DetectorOnPhotos, GivenMessiCutOffAtTheWaist_WhenLightningRuns_ThenTheTorsoIsUnreliableButTheBearingHolds) {
  Detector detector = makeDetector();
  const cv::Mat image = load("messi5.jpg");
  const auto whole = detector.detectFrame(image, "lightning");
  ASSERT_TRUE(whole.has_value() && whole->count == 1U);
  const auto& wk = whole->persons[0].detection.keypoints;
  const double neck_u_px =
      0.5 * (wk[index(CocoKeypoint::kLeftShoulder)].u_px + wk[index(CocoKeypoint::kRightShoulder)].u_px);
  const double hip_v_px = 0.5 * (wk[index(CocoKeypoint::kLeftHip)].v_px + wk[index(CocoKeypoint::kRightHip)].v_px);
  std::printf("[ figures  ] whole: shoulders scored %.2f/%.2f, hips %.2f/%.2f\n",
              wk[index(CocoKeypoint::kLeftShoulder)].score, wk[index(CocoKeypoint::kRightShoulder)].score,
              wk[index(CocoKeypoint::kLeftHip)].score, wk[index(CocoKeypoint::kRightHip)].score);
  // Cuts from just above the hips to about two thirds of the way up the torso.
  for (const int cut_rows :
       {static_cast<int>(hip_v_px) - 10, static_cast<int>(hip_v_px) - 40, static_cast<int>(hip_v_px) - 70}) {
    const cv::Mat cut = image.rowRange(0, cut_rows).clone();
    const auto out = detector.detectFrame(cut, "lightning");
    ASSERT_TRUE(out.has_value()) << out.error().message;
    ASSERT_GE(out->count, 1U) << "cut at row " << cut_rows;
    const TorsoFeatures& torso = out->persons[0].torso;
    const auto& k = out->persons[0].detection.keypoints;
    std::printf(
        "[ figures  ] cut at row %d (hips at %.0f): torso %.0f px (whole %.0f), hips %.0f px above the edge, "
        "scores %.2f/%.2f, %s, bearing %+.1f px off\n",
        cut_rows, hip_v_px, torso.torso_px, whole->persons[0].torso.torso_px,
        cut_rows - 0.5 * (k[index(CocoKeypoint::kLeftHip)].v_px + k[index(CocoKeypoint::kRightHip)].v_px),
        k[index(CocoKeypoint::kLeftHip)].score, k[index(CocoKeypoint::kRightHip)].score,
        std::string(toString(torso.reason)).c_str(), torso.bearing_u_px - neck_u_px);
    EXPECT_FALSE(torso.reliable) << "cut at row " << cut_rows << ": torso " << torso.torso_px << " px";
    EXPECT_TRUE(torso.bearing_ok) << "cut at row " << cut_rows;
    EXPECT_NEAR(torso.bearing_u_px, neck_u_px, 10.0) << "cut at row " << cut_rows;
  }
}

TEST(DetectorOnPhotos, GivenBasketball_WhenMultiposeRuns_ThenTwoPeopleAndTheCloseUpIsUnreliable) {
  Detector detector = makeDetector();
  const cv::Mat image = load("basketball1.png");
  const auto out = detector.detectFrame(image, "multipose");
  ASSERT_TRUE(out.has_value()) << out.error().message;
  ASSERT_EQ(out->count, 2U);
  // The close-up player fills the frame (the larger box); his torso runs off the image.
  const auto area = [](const DetectedPerson& p) { return p.detection.bbox_w_px * p.detection.bbox_h_px; };
  const DetectedPerson& close = area(out->persons[0]) > area(out->persons[1]) ? out->persons[0] : out->persons[1];
  const DetectedPerson& far = area(out->persons[0]) > area(out->persons[1]) ? out->persons[1] : out->persons[0];
  EXPECT_FALSE(close.torso.reliable);
  EXPECT_TRUE(far.torso.reliable) << toString(far.torso.reason);
}

TEST(DetectorOnPhotos, GivenPedestrianVideo_WhenMultiposeRuns_ThenSeveralPedestriansAreFound) {
  Detector detector = makeDetector();
  cv::VideoCapture video(kData + "vtest.avi");
  ASSERT_TRUE(video.isOpened());
  cv::Mat frame;
  for (int i = 0; i <= 200; ++i) ASSERT_TRUE(video.read(frame));
  const auto out = detector.detectFrame(frame, "multipose");
  ASSERT_TRUE(out.has_value()) << out.error().message;
  EXPECT_GE(out->count, 3U);
}

TEST(DetectorOnPhotos, GivenPhotosWithoutPeople_WhenEveryModelRuns_ThenNobodyIsFound) {
  Detector detector = makeDetector();
  for (const char* name : {"fruits.jpg", "box.png", "sudoku.png", "home.jpg", "starry_night.jpg"}) {
    const cv::Mat image = load(name);
    for (const char* model : {"lightning", "thunder", "multipose"}) {
      const auto out = detector.detectFrame(image, model);
      ASSERT_TRUE(out.has_value()) << out.error().message;
      EXPECT_EQ(out->count, 0U) << name << " " << model << ": score " << out->persons[0].detection.score;
    }
  }
}

TEST(DetectorOnPhotos, GivenABuildingFacade_WhenTheSearchModelRuns_ThenNobodyIsFound) {
  // Singlepose always outputs a pose, and on this facade its mean joint score (0.31 lightning,
  // 0.40 thunder) is that of a person: which is why the tracking loop searches with multipose,
  // whose person score stays low here.
  Detector detector = makeDetector();
  const auto out = detector.detectFrame(load("building.jpg"), "multipose");
  ASSERT_TRUE(out.has_value()) << out.error().message;
  EXPECT_EQ(out->count, 0U) << "score " << out->persons[0].detection.score;
}

TEST(DetectorOnPhotos, GivenPedestrianVideo_WhenTracking_ThenTheCropStaysOnOneLockedPerson) {
  // The first 25 frames (2.5 s at 10 fps) of vtest.avi, while the pedestrian locked on first stays
  // over 20 px of torso; later he walks away up the street and is lost.
  Detector detector = makeDetector();
  cv::VideoCapture video(kData + "vtest.avi");
  ASSERT_TRUE(video.isOpened());
  cv::Mat frame;
  int locked = 0, cropped = 0;
  std::optional<double> last_u;
  double largest_step_px = 0.0;
  constexpr int kFrames = 25;
  for (int i = 0; i < kFrames; ++i) {
    ASSERT_TRUE(video.read(frame));
    const auto out = detector.track(frame, rt::secondsToNs(i / 10.0));
    ASSERT_TRUE(out.has_value()) << out.error().message;
    if (!out->target) continue;
    ++locked;
    cropped += out->cropped ? 1 : 0;
    const double u = out->persons[*out->target].torso.u_px;
    if (last_u) largest_step_px = std::max(largest_step_px, std::abs(u - *last_u));
    last_u = u;
  }
  EXPECT_GE(locked, kFrames - 2);
  EXPECT_GE(cropped, kFrames - 3);   // the crop, not the full-frame search, does the tracking
  EXPECT_LT(largest_step_px, 25.0);  // pedestrians move a few pixels a frame: no switch to another
}

}  // namespace
}  // namespace aerotrack::perception
