// Depth frames as 16-bit millimetre PNGs and their index: a frame comes back rounded to the nearest
// millimetre with no-return pixels (0, NaN, inf, negative, beyond 65.535 m) as 0; a missing frame, a
// truncated PNG, an 8-bit PNG, a frame of the wrong size and a bad index row each give an error naming
// the file (strict) or are skipped and counted; an index cut mid-row (kill -9) reads to its last row.
#include "aerotrack/hal/replay/depth_png.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include <opencv2/imgcodecs.hpp>

#include "temp_dir.hpp"

namespace aerotrack::hal::replay {
namespace {

using test::TempDir;

CameraIntrinsics smallCamera() {
  CameraIntrinsics k;
  k.width_px = 8;
  k.height_px = 6;
  k.fx_px = k.fy_px = 4.0;
  k.cx_px = 4.0;
  k.cy_px = 3.0;
  return k;
}

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
  const std::string path = dir.file(depthFrameFileName(7));
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
  EXPECT_EQ(depthFrameFileName(7), "000007.png");
  EXPECT_EQ(depthFrameFileName(12345678), "12345678.png");
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
  EXPECT_NE(truncated.error().message.find("000003.png: not a readable PNG"), std::string::npos)
      << truncated.error().message;

  ASSERT_TRUE(cv::imwrite(dir.file("000004.png"), cv::Mat(6, 8, CV_8UC1, cv::Scalar(9))));
  const auto eight_bit = readDepthPng(dir.file("000004.png"));
  ASSERT_FALSE(eight_bit);
  EXPECT_NE(eight_bit.error().message.find("000004.png: expected a 16-bit"), std::string::npos);

  EXPECT_FALSE(writeDepthPng(dir.file("000005.png"), cv::Mat(6, 8, CV_8UC1)));  // not metres
  EXPECT_FALSE(writeDepthPng(dir.file("no/such/folder/000006.png"), ramp()));   // cannot write
}

/// An index listing frames 1..n (written), with the given extra text appended.
void writeStream(const TempDir& dir, int n, const std::string& extra = "") {
  auto writer = CsvStreamWriter::create(dir.file("frames.csv"), DepthIndexCodec::columns());
  ASSERT_TRUE(writer);
  for (int i = 1; i <= n; ++i) {
    ASSERT_TRUE(writeDepthPng(dir.file(depthFrameFileName(static_cast<std::uint64_t>(i))), ramp()));
    ASSERT_TRUE(writer->write(i * 66'000'000LL, {static_cast<double>(i)}));
  }
  ASSERT_TRUE(writer->close());
  std::ofstream(dir.file("frames.csv"), std::ios::app) << extra;
}

TEST(DepthStream, GivenAnIndexAndItsFramesThenEveryFrameLoadsWithTheManifestsCamera) {
  TempDir dir;
  writeStream(dir, 4, "330000000,5");  // a last row without its newline: a killed recorder's
  std::filesystem::remove(dir.file(depthFrameFileName(5)));
  Eigen::Isometry3d T_BC = Eigen::Isometry3d::Identity();
  T_BC.translation() = Eigen::Vector3d(0.1, 0.0, 0.05);
  const auto stream = loadDepthStream(dir.file("frames.csv"), smallCamera(), T_BC, BadRowPolicy::kStrict);
  ASSERT_TRUE(stream) << stream.error().message;
  ASSERT_EQ(stream->frames.size(), 4U);
  EXPECT_TRUE(stream->truncated_tail);
  for (std::size_t i = 0; i < 4; ++i) {
    const DepthFrame& f = stream->frames[i];
    EXPECT_EQ(f.stamp_ns, static_cast<rt::TimeNs>(i + 1) * 66'000'000LL);
    EXPECT_EQ(f.sequence, i + 1);
    EXPECT_EQ(f.intrinsics.width_px, 8);
    EXPECT_TRUE(f.T_BC.isApprox(T_BC));
    EXPECT_NEAR(f.depth_m.at<float>(1, 2), 0.3137 + 0.9871 * 10, 1e-3);
  }
}

TEST(DepthStream, GivenAMissingFrameAWrongSizeAndABadRowThenStrictStopsAndSkipCounts) {
  TempDir dir;
  writeStream(dir, 5, "400000000,oops\n");
  std::filesystem::remove(dir.file(depthFrameFileName(2)));
  ASSERT_TRUE(writeDepthPng(dir.file(depthFrameFileName(4)), cv::Mat(3, 4, CV_32FC1, cv::Scalar(1.0F))));
  const auto strict =
      loadDepthStream(dir.file("frames.csv"), smallCamera(), Eigen::Isometry3d::Identity(), BadRowPolicy::kStrict);
  ASSERT_FALSE(strict);
  EXPECT_NE(strict.error().message.find("frames.csv:3: "), std::string::npos) << strict.error().message;
  EXPECT_NE(strict.error().message.find("000002.png: missing depth frame"), std::string::npos);

  const auto skip =
      loadDepthStream(dir.file("frames.csv"), smallCamera(), Eigen::Isometry3d::Identity(), BadRowPolicy::kSkip);
  ASSERT_TRUE(skip) << skip.error().message;
  ASSERT_EQ(skip->frames.size(), 3U);  // 1, 3, 5
  EXPECT_EQ(skip->frames[1].sequence, 3U);
  EXPECT_EQ(skip->skipped_rows, 3U);  // frame 2 missing, frame 4 the wrong size, the "oops" row
  EXPECT_NE(skip->first_skip_message.find("000002.png"), std::string::npos) << skip->first_skip_message;
}

}  // namespace
}  // namespace aerotrack::hal::replay
