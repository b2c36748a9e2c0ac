// Tests of the image-mode camera's background (hal/sim/render/background_shader.hpp): the two-pass,
// vectorised span shading against the one-pixel-at-a-time reference (shadePixel) over whole frames
// from cameras at many heights, attitudes and places (ground, horizon, sky; texture coordinates that
// wrap and near-horizon rays that meet the ground kilometres away), and spans that do not depend on
// where a row is cut (obstacles cut rows into runs).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "aerotrack/hal/sim/background_shader.hpp"

namespace aerotrack::hal::sim {
namespace {

constexpr int kWidthPx = 640, kHeightPx = 480;
constexpr double kFxPx = 337.2, kCxPx = 320.0, kCyPx = 240.0;
constexpr double kHazeM = 60.0;

// Camera axes (x right, y down, z forward) turned by yaw about world z, then pitched about the
// camera's x and rolled about its z; pitch 0 looks at the horizon.
Eigen::Matrix3d cameraRotation(double yaw_rad, double pitch_rad, double roll_rad) {
  Eigen::Matrix3d level;  // columns: camera x, y, z in the world when looking along world +x
  level << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix() * level *
         Eigen::AngleAxisd(-pitch_rad, Eigen::Vector3d::UnitX()).toRotationMatrix() *
         Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

struct Mismatch {
  int pixels = 0;
  int worst = 0;
};

Mismatch compareFrame(const GroundTexture& ground, const Eigen::Vector3d& o_W, const Eigen::Matrix3d& R_WC) {
  BackgroundShader shader(ground, o_W, kFxPx, kHazeM);
  std::vector<cv::Vec3b> row(kWidthPx);
  Mismatch m;
  for (int v = 0; v < kHeightPx; ++v) {
    const RowRays rays = BackgroundShader::rowRays(R_WC, kFxPx, kFxPx, kCxPx, kCyPx, v);
    shader.shadeSpan(rays, 0, kWidthPx, row.data());
    for (int u = 0; u < kWidthPx; ++u) {
      const auto i = static_cast<std::size_t>(u);
      const Eigen::Vector3f d = rays.at(u);
      const cv::Vec3b want = shader.shadePixel(d.x(), d.y(), d.z());
      int diff = 0;
      for (int ch = 0; ch < 3; ++ch) diff = std::max(diff, std::abs(int{row[i][ch]} - int{want[ch]}));
      if (diff > 0) ++m.pixels;
      m.worst = std::max(m.worst, diff);
    }
  }
  return m;
}

TEST(BackgroundShader, SpansMatchTheOnePixelReferenceFromManyCameras) {
  const auto ground = GroundTexture::make();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> place(-80.0, 80.0), height(0.2, 25.0), yaw(-M_PI, M_PI), pitch(-1.4, 0.6),
      roll(-0.5, 0.5);
  for (int trial = 0; trial < 12; ++trial) {
    const Eigen::Vector3d o_W(place(rng), place(rng), height(rng));
    const Mismatch m = compareFrame(*ground, o_W, cameraRotation(yaw(rng), pitch(rng), roll(rng)));
    // The reference blends haze the textbook way and may round a channel the other way.
    EXPECT_LE(m.worst, 1) << "trial " << trial;
    EXPECT_LT(m.pixels, kWidthPx * kHeightPx / 100) << "trial " << trial;
  }
}

TEST(BackgroundShader, TheHorizonStraightAheadAndACameraBelowTheGround) {
  const auto ground = GroundTexture::make();
  // Level: rays a hair below the horizon meet the ground kilometres away (the one-texel level).
  EXPECT_LE(compareFrame(*ground, {3.0, -2.0, 1.5}, cameraRotation(0.3, 0.0, 0.0)).worst, 1);
  // Straight down from 0.3 m: the finest level, texel coordinates across the texture's wrap at 0.
  EXPECT_LE(compareFrame(*ground, {0.01, -0.01, 0.3}, cameraRotation(0.0, -M_PI / 2 + 1e-3, 0.0)).worst, 1);
  // Under the ground plane there is no ground to see: sky everywhere, as the reference says.
  EXPECT_LE(compareFrame(*ground, {0.0, 0.0, -1.0}, cameraRotation(0.0, -0.3, 0.2)).worst, 1);
}

TEST(BackgroundShader, ARowCutIntoRunsIsShadedAsAWhole) {
  const auto ground = GroundTexture::make();
  BackgroundShader shader(*ground, {5.0, 7.0, 1.8}, kFxPx, kHazeM);
  const Eigen::Matrix3d R_WC = cameraRotation(0.8, -0.05, 0.35);  // the horizon crosses the rows
  std::vector<cv::Vec3b> whole(kWidthPx), cut(kWidthPx);
  std::mt19937_64 rng(3);
  std::uniform_int_distribution<int> run(1, 90);
  for (int v = 0; v < kHeightPx; v += 7) {
    const RowRays rays = BackgroundShader::rowRays(R_WC, kFxPx, kFxPx, kCxPx, kCyPx, v);
    shader.shadeSpan(rays, 0, kWidthPx, whole.data());
    for (int u = 0; u < kWidthPx;) {
      const int end = std::min(kWidthPx, u + run(rng));
      shader.shadeSpan(rays, u, end, cut.data());
      u = end;
    }
    for (int u = 0; u < kWidthPx; ++u) {
      ASSERT_EQ(whole[static_cast<std::size_t>(u)], cut[static_cast<std::size_t>(u)]) << "row " << v << " u " << u;
    }
  }
}

}  // namespace
}  // namespace aerotrack::hal::sim
