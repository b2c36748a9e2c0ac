// Camera frame files: a depth frame comes back rounded to the nearest millimetre with no-return pixels
// (0, NaN, inf, negative, beyond 65.535 m) as 0; a missing, truncated or 8-bit depth PNG is an error
// naming the file; images come back exactly from PNG and closely from JPEG.
#include "aerotrack/hal/replay/frame_files.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "support/temp_dir.hpp"

namespace aerotrack::hal::replay {
namespace {

using test::TempDir;

cv::Mat ramp() {
  cv::Mat depth_m(6, 8, CV_32FC1);
  for (int v = 0; v < depth_m.rows; ++v)
    for (int u = 0; u < depth_m.cols; ++u) depth_m.at<float>(v, u) = 0.3137F + 0.9871F * static_cast<float>(u + 8 * v);
  return depth_m;
}

TEST(DepthPng, GivenAFrameThenItReadsBackRoundedToTheMillimetreWithNoReturnsAsZero) {
  TempDir dir;
  cv::Mat depth_m = ramp();
  depth_m.at<float>(0, 0) = 0.0F;
  depth_m.at<float>(0, 1) = std::numeric_limits<float>::quiet_NaN();
  depth_m.at<float>(0, 2) = std::numeric_limits<float>::infinity();
  depth_m.at<float>(0, 3) = -1.0F;
  depth_m.at<float>(0, 4) = 70.0F;  // beyond 65.535 m
  const std::string path = dir.file(frameFileName(7, "png"));
  ASSERT_TRUE(writeDepthPng(path, depth_m));
  EXPECT_FALSE(std::filesystem::exists(path + ".part"));
  const auto back = readDepthPng(path);
  ASSERT_TRUE(back) << back.error().message;
  ASSERT_EQ(back->type(), CV_32FC1);
  for (int u = 0; u <= 4; ++u) EXPECT_EQ(back->at<float>(0, u), 0.0F) << u;
  for (int v = 0; v < 6; ++v)
    for (int u = (v == 0 ? 5 : 0); u < 8; ++u) {
      const double expected_mm = std::round(static_cast<double>(depth_m.at<float>(v, u)) * 1000.0);
      EXPECT_FLOAT_EQ(back->at<float>(v, u), static_cast<float>(expected_mm * 1e-3)) << u << "," << v;
    }
  EXPECT_EQ(frameFileName(7, "png"), "000007.png");
  EXPECT_EQ(frameFileName(12345678, "png"), "12345678.png");
}

TEST(DepthPng, GivenBadFilesThenEachErrorNamesTheFile) {
  TempDir dir;
  const auto missing = readDepthPng(dir.file("000001.png"));
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("000001.png: missing"), std::string::npos) << missing.error().message;

  const std::string good = dir.file("000002.png");
  ASSERT_TRUE(writeDepthPng(good, ramp()));
  const auto size = std::filesystem::file_size(good);
  std::filesystem::copy_file(good, dir.file("000003.png"));
  std::filesystem::resize_file(dir.file("000003.png"), size / 2);  // a copy cut in the middle
  const auto truncated = readDepthPng(dir.file("000003.png"));
  ASSERT_FALSE(truncated);
  EXPECT_NE(truncated.error().message.find("000003.png: the PNG data is truncated"), std::string::npos)
      << truncated.error().message;

  ASSERT_TRUE(cv::imwrite(dir.file("000004.png"), cv::Mat(6, 8, CV_8UC1, cv::Scalar(9))));
  const auto eight_bit = readDepthPng(dir.file("000004.png"));
  ASSERT_FALSE(eight_bit);
  EXPECT_NE(eight_bit.error().message.find("000004.png: expected a 16-bit"), std::string::npos);

  EXPECT_FALSE(writeDepthPng(dir.file("000005.png"), cv::Mat(6, 8, CV_8UC1)));  // not metres
  EXPECT_FALSE(writeDepthPng(dir.file("no/such/folder/000006.png"), ramp()));   // cannot write
}

TEST(FrameImages, PngIsLosslessJpegIsCloseAndBadFilesNameTheFile) {
  TempDir dir;
  cv::Mat bgr(48, 64, CV_8UC3);
  cv::randu(bgr, cv::Scalar::all(0), cv::Scalar::all(255));
  cv::GaussianBlur(bgr, bgr, cv::Size(5, 5), 1.5);  // photo-like: JPEG keeps it close
  ASSERT_TRUE(writeImage(dir.file(frameFileName(1, "png")), bgr));
  ASSERT_TRUE(writeImage(dir.file(frameFileName(2, "jpg")), bgr));
  const auto png = readImage(dir.file("000001.png"));
  ASSERT_TRUE(png) << png.error().message;
  EXPECT_EQ(cv::norm(*png, bgr, cv::NORM_INF), 0.0);
  const auto jpg = readImage(dir.file("000002.jpg"));
  ASSERT_TRUE(jpg) << jpg.error().message;
  EXPECT_LT(cv::norm(*jpg, bgr, cv::NORM_L1) / static_cast<double>(bgr.total() * 3), 4.0);  // mean error, levels
  EXPECT_FALSE(writeImage(dir.file("000003.png"), cv::Mat(4, 4, CV_32FC1)));                // not 8-bit BGR
  std::filesystem::resize_file(dir.file("000002.jpg"), 100);
  const auto cut = readImage(dir.file("000002.jpg"));
  EXPECT_FALSE(cut && cut->rows == 48 && cv::norm(*cut, bgr, cv::NORM_L1) < 1e3);  // unreadable or visibly broken
  const auto missing = readImage(dir.file("000009.png"));
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("000009.png: missing"), std::string::npos);
}

}  // namespace
}  // namespace aerotrack::hal::replay
