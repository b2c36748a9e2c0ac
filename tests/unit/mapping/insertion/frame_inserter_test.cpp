// Tests of FrameInserter: a frame between two odometry samples is inserted at the interpolated
// camera pose T_WC = T_WB(stamp) * T_BC (hand-computed hit voxel); frames without a pose are
// skipped, counted and reported with the reason; malformed frames are errors.
#include "aerotrack/mapping/frame_inserter.hpp"

#include <cstring>

#include <gtest/gtest.h>

namespace aerotrack::mapping {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr rt::DurationNs kMs = rt::kNsPerMillisecond;

hal::OdometrySample sample(rt::TimeNs stamp_ns, const Eigen::Vector3d& p_WB_m, double yaw_rad) {
  hal::OdometrySample s;
  s.stamp_ns = stamp_ns;
  s.p_WB_m = p_WB_m;
  s.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()));
  return s;
}

/// 160 x 120, fx = fy = 100, principal point (80.5, 60.5): pixel (80, 60) looks along the
/// optical axis. Camera forward along body x (z_C = x_B, x_C = -y_B, y_C = -z_B), no offset.
hal::DepthFrame axisFrame(rt::TimeNs stamp_ns, float axis_depth_m) {
  hal::DepthFrame frame;
  frame.stamp_ns = stamp_ns;
  frame.intrinsics.width_px = 160;
  frame.intrinsics.height_px = 120;
  frame.intrinsics.fx_px = 100.0;
  frame.intrinsics.fy_px = 100.0;
  frame.intrinsics.cx_px = 80.5;
  frame.intrinsics.cy_px = 60.5;
  frame.depth_m = cv::Mat::zeros(120, 160, CV_32FC1);
  frame.depth_m.at<float>(60, 80) = axis_depth_m;
  frame.T_BC.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return frame;
}

DepthPointsParams everyPixel() {
  DepthPointsParams params;
  params.decimation = 1;
  return params;
}

struct Fixture {
  PoseHistory poses = PoseHistory::create({}).value();
  OctomapMap map = OctomapMap::create().value();
  FrameInserter inserter = FrameInserter::create(everyPixel()).value();
};

TEST(FrameInserter, GivenInvalidParams_WhenCreate_ThenError) {
  DepthPointsParams params;
  params.max_range_m = 0.1;
  EXPECT_FALSE(FrameInserter::create(params).has_value());
}

TEST(FrameInserter, GivenFrameBetweenTwoPoses_WhenInserted_ThenHitAtInterpolatedCameraPose) {
  Fixture f;
  // Body at x = 0 then x = 2 (20 ms later), 1.55 m up, yaw 90 deg (facing +y) throughout.
  (void)f.poses.push(sample(0, {0.05, 0.05, 1.55}, kPi / 2));
  (void)f.poses.push(sample(20 * kMs, {2.05, 0.05, 1.55}, kPi / 2));
  // At 10 ms the body is at (1.05, 0.05, 1.55) facing +y: the 3 m axis hit is (1.05, 3.05, 1.55).
  const FrameInsertReport report = f.inserter.insert(axisFrame(10 * kMs, 3.0F), f.poses, f.map).value();
  EXPECT_EQ(report.status, FrameInsertStatus::kInserted);
  EXPECT_EQ(report.points.hits, 1U);
  EXPECT_EQ(report.insert.occupied_voxels, 1U);
  const octomap::OcTreeNode* hit = f.map.tree().search(1.05, 3.05, 1.55);
  ASSERT_NE(hit, nullptr);
  EXPECT_TRUE(f.map.tree().isNodeOccupied(hit));
  const octomap::OcTreeNode* between = f.map.tree().search(1.05, 1.55, 1.55);
  ASSERT_NE(between, nullptr);
  EXPECT_FALSE(f.map.tree().isNodeOccupied(between));
  EXPECT_EQ(f.map.occupiedVoxelCount(), 1U);
  EXPECT_EQ(f.inserter.framesInserted(), 1U);
  EXPECT_EQ(f.map.framesInserted(), 1U);
}

TEST(FrameInserter, GivenNoPoseAtCaptureTime_WhenInserted_ThenSkippedCountedAndWhy) {
  Fixture f;
  FrameInsertReport report = f.inserter.insert(axisFrame(5 * kMs, 3.0F), f.poses, f.map).value();
  EXPECT_EQ(report.status, FrameInsertStatus::kSkippedNoPose);
  EXPECT_EQ(report.pose_status, PoseLookupStatus::kEmpty);
  EXPECT_STREQ(toString(report.status), "depth frame skipped: no pose at its capture time");

  (void)f.poses.push(sample(0, {0.0, 0.0, 1.0}, 0.0));
  (void)f.poses.push(sample(10 * kMs, {0.1, 0.0, 1.0}, 0.0));
  // 20 ms after the newest odometry: not extrapolated.
  report = f.inserter.insert(axisFrame(30 * kMs, 3.0F), f.poses, f.map).value();
  EXPECT_EQ(report.status, FrameInsertStatus::kSkippedNoPose);
  EXPECT_EQ(report.pose_status, PoseLookupStatus::kAfterNewest);
  report = f.inserter.insert(axisFrame(-1, 3.0F), f.poses, f.map).value();
  EXPECT_EQ(report.pose_status, PoseLookupStatus::kBeforeOldest);

  EXPECT_EQ(f.inserter.framesSkippedNoPose(), 3U);
  EXPECT_EQ(f.inserter.framesInserted(), 0U);
  EXPECT_EQ(f.map.framesInserted(), 0U);
  EXPECT_EQ(f.map.tree().size(), 0U);
}

TEST(FrameInserter, GivenMalformedFrame_WhenInserted_ThenErrorCountedAndMapUnchanged) {
  Fixture f;
  (void)f.poses.push(sample(0, {0.0, 0.0, 1.0}, 0.0));
  hal::DepthFrame frame = axisFrame(0, 3.0F);
  frame.intrinsics.width_px = 100;  // Disagrees with the image.
  const rt::Expected<FrameInsertReport> result = f.inserter.insert(frame, f.poses, f.map);
  EXPECT_FALSE(result.has_value());
  EXPECT_EQ(f.inserter.framesInvalid(), 1U);
  EXPECT_EQ(f.map.tree().size(), 0U);
}

}  // namespace
}  // namespace aerotrack::mapping
