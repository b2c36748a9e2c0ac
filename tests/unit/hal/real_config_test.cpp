// The `hal.real:` map's one computation: the depth camera's pose in the body from its mount, checked
// against the axes written out by hand (optical x right, y down, z forward; body FLU).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "aerotrack/hal/real_config.hpp"

namespace aerotrack::hal {
namespace {

TEST(DepthCameraPose, AtZeroTheOpticalAxisIsBodyForwardAndTheImageRightIsBodyRight) {
  const Eigen::Isometry3d T_BC = depthCameraPose({0.1, 0.0, 0.03}, {0, 0, 0});
  const Eigen::Matrix3d R = T_BC.linear();
  EXPECT_TRUE(R.col(2).isApprox(Eigen::Vector3d(1, 0, 0)));   // optical z: forward
  EXPECT_TRUE(R.col(0).isApprox(Eigen::Vector3d(0, -1, 0)));  // image right: body -y (right)
  EXPECT_TRUE(R.col(1).isApprox(Eigen::Vector3d(0, 0, -1)));  // image down: body down
  EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
  EXPECT_TRUE(T_BC.translation().isApprox(Eigen::Vector3d(0.1, 0.0, 0.03)));
}

TEST(DepthCameraPose, PositivePitchTiltsTheCameraDownAndYawTurnsItLeft) {
  const double c = std::cos(std::numbers::pi / 6.0), s = std::sin(std::numbers::pi / 6.0);
  const Eigen::Matrix3d pitched = depthCameraPose(Eigen::Vector3d::Zero(), {0, 30, 0}).linear();
  EXPECT_TRUE(pitched.col(2).isApprox(Eigen::Vector3d(c, 0, -s)));  // looks 30 degrees below the horizon
  EXPECT_TRUE(pitched.col(0).isApprox(Eigen::Vector3d(0, -1, 0)));  // image right unchanged
  const Eigen::Matrix3d yawed = depthCameraPose(Eigen::Vector3d::Zero(), {0, 0, 90}).linear();
  EXPECT_TRUE(yawed.col(2).isApprox(Eigen::Vector3d(0, 1, 0)));  // looks left
  const Eigen::Matrix3d rolled = depthCameraPose(Eigen::Vector3d::Zero(), {90, 0, 0}).linear();
  EXPECT_TRUE(rolled.col(2).isApprox(Eigen::Vector3d(1, 0, 0)));   // still forward
  EXPECT_TRUE(rolled.col(0).isApprox(Eigen::Vector3d(0, 0, -1)));  // rolled right: image right is body down
}

}  // namespace
}  // namespace aerotrack::hal
