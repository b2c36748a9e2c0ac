// Tests of the sim gimbal camera's image mode (sensors.gimbal_camera.mode: image): the scenario key is
// read strictly with keypoints as the default, and in image mode grab() delivers rendered frames at the
// camera's rate stamped at their exposure times while grabDetections() stays silent.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "aerotrack/hal/sim/devices.hpp"

namespace aerotrack::hal::sim {
namespace {

std::string scenarioYaml(const std::string& gimbal_camera) {
  return R"(name: image_mode
end_margin_s: 0.5
max_duration_s: 4.0
world:
  bounds_min_m: [-10.0, -10.0, 0.0]
  bounds_max_m: [10.0, 10.0, 5.0]
  cylinders:
    - {center_m: [3.0, 2.0], radius_m: 0.3, height_m: 3.0}
person:
  height_m: 1.75
  torso_m: 0.50
  start_delay_s: 0.5
  path:
    - {p_m: [0.0, 0.0], speed_mps: 1.0}
    - {p_m: [4.0, 0.0], speed_mps: 0.0}
drone:
  start_m: [-2.5, 0.0, 1.5]
  start_yaw_rad: 0.0
  radius_m: 0.25
  mass_kg: 1.0
  thrust_to_weight: 2.5
success:
  tracking_distance_m: 2.5
  final_distance_factor: 2.0
)" + gimbal_camera;
}

const std::string kCameraKeys = R"(    rate_hz: 10
    latency_s: 0.04
    width_px: 320
    height_px: 240
    hfov_deg: 87
    pixel_noise_torso_fraction: 0.028
    keypoint_miss_probability: 0.03
)";

TEST(ImageModeConfig, ModeDefaultsToKeypointsAndIsReadStrictly) {
  // Given scenarios without the key, with each value, and with a misspelt value
  const auto absent = parseScenarioSpec(scenarioYaml(""), "a.yaml");
  const auto keypoints =
      parseScenarioSpec(scenarioYaml("sensors:\n  gimbal_camera:\n    mode: keypoints\n" + kCameraKeys), "b.yaml");
  const auto image =
      parseScenarioSpec(scenarioYaml("sensors:\n  gimbal_camera:\n    mode: image\n" + kCameraKeys), "c.yaml");
  const auto bad =
      parseScenarioSpec(scenarioYaml("sensors:\n  gimbal_camera:\n    mode: images\n" + kCameraKeys), "d.yaml");

  // Then the mode is keypoints unless image is asked for, and a bad value names the key
  ASSERT_TRUE(absent.has_value()) << absent.error().message;
  ASSERT_TRUE(keypoints.has_value()) << keypoints.error().message;
  ASSERT_TRUE(image.has_value()) << image.error().message;
  EXPECT_EQ(absent->gimbal_camera.mode, GimbalCameraMode::kKeypoints);
  EXPECT_EQ(keypoints->gimbal_camera.mode, GimbalCameraMode::kKeypoints);
  EXPECT_EQ(image->gimbal_camera.mode, GimbalCameraMode::kImage);
  ASSERT_FALSE(bad.has_value());
  EXPECT_NE(bad.error().message.find("sensors.gimbal_camera.mode"), std::string::npos) << bad.error().message;
}

// A cast file of two people (the default cast's first two) written to the test's temporary folder.
std::string writeCastFile(const std::string& name, const std::string& extra = "") {
  const PersonCastSpec cast = defaultCast();
  std::ostringstream out;
  out << "people:\n";
  for (std::size_t i = 0; i < 2; ++i) {
    const PersonSpriteSpec& p = cast.people[i];
    out << "  - name: " << (i == 0 ? "a" : "b") << "\n    image: " << p.image_path << "\n";
    if (p.frame >= 0) out << "    frame: " << p.frame << "\n";
    out << "    view: " << toString(p.view) << "\n    crop_px: [" << p.crop_px[0] << ", " << p.crop_px[1] << ", "
        << p.crop_px[2] << ", " << p.crop_px[3] << "]\n    keypoints_px: [";
    for (std::size_t k = 0; k < kNumKeypoints; ++k)
      out << (k ? ", " : "") << "[" << p.keypoints_px[k].x() << ", " << p.keypoints_px[k].y() << "]";
    out << "]\n";
  }
  out << extra;
  const std::string path = testing::TempDir() + "/" + name;
  std::ofstream(path) << out.str();
  return path;
}

