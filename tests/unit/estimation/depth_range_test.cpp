// Tests of the depth camera's range along a line of sight (depth_range.hpp): against the analytic crossing of a
// flat wall from random lines (the march's refinement is exact on a plane), a person in front of a wall, an
// occluder between the depth camera and the line, a line out of view, bad images and bad parameters.
#include "aerotrack/estimation/depth_range.hpp"

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

namespace aerotrack::estimation {
namespace {

/// 160 x 120, fx = fy = 80, principal point at the centre; every pixel at `z_m`.
hal::DepthFrame wallAt(double z_m) {
  hal::DepthFrame frame;
  frame.intrinsics.width_px = 160;
  frame.intrinsics.height_px = 120;
  frame.intrinsics.fx_px = 80.0;
  frame.intrinsics.fy_px = 80.0;
  frame.intrinsics.cx_px = 80.0;
  frame.intrinsics.cy_px = 60.0;
  frame.depth_m = cv::Mat(120, 160, CV_32FC1, cv::Scalar(z_m));
  return frame;
}

DepthRangeParams params() {
  DepthRangeParams p;
  p.enabled = true;
  return p;
}

// The depth camera at the origin of W looking along +z (its optical frame is W).
const Eigen::Isometry3d kT_WD = Eigen::Isometry3d::Identity();

TEST(DepthRange, GivenAFlatWallThenTheRangeIsWhereTheLineCrossesIt) {
  const hal::DepthFrame wall = wallAt(4.0);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> offset(-0.3, 0.3);
  std::uniform_real_distribution<double> slope(-0.4, 0.4);
  for (int trial = 0; trial < 200; ++trial) {
    // A camera beside the depth camera (as a gimbal camera is) looking roughly the same way.
    const Eigen::Vector3d origin(offset(rng), offset(rng), offset(rng));
    const Eigen::Vector3d dir = Eigen::Vector3d(slope(rng), slope(rng), 1.0).normalized();
    const DepthSurface surface = surfaceAlongLine(wall, kT_WD, origin, dir, params());
    ASSERT_EQ(surface.status, DepthRangeStatus::kFound) << trial;
    const double expected_m = (4.0 - origin.z()) / dir.z();  // the slow, obvious answer: the plane's crossing
    EXPECT_NEAR(surface.range_m, expected_m, 1e-4) << trial;
  }
}

TEST(DepthRange, GivenAPersonInFrontOfAWallThenTheLineThroughThemFindsTheirFront) {
  hal::DepthFrame frame = wallAt(6.0);
  // A person 3 m ahead covering the middle columns (a 0.5 m wide body at 3 m: 13 px).
  frame.depth_m(cv::Rect(74, 30, 13, 60)) = 3.0;
  const Eigen::Vector3d origin(0.1, -0.05, 0.0);  // the gimbal camera, 10 cm to the side
  const Eigen::Vector3d dir = (Eigen::Vector3d(0.0, 0.0, 3.0) - origin).normalized();
  const DepthSurface surface = surfaceAlongLine(frame, kT_WD, origin, dir, params());
  ASSERT_EQ(surface.status, DepthRangeStatus::kFound);
  EXPECT_NEAR(surface.range_m, (Eigen::Vector3d(0.0, 0.0, 3.0) - origin).norm(), 0.01);
  // The body's centre lies body_offset_m behind their front, horizontally along the line (here x-z is level: W's
  // "horizontal" is x-y, so use a level line for the centre).
  DepthRangeParams p = params();
  p.body_offset_m = 0.25;
  const Eigen::Vector2d centre = bodyCentreBehind(Eigen::Vector3d::Zero(), Eigen::Vector3d(0.6, 0.8, 0.0), 5.0, p);
  EXPECT_TRUE(centre.isApprox(Eigen::Vector2d(0.6 * 5.25, 0.8 * 5.25)));
}

TEST(DepthRange, GivenSomethingBetweenTheDepthCameraAndTheLineThenOccluded) {
  hal::DepthFrame frame = wallAt(6.0);
  // The line x = 0.3 m projects to u = 80 + 80 * 0.3 / z: columns 90-93 for z in [1.8, 2.4]. There the depth
  // camera sees a pole 1 m away, nearer than the line: what lies on the line beyond is hidden from it.
  frame.depth_m(cv::Rect(90, 0, 4, 120)) = 1.0;
  const DepthSurface surface =
      surfaceAlongLine(frame, kT_WD, Eigen::Vector3d(0.3, 0.0, 0.0), Eigen::Vector3d::UnitZ(), params());
  EXPECT_EQ(surface.status, DepthRangeStatus::kOccluded);
}

TEST(DepthRange, GivenALineOutOfViewOrThroughFreeSpaceThenNothing) {
  const hal::DepthFrame wall = wallAt(20.0);  // beyond max_range_m: the line never reaches it
  EXPECT_EQ(surfaceAlongLine(wall, kT_WD, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), params()).status,
            DepthRangeStatus::kNoSurface);
  EXPECT_EQ(surfaceAlongLine(wall, kT_WD, Eigen::Vector3d::Zero(), -Eigen::Vector3d::UnitZ(), params()).status,
            DepthRangeStatus::kOutOfView);  // behind the depth camera
  hal::DepthFrame blank = wallAt(0.0);      // no data anywhere (a dead sensor)
  EXPECT_EQ(surfaceAlongLine(blank, kT_WD, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), params()).status,
            DepthRangeStatus::kOutOfView);
  hal::DepthFrame wrong = wallAt(4.0);
  wrong.intrinsics.width_px = 320;  // the image is not the size its intrinsics say
  EXPECT_EQ(surfaceAlongLine(wrong, kT_WD, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), params()).status,
            DepthRangeStatus::kOutOfView);
  hal::DepthFrame nan_pixels = wallAt(4.0);
  nan_pixels.depth_m = cv::Scalar(std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(surfaceAlongLine(nan_pixels, kT_WD, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), params()).status,
            DepthRangeStatus::kOutOfView);
}

TEST(DepthRange, GivenTheNoiseModelThenItGrowsAsAStereoCamerasFromItsFloor) {
  DepthRangeParams p = params();
  p.range_std_m = 0.05;
  p.range_std_per_m2 = 0.0015;
  EXPECT_NEAR(depthRangeStdM(0.0, p), 0.05, 1e-12);
  EXPECT_NEAR(depthRangeStdM(4.0, p), std::hypot(0.05, 0.0015 * 16.0), 1e-12);
}

TEST(DepthRange, GivenBadParamsThenValidateSaysWhich) {
  EXPECT_TRUE(validate(params()).has_value());
  DepthRangeParams p = params();
  p.step_m = 0.5;  // longer than the tolerance: a step could jump over a surface
  EXPECT_FALSE(validate(p).has_value());
  p = params();
  p.max_range_m = p.min_range_m;
  EXPECT_FALSE(validate(p).has_value());
  p = params();
  p.max_ratio = 0.9;
  EXPECT_FALSE(validate(p).has_value());
  p = params();
  p.range_std_m = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(validate(p).has_value());
  p = params();
  p.scale_rate = 1.5;  // a rate above 1 overshoots the ratio it learns from
  EXPECT_FALSE(validate(p).has_value());
  p.scale_rate = -0.1;
  EXPECT_FALSE(validate(p).has_value());
}

}  // namespace
}  // namespace aerotrack::estimation
