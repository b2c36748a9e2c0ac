// Video import (hal/replay/video_import.hpp) on a small video written here: the dataset holds every
// frame (as the decoder gives it, JPEG-close), stamped at index / fps from the chosen start, with the
// stated pinhole camera; it replays through the replay camera; a folder holding a recording, a missing
// or undecodable video and a bad field of view are one-line errors.
#include "aerotrack/hal/replay/video_import.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "aerotrack/hal/replay/manifest.hpp"
#include "aerotrack/hal/replay/replay_devices.hpp"
#include "support/temp_dir.hpp"

namespace aerotrack::hal::replay {
namespace {

/// 12 frames of 64 x 48 at 8 fps, frame i a bar at column 4 i.
std::string writeVideo(const test::TempDir& dir) {
  const std::string path = dir.file("in.avi");
  cv::VideoWriter writer(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 8.0, cv::Size(64, 48));
  EXPECT_TRUE(writer.isOpened());
  for (int i = 0; i < 12; ++i) {
    cv::Mat frame(48, 64, CV_8UC3, cv::Scalar(30, 30, 30));
    cv::rectangle(frame, cv::Rect(4 * i, 0, 4, 48), cv::Scalar(255, 255, 255), cv::FILLED);
    writer.write(frame);
  }
  return path;
}

/// The column of the bright bar in an image.
int barColumn(const cv::Mat& bgr) {
  cv::Mat gray;
  cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
  cv::Mat column_sums;
  cv::reduce(gray, column_sums, 0, cv::REDUCE_SUM, CV_64F);
  cv::Point max_at;
  cv::minMaxLoc(column_sums, nullptr, nullptr, nullptr, &max_at);
  return max_at.x;
}

TEST(VideoImport, EveryFrameStampedWithTheStatedCameraAndReplayable) {
  test::TempDir dir;
  VideoImportOptions options;
  options.video = writeVideo(dir);
  options.dir = dir.file("rec");
  options.hfov_deg = 90.0;
  options.start_s = 0.25;  // skips two frames at 8 fps
  const auto report = importVideo(options);
  ASSERT_TRUE(report) << report.error().message;
  EXPECT_EQ(report->frames, 10U);
  EXPECT_DOUBLE_EQ(report->fps, 8.0);
  EXPECT_NEAR(report->intrinsics.fx_px, 32.0, 1e-9);  // half the width over tan(45 deg)
  EXPECT_EQ(report->intrinsics.fy_px, report->intrinsics.fx_px);
  EXPECT_EQ(report->intrinsics.cy_px, 24.0);

  const auto manifest = readManifest(dir.file("rec/manifest.yaml"));
  ASSERT_TRUE(manifest) << manifest.error().message;
  EXPECT_EQ(manifest->source, "import");
  ASSERT_TRUE(manifest->gimbal_camera.has_value());
  EXPECT_EQ(manifest->gimbal_camera->image_format, "jpg");

  ReplayOptions replay;
  replay.dir = options.dir;
  replay.bad_rows = BadRowPolicy::kStrict;
  auto dataset = ReplayDataset::open(replay, 0);
  ASSERT_TRUE(dataset) << dataset.error().message;
  ReplayGimbalCamera camera(*dataset);
  int served = 0;
  for (rt::TimeNs t = 0; t <= rt::secondsToNs(1.25); t += rt::kNsPerSecond / 60) {
    const ImageFrameHandle frame = camera.grab(t);
    if (!frame) continue;
    EXPECT_EQ(frame->stamp_ns, static_cast<rt::TimeNs>(served) * 125'000'000);
    EXPECT_EQ(frame->sequence, static_cast<std::uint64_t>(served + 2));  // the video's frame index
    EXPECT_NEAR(barColumn(frame->bgr), 4 * (served + 2) + 1.5, 2.0) << served;
    ++served;
  }
  EXPECT_EQ(served, 10);
}

TEST(VideoImport, BadInputsAreOneLineErrors) {
  test::TempDir dir;
  VideoImportOptions options;
  options.video = writeVideo(dir);
  options.dir = dir.file("rec");
  options.hfov_deg = 0.0;
  auto bad_fov = importVideo(options);
  ASSERT_FALSE(bad_fov);
  EXPECT_NE(bad_fov.error().message.find("field of view"), std::string::npos);
  options.hfov_deg = 60.0;
  options.max_frames = 3;
  ASSERT_TRUE(importVideo(options));
  auto again = importVideo(options);
  ASSERT_FALSE(again);
  EXPECT_NE(again.error().message.find("already holds a recording"), std::string::npos);
  options.dir = dir.file("rec2");
  options.video = dir.file("missing.avi");
  auto missing = importVideo(options);
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("missing.avi: no such file"), std::string::npos);
  std::ofstream(dir.file("garbage.avi")) << std::string(4000, 'x');
  options.video = dir.file("garbage.avi");
  auto garbage = importVideo(options);
  ASSERT_FALSE(garbage);
  EXPECT_FALSE(std::filesystem::exists(dir.file("rec2/manifest.yaml")));  // no recording left behind
}

}  // namespace
}  // namespace aerotrack::hal::replay
