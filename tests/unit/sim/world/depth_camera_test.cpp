// Tests of the simulated depth camera (hal/sim/world): intrinsics, parameter validation, depth as
// camera-frame z (not ray length) against analytic scenes (a wall, a cylinder, the ground),
// range limits, the sigma = k z^2 noise model and dropout rate (statistical, with stated
// tolerances), determinism for one seed, and no reallocation of a correctly sized image.
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "../../../support/require.hpp"
#include "aerotrack/hal/depth_units.hpp"
#include "aerotrack/hal/sim/depth_camera.hpp"

namespace aerotrack::hal::sim {
namespace {

// Depths are whole millimetres (Z16): within half a millimetre of the exact value, plus float rounding.
constexpr double kZ16Tol = 0.5e-3 + 1e-5;

ObstacleWorld makeWorld(std::vector<Box> boxes, std::vector<Cylinder> cylinders) {
  return aerotrack::test::require(ObstacleWorld::create(std::move(boxes), std::move(cylinders)),
                                  "ObstacleWorld::create");
}

/// Camera at p_W_m looking along world +x, level: C z -> W x, C x -> W -y, C y -> W -z.
Eigen::Isometry3d lookAlongX(const Eigen::Vector3d& p_W_m) {
  Eigen::Matrix3d R_WC;
  R_WC.col(0) = -Eigen::Vector3d::UnitY();
  R_WC.col(1) = -Eigen::Vector3d::UnitZ();
  R_WC.col(2) = Eigen::Vector3d::UnitX();
  Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();
  T_WC.linear() = R_WC;
  T_WC.translation() = p_W_m;
  return T_WC;
}

/// Camera at p_W_m looking straight down (C z -> W -z).
Eigen::Isometry3d lookDown(const Eigen::Vector3d& p_W_m) {
  Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();
  T_WC.linear() = Eigen::Vector3d(1, -1, -1).asDiagonal();
  T_WC.translation() = p_W_m;
  return T_WC;
}

DepthCameraParams ideal() {
  DepthCameraParams params;
  params.noise_coeff_per_m = 0.0;
  params.dropout_probability = 0.0;
  return params;
}

/// A wall facing the camera (x in [d, d + 0.2]) covering the whole field of view.
ObstacleWorld wallAt(double d_m) {
  return makeWorld({Box{Eigen::Vector3d(d_m, -100, 0), Eigen::Vector3d(d_m + 0.2, 100, 200)}}, {});
}

/// Mean and sample standard deviation of the non-zero pixels; count of zero pixels.
struct Stats {
  double mean = 0.0;
  double stddev = 0.0;
  int zeros = 0;
};
Stats stats(const cv::Mat& depth_m) {
  double sum = 0.0;
  double sum2 = 0.0;
  int n = 0;
  Stats s;
  for (int v = 0; v < depth_m.rows; ++v) {
    for (int u = 0; u < depth_m.cols; ++u) {
      const auto z = static_cast<double>(depth_m.at<float>(v, u));
      if (z == 0.0) {
        ++s.zeros;
        continue;
      }
      sum += z;
      sum2 += z * z;
      ++n;
    }
  }
  s.mean = sum / n;
  s.stddev = std::sqrt((sum2 - n * s.mean * s.mean) / (n - 1));
  return s;
}

TEST(DepthCameraParams, GivenDefaultsThenValidAndD435Like) {
  const DepthCameraParams params;
  EXPECT_TRUE(DepthCameraParams::validate(params).has_value());
  EXPECT_EQ(params.width_px, 160);
  EXPECT_EQ(params.height_px, 120);
  EXPECT_EQ(params.hfov_deg, 87.0);
  EXPECT_EQ(params.vfov_deg, 58.0);
}

TEST(DepthCameraParams, GivenOutOfRangeFieldsThenValidateFails) {
  const auto invalid = [](auto mutate) {
    DepthCameraParams params;
    mutate(params);
    return !DepthCameraParams::validate(params).has_value();
  };
  EXPECT_TRUE(invalid([](DepthCameraParams& p) { p.width_px = 0; }));
  EXPECT_TRUE(invalid([](DepthCameraParams& p) { p.height_px = -3; }));
  EXPECT_TRUE(invalid([](DepthCameraParams& p) { p.hfov_deg = 180.0; }));
  EXPECT_TRUE(invalid([](DepthCameraParams& p) { p.vfov_deg = std::nan(""); }));
  EXPECT_TRUE(invalid([](DepthCameraParams& p) { p.min_range_m = -0.1; }));
  EXPECT_TRUE(invalid([](DepthCameraParams& p) { p.min_range_m = 11.0; }));
  EXPECT_TRUE(invalid([](DepthCameraParams& p) { p.max_range_m = std::numeric_limits<double>::infinity(); }));
  EXPECT_TRUE(invalid([](DepthCameraParams& p) { p.noise_coeff_per_m = -1e-3; }));
  EXPECT_TRUE(invalid([](DepthCameraParams& p) { p.dropout_probability = 1.5; }));
}

TEST(DepthIntrinsics, GivenFieldsOfViewThenFocalLengthsFromHalfAngles) {
  const CameraIntrinsics k = depthIntrinsics(DepthCameraParams{});
  EXPECT_EQ(k.width_px, 160);
  EXPECT_EQ(k.height_px, 120);
  EXPECT_NEAR(k.fx_px, 80.0 / std::tan(43.5 * std::numbers::pi / 180.0), 1e-12);
  EXPECT_NEAR(k.fy_px, 60.0 / std::tan(29.0 * std::numbers::pi / 180.0), 1e-12);
  EXPECT_EQ(k.cx_px, 80.0);
  EXPECT_EQ(k.cy_px, 60.0);
}

TEST(RenderDepth, GivenAnyPoseThenEveryValueIsAWholeNumberOfMillimetresAsTheD435Delivers) {
  DepthCameraParams params = ideal();
  params.noise_coeff_per_m = 0.0015;  // noisy values are rounded too
  const ObstacleWorld world = makeWorld({}, {Cylinder{Eigen::Vector2d(4.0, 0.3), 0.4, 0.0, 100.0}});
  std::mt19937_64 rng(3);
  cv::Mat depth_m;
  renderDepth(world, lookAlongX({0, 0, 1.2}), params, rng, depth_m);
  int valid = 0;
  for (int v = 0; v < depth_m.rows; ++v) {
    for (int u = 0; u < depth_m.cols; ++u) {
      const float z = depth_m.at<float>(v, u);
      ASSERT_EQ(z, depthFromZ16(depthToZ16(static_cast<double>(z))))
          << u << ", " << v;  // a Z16 value, read back exactly
      valid += z > 0.0F ? 1 : 0;
    }
  }
  EXPECT_GT(valid, depth_m.rows * depth_m.cols / 4);
}

TEST(RenderDepth, GivenWallFacingTheCameraAtDThenEveryPixelIsD) {
  for (const double d_m : {0.5, 4.0, 9.5}) {
    std::mt19937_64 rng(1);
    cv::Mat depth_m;
    renderDepth(wallAt(d_m), lookAlongX({0, 0, 50}), ideal(), rng, depth_m);
    ASSERT_EQ(depth_m.type(), CV_32FC1);
    ASSERT_EQ(depth_m.rows, 120);
    ASSERT_EQ(depth_m.cols, 160);
    double min_m = 0.0;
    double max_m = 0.0;
    cv::minMaxLoc(depth_m, &min_m, &max_m);
    EXPECT_NEAR(min_m, d_m, kZ16Tol);
    EXPECT_NEAR(max_m, d_m, kZ16Tol);
  }
}

TEST(RenderDepth, GivenCylinderStraightAheadThenCentreColumnIsDistanceMinusRadius) {
  DepthCameraParams params = ideal();
  params.width_px = 161;  // odd sizes: the centre pixel's ray is the optical axis
  params.height_px = 121;
  const double d_m = 6.0;
  const double r_m = 0.4;
  const double h_m = 1.5;
  const ObstacleWorld world = makeWorld({}, {Cylinder{Eigen::Vector2d(d_m, 0), r_m, 0.0, 100.0}});
  std::mt19937_64 rng(1);
  cv::Mat depth_m;
  renderDepth(world, lookAlongX({0, 0, h_m}), params, rng, depth_m);
  const CameraIntrinsics k = depthIntrinsics(params);
  // Centre column: the cylinder's front line at z = d - r, unless the ground is nearer.
  for (int v = 0; v < params.height_px; ++v) {
    const double y_c = (v + 0.5 - k.cy_px) / k.fy_px;
    const double expected = y_c * (d_m - r_m) <= h_m ? d_m - r_m : h_m / y_c;
    EXPECT_NEAR(depth_m.at<float>(v, 80), expected, kZ16Tol) << "row " << v;
  }
  // Centre row, other columns: line (s z, z) meets the circle around (0, d):
  // (1 + s^2) z^2 - 2 d z + d^2 - r^2 = 0; no hit (and no ground at the horizon) reads 0.
  int hit_columns = 0;
  for (int u = 0; u < params.width_px; ++u) {
    const double s = (u + 0.5 - k.cx_px) / k.fx_px;
    const double disc = d_m * d_m - (1 + s * s) * (d_m * d_m - r_m * r_m);
    const double expected = disc >= 0.0 ? (d_m - std::sqrt(disc)) / (1 + s * s) : 0.0;
    EXPECT_NEAR(depth_m.at<float>(60, u), expected, kZ16Tol) << "column " << u;
    hit_columns += disc >= 0.0 ? 1 : 0;
  }
  EXPECT_GE(hit_columns, 5);
}

TEST(RenderDepth, GivenGroundOnlyThenRowsBeyondMaxRangeAndAboveHorizonAreZero) {
  const ObstacleWorld world = makeWorld({}, {});
  const DepthCameraParams params = ideal();
  const CameraIntrinsics k = depthIntrinsics(params);
  std::mt19937_64 rng(1);
  cv::Mat depth_m;
  const double h_m = 1.5;
  renderDepth(world, lookAlongX({3, -2, h_m}), params, rng, depth_m);
  int ground_rows = 0;
  for (int v = 0; v < params.height_px; ++v) {
    const double y_c = (v + 0.5 - k.cy_px) / k.fy_px;
    const double z = y_c > 0.0 ? h_m / y_c : 0.0;  // ground at camera-frame z = h / y
    const double expected = z <= params.max_range_m ? z : 0.0;
    if (std::abs(z - params.max_range_m) < 1e-6) continue;  // exactly at the limit: either
    ground_rows += expected > 0.0 ? 1 : 0;
    for (int u = 0; u < params.width_px; ++u) {
      ASSERT_NEAR(depth_m.at<float>(v, u), expected, kZ16Tol) << "pixel " << u << ", " << v;
    }
  }
  EXPECT_GT(ground_rows, 30);
  EXPECT_LT(ground_rows, 60);
}

TEST(RenderDepth, GivenSurfacesOutsideTheRangeThenZero) {
  std::mt19937_64 rng(1);
  cv::Mat depth_m;
  renderDepth(wallAt(12.0), lookAlongX({0, 0, 50}), ideal(), rng, depth_m);  // beyond max 10 m
  EXPECT_EQ(cv::countNonZero(depth_m), 0);
  renderDepth(wallAt(0.2), lookAlongX({0, 0, 50}), ideal(), rng, depth_m);  // below min 0.3 m
  EXPECT_EQ(cv::countNonZero(depth_m), 0);
  renderDepth(makeWorld({}, {}), lookDown({0, 0, 0.25}), ideal(), rng, depth_m);  // ground too near
  EXPECT_EQ(cv::countNonZero(depth_m), 0);
  renderDepth(makeWorld({}, {}), lookDown({0, 0, 0.35}), ideal(), rng, depth_m);
  EXPECT_EQ(cv::countNonZero(depth_m), 160 * 120);
}

TEST(RenderDepth, GivenNoiseThenSampleStdDevIsKzSquaredWithin10Percent) {
  DepthCameraParams params = ideal();
  params.noise_coeff_per_m = 0.0015;
  for (const double z_m : {1.0, 4.0, 9.0}) {
    std::mt19937_64 rng(3);
    cv::Mat depth_m;
    renderDepth(wallAt(z_m), lookAlongX({0, 0, 50}), params, rng, depth_m);
    const Stats s = stats(depth_m);
    const double sigma = params.noise_coeff_per_m * z_m * z_m;
    EXPECT_EQ(s.zeros, 0);
    EXPECT_NEAR(s.stddev, sigma, 0.1 * sigma) << "z " << z_m;  // 19,200 samples: ~0.5 % std error
    EXPECT_NEAR(s.mean, z_m, 5.0 * sigma / std::sqrt(19200.0) + 1e-6) << "z " << z_m;
  }
}

TEST(RenderDepth, GivenDropoutProbabilityThenThatFractionOfPixelsIsZero) {
  DepthCameraParams params = ideal();
  params.dropout_probability = 0.2;
  std::mt19937_64 rng(5);
  cv::Mat depth_m;
  renderDepth(wallAt(4.0), lookAlongX({0, 0, 50}), params, rng, depth_m);
  const double fraction = 1.0 - cv::countNonZero(depth_m) / 19200.0;
  EXPECT_NEAR(fraction, 0.2, 5.0 * std::sqrt(0.2 * 0.8 / 19200.0));  // 5 binomial sigmas
  params.dropout_probability = 1.0;
  renderDepth(wallAt(4.0), lookAlongX({0, 0, 50}), params, rng, depth_m);
  EXPECT_EQ(cv::countNonZero(depth_m), 0);
}

/// A random forest of ~190 trees and 20 boxes (some floating, some raised), 40 x 40 m.
ObstacleWorld randomForest(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> xy(-20.0, 20.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Cylinder> trees;
  for (int i = 0; i < 190; ++i) {
    const double z0 = unit(rng) < 0.2 ? 2.0 * unit(rng) : 0.0;
    trees.push_back(
        Cylinder{Eigen::Vector2d(xy(rng), xy(rng)), 0.15 + 0.25 * unit(rng), z0, z0 + 1.0 + 7.0 * unit(rng)});
  }
  std::vector<Box> boxes;
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector3d lo(xy(rng), xy(rng), unit(rng) < 0.25 ? 3.0 * unit(rng) : 0.0);
    boxes.push_back(Box{lo, lo + Eigen::Vector3d(0.1 + 6.0 * unit(rng), 0.1 + 6.0 * unit(rng), 0.5 + 4.0 * unit(rng))});
  }
  return makeWorld(std::move(boxes), std::move(trees));
}

TEST(RenderDepth, GivenRandomPosesInAForestThenEveryPixelEqualsItsRaycast) {
  // Reference: ObstacleWorld::raycast (grid walk) through each pixel centre, depth = t / |(x, y, 1)|.
  std::mt19937_64 rng(21);
  const ObstacleWorld world = randomForest(rng);
  DepthCameraParams params = ideal();
  params.width_px = 64;
  params.height_px = 48;
  const CameraIntrinsics k = depthIntrinsics(params);
  std::uniform_real_distribution<double> xy(-25.0, 25.0);
  std::uniform_real_distribution<double> z(0.2, 6.0);
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < 40; ++i) {  // level and arbitrarily rotated cameras
    Eigen::Isometry3d T_WC = lookAlongX({xy(rng), xy(rng), z(rng)});
    const Eigen::Quaterniond q = Eigen::Quaterniond::UnitRandom();
    if (i % 2 == 1) T_WC.linear() = q.toRotationMatrix();
    poses.push_back(T_WC);
  }
  const Box& wall = world.boxes().front();
  poses.push_back(lookAlongX(0.5 * (wall.min_W_m + wall.max_W_m)));                 // inside a box
  poses.push_back(lookAlongX(wall.min_W_m - Eigen::Vector3d(0.01, -0.05, -0.05)));  // 1 cm from a face
  int nonzero = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Isometry3d& T_WC = poses[i];
    cv::Mat depth_m;
    renderDepth(world, T_WC, params, rng, depth_m);
    for (int v = 0; v < params.height_px; ++v) {
      for (int u = 0; u < params.width_px; ++u) {
        const Eigen::Vector3d ray_C((u + 0.5 - k.cx_px) / k.fx_px, (v + 0.5 - k.cy_px) / k.fy_px, 1.0);
        const double norm = ray_C.norm();
        const auto t_m =
            world.raycast(T_WC.translation(), T_WC.linear() * (ray_C / norm), params.max_range_m * norm, true);
        const double z_m = t_m ? *t_m / norm : 0.0;
        const double expected = z_m >= params.min_range_m && z_m <= params.max_range_m ? z_m : 0.0;
        ASSERT_NEAR(depth_m.at<float>(v, u), expected, kZ16Tol) << "pose " << i << " pixel " << u << ", " << v;
        nonzero += expected > 0.0 ? 1 : 0;
      }
    }
  }
  EXPECT_GT(nonzero, static_cast<int>(poses.size()) * 64 * 48 / 4);  // mostly hits, not empty images
}