TEST(ImageModeConfig, ACastFileAndTheTargetPersonAreReadStrictly) {
  // Given a cast file of two people, and scenarios naming it and their target
  const std::string path = writeCastFile("cast_ok.yaml");
  const auto with = [&](const std::string& keys) {
    return parseScenarioSpec(scenarioYaml("sensors:\n  gimbal_camera:\n    mode: image\n" + kCameraKeys + keys),
                             "e.yaml");
  };
  const auto spec = with("    people: " + path + "\n    target_person: b\n");

  // Then the cast is read and the target is the person named
  ASSERT_TRUE(spec.has_value()) << spec.error().message;
  ASSERT_EQ(spec->gimbal_camera.cast.people.size(), 2U);
  EXPECT_EQ(spec->gimbal_camera.cast.people[1].name, "b");
  EXPECT_EQ(spec->gimbal_camera.cast.people[1].frame, defaultCast().people[1].frame);
  EXPECT_EQ(spec->gimbal_camera.target_person, 1U);
  // ... and without the keys, the default cast's first person is the target
  const auto plain = with("");
  ASSERT_TRUE(plain.has_value());
  EXPECT_EQ(plain->gimbal_camera.cast.people.size(), defaultCast().people.size());
  EXPECT_EQ(plain->gimbal_camera.target_person, 0U);

  // And a missing file, an unknown person, a misspelt key, a keypoint outside the crop and an empty
  // cast are one-line errors naming the key
  const auto expectError = [&](const std::string& keys, const std::string& needle) {
    const auto bad = with(keys);
    ASSERT_FALSE(bad.has_value()) << keys;
    EXPECT_NE(bad.error().message.find(needle), std::string::npos) << bad.error().message;
    EXPECT_EQ(bad.error().message.find('\n'), std::string::npos) << bad.error().message;
  };
  expectError("    people: /nonexistent/cast.yaml\n", "sensors.gimbal_camera.people");
  expectError("    people: " + path + "\n    target_person: c\n", "no person named c");
  expectError("    people: " + writeCastFile("cast_typo.yaml", "    veiw: front\n") + "\n", "veiw");
  std::ostringstream read;
  read << std::ifstream(path).rdbuf();
  const std::string text = read.str();
  const std::string far = testing::TempDir() + "/cast_far.yaml";
  std::string moved = text;  // the first person's nose far outside its crop
  const std::size_t nose = moved.find("[95, 115]");
  ASSERT_NE(nose, std::string::npos);
  moved.replace(nose, 9, "[9500, 115]");
  std::ofstream(far) << moved;
  expectError("    people: " + far + "\n", "keypoint 0 lies outside crop_px");
  const std::string empty = testing::TempDir() + "/cast_empty.yaml";
  std::ofstream(empty) << "people: []\n";
  expectError("    people: " + empty + "\n", "the cast is empty");
}

TEST(ImageMode, AMissingPhotoFailsTheSimulationsCreation) {
  // Given an image-mode scenario whose sprite photo is missing
  auto spec = parseScenarioSpec(scenarioYaml("sensors:\n  gimbal_camera:\n    mode: image\n" + kCameraKeys), "g.yaml");
  ASSERT_TRUE(spec.has_value());
  spec->gimbal_camera.cast.people[0].image_path = "/nonexistent/sprite.png";
  auto trial = instantiate(*spec, 1);
  ASSERT_TRUE(trial.has_value());

  // When the simulation is created, then it is an error naming the file and the sensor
  const auto sim = Simulation::create(*trial, {}, 0);
  ASSERT_FALSE(sim.has_value());
  EXPECT_NE(sim.error().message.find("/nonexistent/sprite.png"), std::string::npos) << sim.error().message;
  EXPECT_NE(sim.error().message.find("gimbal_camera"), std::string::npos) << sim.error().message;
}

/// The cast's photo missing (opencv-doc not installed), or "".
std::string missingCastPhoto() {
  for (const PersonSpriteSpec& p : defaultCast().people)
    if (!std::filesystem::exists(p.image_path)) return p.image_path;
  return "";
}

/// A simulation of the scenario above with an image-mode camera at 10 Hz, 320 x 240, from start_ns.
std::shared_ptr<Simulation> imageModeSimulation(SimulationOptions options, TimeNs start_ns) {
  const auto spec =
      parseScenarioSpec(scenarioYaml("sensors:\n  gimbal_camera:\n    mode: image\n" + kCameraKeys), "h.yaml");
  EXPECT_TRUE(spec.has_value()) << spec.error().message;
  auto trial = instantiate(*spec, 7);
  EXPECT_TRUE(trial.has_value());
  options.render_depth = false;
  auto sim = Simulation::create(*trial, options, start_ns);
  EXPECT_TRUE(sim.has_value()) << sim.error().message;
  return sim ? std::shared_ptr<Simulation>(std::move(sim.value())) : nullptr;
}

