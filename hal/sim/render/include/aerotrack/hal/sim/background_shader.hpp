// The image-mode camera's background: the sky's gradient and the textured, hazy ground, seen along
// pixel rays. Split from scene_renderer.cpp because it is most of a frame's cost (issue 22 item 1:
// <= 5 ms a frame): a row's run of background pixels is shaded in two passes, one branch-free pass
// of single-precision arithmetic the compiler vectorises, then the texture lookups. shadePixel()
// is the same colour the obvious way, one pixel at a time: the reference the spans are tested
// against (tests/unit/sim/render/background_shader_test.cpp).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

namespace aerotrack::hal::sim {

/// The sky's colour at the horizon (B, G, R in [0, 255]): what haze fades everything towards.
inline constexpr std::array<float, 3> kSkyHorizonBgr = {235.0F, 218.0F, 200.0F};

/// The ground's texture: brightness factors on a 25.6 m square period, level k with 0.05 * 2^k m
/// texels (a mip pyramid, 512 x 512 down to 1 x 1). Immutable once made; shared by renderer copies.
struct GroundTexture {
  static constexpr int kSize = 512;        ///< texels along each side of level 0
  static constexpr double kTexelM = 0.05;  ///< level 0's texel
  std::vector<std::vector<float>> levels;  ///< levels[k]: (kSize >> k)^2 texels, row-major (y, x)

  /// 1.6 m tiles, 0.2 m cells and 0.05 m texels of hashed brightness; each level the mean of 2 x 2
  /// texels of the one below. Deterministic.
  static std::shared_ptr<const GroundTexture> make();
};

/// One row's pixel rays in the world frame, scaled so that camera z = 1 (a hit at ray parameter t
/// has depth t): pixel u's ray is d0 + u step.
struct RowRays {
  Eigen::Vector3f d0 = Eigen::Vector3f::Zero(), step = Eigen::Vector3f::Zero();
  Eigen::Vector3f at(int u) const { return d0 + static_cast<float>(u) * step; }
};

/// The background seen from one camera position. Cheap to make (once per frame); holds the spans'
/// buffers, so one shader per thread.
class BackgroundShader {
 public:
  static constexpr int kTopLevel = 9;  ///< log2(GroundTexture::kSize): the 1 x 1 level
  static constexpr int kChunk = 64;    ///< pixels per pass of a span: the passes' buffers stay in L1

  /// o_W: the camera's position; fx_px: its focal length (a pixel's footprint on the ground);
  /// haze_distance_m: range at which haze is half of a colour. ground must outlive the shader.
  BackgroundShader(const GroundTexture& ground, const Eigen::Vector3d& o_W, double fx_px, double haze_distance_m);

  /// The rays of row v (R_WC: the camera's rotation; pixel centres at +0.5).
  static RowRays rowRays(const Eigen::Matrix3d& R_WC, double fx_px, double fy_px, double cx_px, double cy_px, int v);

  /// Shades pixels [u0, u1) of a row with rays `rays` into row[u0, u1): ground where the ray goes
  /// down from a camera above it, else sky.
  void shadeSpan(const RowRays& rays, int u0, int u1, cv::Vec3b* row);

  /// The colour of one ray (x, y, z: RowRays::at), computed the obvious way: the reference.
  cv::Vec3b shadePixel(float dx, float dy, float dz) const;

 private:
  void groundSpan(const RowRays& rays, int u0, int u1, cv::Vec3b* row);
  void skySpan(const RowRays& rays, int u0, int u1, cv::Vec3b* row);

  const GroundTexture* ground_;
  bool above_ground_;
  // Single precision: a grass texel needs no more than float's 24 bits. The camera's x, y are taken
  // modulo the texture's 25.6 m period first, so float keeps mm resolution there.
  float o_x_, o_y_, o_z_;
  float inv_height_;
  float footprint_scale_;  ///< a ray's range times this: its pixel's footprint in level-0 texels
  float haze_m_;
  std::array<const float*, kTopLevel + 1> level_data_{};
  /// The spans' per-pass buffers: level-0 texel coordinates, the level, 1 - haze (or the sky's elevation).
  struct {
    std::array<int, kChunk> tx, ty, level;
    std::array<float, kChunk> keep;
  } buffers_{};
};

}  // namespace aerotrack::hal::sim