TEST(RenderDepth, GivenSameSeedThenIdenticalImageAndOtherSeedDiffers) {
  std::mt19937_64 scene_rng(11);
  std::uniform_real_distribution<double> xy(-20.0, 20.0);
  std::vector<Cylinder> trees;
  for (int i = 0; i < 190; ++i) trees.push_back(Cylinder{Eigen::Vector2d(xy(scene_rng), xy(scene_rng)), 0.3, 0, 6});
  const ObstacleWorld world = makeWorld({}, std::move(trees));
  const DepthCameraParams params;  // default noise and dropout
  const auto render = [&](std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    cv::Mat depth_m;
    renderDepth(world, lookAlongX({-19, 0.5, 1.5}), params, rng, depth_m);
    return depth_m;
  };
  const cv::Mat a = render(99);
  const cv::Mat b = render(99);
  const cv::Mat c = render(100);
  ASSERT_TRUE(a.isContinuous() && b.isContinuous());
  EXPECT_EQ(std::memcmp(a.data, b.data, a.total() * a.elemSize()), 0);
  EXPECT_NE(std::memcmp(a.data, c.data, a.total() * a.elemSize()), 0);
  EXPECT_GT(cv::countNonZero(a), 19200 / 3);
}

TEST(RenderDepth, GivenCorrectlySizedImageThenNotReallocated) {
  std::mt19937_64 rng(1);
  cv::Mat depth_m(120, 160, CV_32FC1, cv::Scalar(-1.0));
  const uchar* data = depth_m.data;
  renderDepth(wallAt(4.0), lookAlongX({0, 0, 50}), ideal(), rng, depth_m);
  EXPECT_EQ(depth_m.data, data);
  cv::Mat wrong(10, 10, CV_8UC1);
  renderDepth(wallAt(4.0), lookAlongX({0, 0, 50}), ideal(), rng, wrong);
  EXPECT_EQ(wrong.type(), CV_32FC1);
  EXPECT_EQ(wrong.size(), cv::Size(160, 120));
}

}  // namespace
}  // namespace aerotrack::hal::sim
