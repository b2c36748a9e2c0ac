// Tests of depthToPoints: back-projection of hand-computed pixels (pixel centre u + 0.5 =
// cx + fx x / z), the world transform, pixels ignored (no data, too near), misses at max range
// measured along the ray, decimation counts, memory reuse and input validation.
#include "aerotrack/mapping/depth_points.hpp"

#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

namespace aerotrack::mapping {
namespace {

constexpr double kTolM = 1e-5;  // Points are stored as float.

/// 160 x 120 frame, fx = 100, fy = 120, principal point (80.5, 60.5): the centre of pixel
/// (80, 60) is on the optical axis. All pixels 0 (no data).
hal::DepthFrame makeFrame(int width_px = 160, int height_px = 120) {
  hal::DepthFrame frame;
  frame.intrinsics.width_px = width_px;
  frame.intrinsics.height_px = height_px;
  frame.intrinsics.fx_px = 100.0;
  frame.intrinsics.fy_px = 120.0;
  frame.intrinsics.cx_px = 80.5;
  frame.intrinsics.cy_px = 60.5;
  frame.depth_m = cv::Mat::zeros(height_px, width_px, CV_32FC1);
  return frame;
}

DepthPointsParams everyPixel() {
  DepthPointsParams params;
  params.decimation = 1;
  return params;
}

Eigen::Vector3d at(const octomap::Pointcloud& cloud, std::size_t i) {
  const octomap::point3d& p = cloud[i];
  return Eigen::Vector3f(p.x(), p.y(), p.z()).cast<double>();
}

TEST(DepthPoints, GivenInvalidParams_WhenValidate_ThenError) {
  DepthPointsParams params;
  params.decimation = 0;
  EXPECT_FALSE(validate(params).has_value());
  params = {};
  params.min_range_m = 6.0;
  EXPECT_FALSE(validate(params).has_value());
  params = {};
  params.max_range_m = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(validate(params).has_value());
  params = {};
  params.min_range_m = -0.1;
  EXPECT_FALSE(validate(params).has_value());
  EXPECT_TRUE(validate(DepthPointsParams{}).has_value());
}

TEST(DepthPoints, GivenOnePixelAtKnownDepth_WhenConvert_ThenHitAtHandComputedCameraPoint) {
  hal::DepthFrame frame = makeFrame();
  // Pixel (104, 30) at z = 2: x = (104.5 - 80.5) * 2 / 100 = 0.48, y = (30.5 - 60.5) * 2 / 120 = -0.5.
  frame.depth_m.at<float>(30, 104) = 2.0F;
  octomap::Pointcloud hits;
  octomap::Pointcloud misses;
  const DepthPointsStats stats =
      depthToPoints(frame, Eigen::Isometry3d::Identity(), everyPixel(), hits, misses).value();
  ASSERT_EQ(hits.size(), 1U);
  EXPECT_EQ(misses.size(), 0U);
  EXPECT_EQ(stats.hits, 1U);
  EXPECT_EQ(stats.pixels_visited, 160U * 120U);
  EXPECT_EQ(stats.no_data, 160U * 120U - 1U);
  const Eigen::Vector3d p_C = at(hits, 0);
  EXPECT_NEAR(p_C.x(), 0.48, kTolM);
  EXPECT_NEAR(p_C.y(), -0.5, kTolM);
  EXPECT_NEAR(p_C.z(), 2.0, kTolM);
  // And it projects back onto the pixel's centre: u + 0.5 = cx + fx x / z.
  EXPECT_NEAR(80.5 + 100.0 * p_C.x() / p_C.z(), 104.5, 1e-4);
  EXPECT_NEAR(60.5 + 120.0 * p_C.y() / p_C.z(), 30.5, 1e-4);
}

TEST(DepthPoints, GivenCameraPose_WhenConvert_ThenPointInWorld) {
  hal::DepthFrame frame = makeFrame();
  frame.depth_m.at<float>(30, 104) = 2.0F;  // p_C = (0.48, -0.5, 2) as above.
  // Camera at (1, 2, 3) looking along world +x: z_C = x_W, x_C = -y_W, y_C = -z_W.
  Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();
  T_WC.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  T_WC.translation() = Eigen::Vector3d(1.0, 2.0, 3.0);
  octomap::Pointcloud hits;
  octomap::Pointcloud misses;
  (void)depthToPoints(frame, T_WC, everyPixel(), hits, misses).value();
  ASSERT_EQ(hits.size(), 1U);
  EXPECT_TRUE(at(hits, 0).isApprox(Eigen::Vector3d(1.0 + 2.0, 2.0 - 0.48, 3.0 + 0.5), kTolM));
}

TEST(DepthPoints, GivenInvalidAndTooNearPixels_WhenConvert_ThenIgnoredAndCounted) {
  hal::DepthFrame frame = makeFrame();
  frame.depth_m.at<float>(0, 0) = std::numeric_limits<float>::quiet_NaN();
  frame.depth_m.at<float>(0, 1) = std::numeric_limits<float>::infinity();
  frame.depth_m.at<float>(0, 2) = -std::numeric_limits<float>::infinity();
  frame.depth_m.at<float>(0, 3) = -1.0F;
  frame.depth_m.at<float>(60, 80) = 0.29F;  // On the axis: range 0.29 < 0.3.
  frame.depth_m.at<float>(60, 81) = 0.31F;  // Range just above 0.3: kept.
  octomap::Pointcloud hits;
  octomap::Pointcloud misses;
  const DepthPointsStats stats =
      depthToPoints(frame, Eigen::Isometry3d::Identity(), everyPixel(), hits, misses).value();
  EXPECT_EQ(stats.too_near, 1U);
  EXPECT_EQ(stats.hits, 1U);
  EXPECT_EQ(stats.misses, 0U);
  EXPECT_EQ(stats.no_data, 160U * 120U - 2U);
  ASSERT_EQ(hits.size(), 1U);
  EXPECT_NEAR(at(hits, 0).z(), 0.31, kTolM);
}

TEST(DepthPoints, GivenPixelsBeyondMaxRange_WhenConvert_ThenMissesOnTheRayAtMaxRange) {
  hal::DepthFrame frame = makeFrame();
  // On the axis at z = 10: a miss at (0, 0, 6).
  frame.depth_m.at<float>(60, 80) = 10.0F;
  // Pixel (155, 60): ray (0.75, 0, 1), |ray| = 1.25. z = 4.9 is range 6.125 > 6: a miss at
  // range 6, (0.75, 0, 1) * 6 / 1.25 = (3.6, 0, 4.8), though its depth is below 6.
  frame.depth_m.at<float>(60, 155) = 4.9F;
  // Same ray, z = 4.7: range 5.875 <= 6: a hit at (3.525, 0, 4.7).
  frame.depth_m.at<float>(61, 155) = 4.7F;  // Row 61: y = 1 / 120 * 4.7.
  octomap::Pointcloud hits;
  octomap::Pointcloud misses;
  const DepthPointsStats stats =
      depthToPoints(frame, Eigen::Isometry3d::Identity(), everyPixel(), hits, misses).value();
  EXPECT_EQ(stats.misses, 2U);
  EXPECT_EQ(stats.hits, 1U);
  ASSERT_EQ(misses.size(), 2U);
  ASSERT_EQ(hits.size(), 1U);
  EXPECT_TRUE(at(misses, 0).isApprox(Eigen::Vector3d(0.0, 0.0, 6.0), kTolM));
  EXPECT_TRUE(at(misses, 1).isApprox(Eigen::Vector3d(3.6, 0.0, 4.8), kTolM));
  EXPECT_NEAR(at(misses, 1).norm(), 6.0, kTolM);
  EXPECT_TRUE(at(hits, 0).isApprox(Eigen::Vector3d(3.525, 4.7 / 120.0, 4.7), kTolM));
}

TEST(DepthPoints, GivenDecimation_WhenConvert_ThenEveryNthPixelFromTheCorner) {
  hal::DepthFrame frame = makeFrame();
  frame.depth_m.setTo(3.0);
  octomap::Pointcloud hits;
  octomap::Pointcloud misses;
  DepthPointsParams params;  // decimation 4: 40 x 30.
  DepthPointsStats stats = depthToPoints(frame, Eigen::Isometry3d::Identity(), params, hits, misses).value();
  EXPECT_EQ(stats.pixels_visited, 1200U);
  EXPECT_EQ(hits.size(), 1200U);
  // First point: pixel (0, 0); second: pixel (4, 0).
  EXPECT_NEAR(at(hits, 0).x(), (0.5 - 80.5) * 3.0 / 100.0, kTolM);
  EXPECT_NEAR(at(hits, 0).y(), (0.5 - 60.5) * 3.0 / 120.0, kTolM);
  EXPECT_NEAR(at(hits, 1).x(), (4.5 - 80.5) * 3.0 / 100.0, kTolM);
  // Row 1 of the decimated grid is pixel row 4.
  EXPECT_NEAR(at(hits, 40).y(), (4.5 - 60.5) * 3.0 / 120.0, kTolM);

  params.decimation = 7;  // ceil(160 / 7) * ceil(120 / 7) = 23 * 18.
  stats = depthToPoints(frame, Eigen::Isometry3d::Identity(), params, hits, misses).value();
  EXPECT_EQ(stats.pixels_visited, 23U * 18U);
  EXPECT_EQ(hits.size(), 23U * 18U);

  hal::DepthFrame big = makeFrame(640, 480);  // 640 x 480 at 16: the same 40 x 30 points.
  big.depth_m.setTo(3.0);
  params.decimation = 16;
  stats = depthToPoints(big, Eigen::Isometry3d::Identity(), params, hits, misses).value();
  EXPECT_EQ(stats.pixels_visited, 1200U);
  EXPECT_EQ(hits.size() + misses.size(), 1200U);  // Oblique corner rays reach past 6 m.
}

TEST(DepthPoints, GivenCloudsFromAPreviousFrame_WhenConvertAgain_ThenClearedAndMemoryReused) {
  hal::DepthFrame frame = makeFrame();
  frame.depth_m.setTo(3.0);
  frame.depth_m.at<float>(0, 0) = 50.0F;
  octomap::Pointcloud hits;
  octomap::Pointcloud misses;
  (void)depthToPoints(frame, Eigen::Isometry3d::Identity(), {}, hits, misses).value();
  ASSERT_EQ(hits.size(), 1199U);
  ASSERT_EQ(misses.size(), 1U);
  const octomap::point3d* hits_data = &*hits.begin();
  const octomap::point3d* misses_data = &*misses.begin();
  (void)depthToPoints(frame, Eigen::Isometry3d::Identity(), {}, hits, misses).value();
  EXPECT_EQ(hits.size(), 1199U);  // Not 2398: cleared first.
  EXPECT_EQ(misses.size(), 1U);
  EXPECT_EQ(&*hits.begin(), hits_data);  // Same buffers.
  EXPECT_EQ(&*misses.begin(), misses_data);
}

TEST(DepthPoints, GivenMalformedFrameOrPose_WhenConvert_ThenErrorAndNoPoints) {
  octomap::Pointcloud hits;
  octomap::Pointcloud misses;
  hits.push_back(1.0F, 2.0F, 3.0F);
  hal::DepthFrame frame = makeFrame();
  frame.depth_m.setTo(3.0);

  hal::DepthFrame wrong_type = frame;
  wrong_type.depth_m = cv::Mat::zeros(120, 160, CV_64FC1);
  EXPECT_FALSE(depthToPoints(wrong_type, Eigen::Isometry3d::Identity(), {}, hits, misses).has_value());
  EXPECT_EQ(hits.size(), 0U);

  hal::DepthFrame wrong_size = frame;
  wrong_size.intrinsics.width_px = 320;
  EXPECT_FALSE(depthToPoints(wrong_size, Eigen::Isometry3d::Identity(), {}, hits, misses).has_value());

  hal::DepthFrame empty = frame;
  empty.depth_m = cv::Mat();
  EXPECT_FALSE(depthToPoints(empty, Eigen::Isometry3d::Identity(), {}, hits, misses).has_value());

  hal::DepthFrame zero_focal = frame;
  zero_focal.intrinsics.fx_px = 0.0;
  EXPECT_FALSE(depthToPoints(zero_focal, Eigen::Isometry3d::Identity(), {}, hits, misses).has_value());

  Eigen::Isometry3d T_nan = Eigen::Isometry3d::Identity();
  T_nan.translation().x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(depthToPoints(frame, T_nan, {}, hits, misses).has_value());

  DepthPointsParams bad;
  bad.decimation = 0;
  const rt::Expected<DepthPointsStats> result = depthToPoints(frame, Eigen::Isometry3d::Identity(), bad, hits, misses);
  ASSERT_FALSE(result.has_value());
  EXPECT_NE(result.error().message.find("decimation"), std::string::npos);
  EXPECT_EQ(hits.size(), 0U);
  EXPECT_EQ(misses.size(), 0U);
}

TEST(DepthPoints, GivenAReturnInsideAnExcludedBody_WhenConvert_ThenItIsAMissAtTheReturn) {
  // Two pixels 2 m ahead of a camera at (1, 2, 3) looking along world +x: (104, 30) lands at
  // (3, 1.52, 3.5) as in GivenCameraPose, and (56, 30) at (3, 2.48, 3.5).
  hal::DepthFrame frame = makeFrame();
  frame.depth_m.at<float>(30, 104) = 2.0F;
  frame.depth_m.at<float>(30, 56) = 2.0F;
  Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();
  T_WC.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  T_WC.translation() = Eigen::Vector3d(1.0, 2.0, 3.0);
  // A person's column around (3, 1.5), 0.1 m wide: takes the first; the second is 0.98 m from its axis.
  const std::vector<ExcludedBody> person{{Eigen::Vector2d(3.0, 1.5), 0.1, 0.0, 4.0}};
  octomap::Pointcloud hits;
  octomap::Pointcloud misses;
  const DepthPointsStats stats = depthToPoints(frame, T_WC, everyPixel(), hits, misses, person).value();
  EXPECT_EQ(stats.excluded, 1U);
  EXPECT_EQ(stats.hits, 1U);
  ASSERT_EQ(misses.size(), 1U);
  EXPECT_TRUE(at(misses, 0).isApprox(Eigen::Vector3d(3.0, 1.52, 3.5), kTolM));  // the ray ends at the return
  ASSERT_EQ(hits.size(), 1U);
  EXPECT_TRUE(at(hits, 0).isApprox(Eigen::Vector3d(3.0, 2.48, 3.5), kTolM));
  // Above the column's top, the same return is an obstacle again (a ceiling over the person).
  const std::vector<ExcludedBody> short_person{{Eigen::Vector2d(3.0, 1.5), 0.1, 0.0, 3.4}};
  const DepthPointsStats above = depthToPoints(frame, T_WC, everyPixel(), hits, misses, short_person).value();
  EXPECT_EQ(above.excluded, 0U);
  EXPECT_EQ(above.hits, 2U);
  // Below the column's foot, too (the ground under the person).
  const std::vector<ExcludedBody> raised{{Eigen::Vector2d(3.0, 1.5), 0.1, 3.6, 5.0}};
  EXPECT_EQ(depthToPoints(frame, T_WC, everyPixel(), hits, misses, raised).value().excluded, 0U);
  // A body of no width excludes nothing.
  const std::vector<ExcludedBody> nobody{{Eigen::Vector2d(3.0, 1.52), 0.0, 0.0, 4.0}};
  EXPECT_EQ(depthToPoints(frame, T_WC, everyPixel(), hits, misses, nobody).value().excluded, 0U);
}

}  // namespace
}  // namespace aerotrack::mapping