TEST(ImageMode, GrabDeliversFramesAtTheCameraRateStampedAtExposure) {
  if (const std::string missing = missingCastPhoto(); !missing.empty())
    GTEST_SKIP() << missing << " is missing: install opencv-doc";
  // Given an image-mode camera at 10 Hz, 320 x 240, and its device polled at 200 Hz for 1.5 s
  std::shared_ptr<Simulation> shared = imageModeSimulation({}, 1'000'000'000);
  ASSERT_NE(shared, nullptr);
  SimGimbalCamera camera(shared);

  std::vector<ImageFrameHandle> frames;
  int detections = 0;
  for (TimeNs t = 1'000'000'000; t <= 2'500'000'000; t += 5'000'000) {
    shared->step(t);
    if (ImageFrameHandle frame = camera.grab(t)) {
      EXPECT_LE(frame->stamp_ns, t);
      frames.push_back(std::move(frame));
    }
    if (camera.grabDetections(t)) ++detections;
  }

  // Then one frame per exposure: 16 at 0, 100, ..., 1500 ms, stamped exactly there, numbered in
  // sequence, of the configured size, and no detections at all
  ASSERT_EQ(frames.size(), 16U);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i]->stamp_ns, 1'000'000'000 + static_cast<TimeNs>(i) * 100'000'000);
    EXPECT_EQ(frames[i]->sequence, i + 1);
    EXPECT_EQ(frames[i]->bgr.cols, 320);
    EXPECT_EQ(frames[i]->bgr.rows, 240);
    EXPECT_EQ(frames[i]->bgr.type(), CV_8UC3);
    EXPECT_EQ(frames[i]->intrinsics.width_px, 320);
  }
  EXPECT_EQ(detections, 0);
  // Frames still held are never overwritten: the first and last differ (the drone took off).
  cv::Mat diff;
  cv::absdiff(frames.front()->bgr, frames.back()->bgr, diff);
  EXPECT_GT(cv::norm(diff, cv::NORM_L1), 0.0);
  EXPECT_EQ(camera.health(2'500'000'000).last_sample_ns, frames.back()->stamp_ns);
}

TEST(ImageMode, GivenTheCameraLateFaultThenEachFrameArrivesHalfASecondAfterItsExposure) {
  if (const std::string missing = missingCastPhoto(); !missing.empty())
    GTEST_SKIP() << missing << " is missing: install opencv-doc";
  // Given the 10 Hz camera of the test above, late from 0.5 s to 1.5 s after the start (issue 23)
  SimulationOptions options;
  options.faults.camera_late = {0.5, 1.5};
  const TimeNs start_ns = 1'000'000'000;
  std::shared_ptr<Simulation> shared = imageModeSimulation(options, start_ns);
  ASSERT_NE(shared, nullptr);
  SimGimbalCamera camera(shared);
  std::vector<std::pair<TimeNs, TimeNs>> arrivals;  // (exposure, arrival), from the start
  for (TimeNs t = start_ns; t <= start_ns + 2'000'000'000; t += 5'000'000) {
    shared->step(t);
    if (ImageFrameHandle frame = camera.grab(t)) arrivals.emplace_back(frame->stamp_ns - start_ns, t - start_ns);
  }
  // Then before the window each frame arrives at its exposure; in it, the frames exposed from 0.5 s on
  // arrive 500 ms after their exposure (the first at 1.0 s); when it ends the camera delivers its newest
  // exposure again, on time (those still waiting are skipped, as a camera's newest-frame rule does).
  int late = 0;
  for (const auto& [exposure, arrival] : arrivals) {
    if (arrival < 500'000'000 || arrival >= 1'500'000'000) {
      EXPECT_EQ(arrival, exposure) << arrival;
    } else {
      EXPECT_EQ(arrival - exposure, 500'000'000) << arrival;
      EXPECT_GE(arrival, 1'000'000'000);
      ++late;
    }
  }
  EXPECT_EQ(late, 5);  // exposed at 0.5, 0.6, ..., 0.9 s
  EXPECT_EQ(arrivals.back().first, 2'000'000'000);
}

TEST(ImageMode, KeypointModeDeliversNoImages) {
  const auto spec = parseScenarioSpec(scenarioYaml(""), "i.yaml");
  ASSERT_TRUE(spec.has_value());
  auto trial = instantiate(*spec, 1);
  auto sim = Simulation::create(*trial, {}, 0);
  ASSERT_TRUE(sim.has_value());
  std::shared_ptr<Simulation> shared = std::move(sim.value());
  SimGimbalCamera camera(shared);
  int detections = 0;
  for (TimeNs t = 0; t <= 1'000'000'000; t += 5'000'000) {
    shared->step(t);
    EXPECT_EQ(camera.grab(t), nullptr);
    while (camera.grabDetections(t)) ++detections;
  }
  EXPECT_GT(detections, 20);
}

}  // namespace
}  // namespace aerotrack::hal::sim
