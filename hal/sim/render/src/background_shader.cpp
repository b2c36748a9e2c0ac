// Sky and ground of the image-mode camera. See background_shader.hpp.
#include "aerotrack/hal/sim/background_shader.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>

#include "render_hash.hpp"
#include "render_math.hpp"

namespace aerotrack::hal::sim {
namespace {

constexpr int kTopLevel = BackgroundShader::kTopLevel;
constexpr float kInvTexel0 = 20.0F;  // 1 / GroundTexture::kTexelM, exact in float
// Texel coordinates are taken at most this far along a ray, so that they fit an int (near the
// horizon the ray meets the ground arbitrarily far away). No pixel changes: a level finer than the
// top one (a single texel) is read only within a few hundred metres (80 m from 1.5 m high).
constexpr float kMaxGroundRayM = 1e6F;
constexpr int kChunk = BackgroundShader::kChunk;

// B, G, R in [0, 255].
constexpr std::array<float, 3> kSkyZenith = {205.0F, 140.0F, 80.0F};
constexpr std::array<float, 3> kGrass = {52.0F, 112.0F, 70.0F};

/// floor(log2(x)) for a finite x >= 1, from the exponent bits.
int floorLog2(float x) {
  return static_cast<int>((std::bit_cast<std::uint32_t>(x) >> 23) & 0xFFU) - 127;
}

/// The mip level for a pixel's footprint: the finest with texels >= footprint (level-0 texels).
int levelFor(float footprint_texels) {
  const int level = minI(kTopLevel, floorLog2(footprint_texels) + 1);
  return footprint_texels < 1.0F ? 0 : level;
}

}  // namespace

std::shared_ptr<const GroundTexture> GroundTexture::make() {
  auto ground = std::make_shared<GroundTexture>();
  std::vector<float> level(static_cast<std::size_t>(kSize) * kSize);
  for (int j = 0; j < kSize; ++j) {
    for (int i = 0; i < kSize; ++i) {
      double shade = (((i / 32) + (j / 32)) & 1) ? 1.06 : 0.94;
      shade += 0.22 * (hash01(i / 4, j / 4, 1) - 0.5);
      shade += 0.16 * (hash01(i, j, 2) - 0.5);
      level[static_cast<std::size_t>(j) * kSize + static_cast<std::size_t>(i)] = static_cast<float>(shade);
    }
  }
  for (int size = kSize; size >= 1; size /= 2) {
    ground->levels.push_back(level);
    if (size == 1) break;
    const int half = size / 2;
    std::vector<float> down(static_cast<std::size_t>(half) * half);
    for (int j = 0; j < half; ++j) {
      for (int i = 0; i < half; ++i) {
        const auto at = [&](int x, int y) {
          return level[static_cast<std::size_t>(y) * static_cast<std::size_t>(size) + static_cast<std::size_t>(x)];
        };
        down[static_cast<std::size_t>(j) * static_cast<std::size_t>(half) + static_cast<std::size_t>(i)] =
            0.25F * (at(2 * i, 2 * j) + at(2 * i + 1, 2 * j) + at(2 * i, 2 * j + 1) + at(2 * i + 1, 2 * j + 1));
      }
    }
    level = std::move(down);
  }
  return ground;
}

BackgroundShader::BackgroundShader(const GroundTexture& ground, const Eigen::Vector3d& o_W, double fx_px,
                                   double haze_distance_m)
    : ground_(&ground), above_ground_(o_W.z() > 0.0) {
  for (std::size_t l = 0; l < level_data_.size(); ++l) level_data_[l] = ground_->levels[l].data();
  const double period_m = GroundTexture::kSize * GroundTexture::kTexelM;
  o_x_ = static_cast<float>(o_W.x() - period_m * std::floor(o_W.x() / period_m));
  o_y_ = static_cast<float>(o_W.y() - period_m * std::floor(o_W.y() / period_m));
  o_z_ = static_cast<float>(o_W.z());
  inv_height_ = above_ground_ ? static_cast<float>(1.0 / o_W.z()) : 0.0F;
  footprint_scale_ = static_cast<float>(1.0 / fx_px / GroundTexture::kTexelM);
  haze_m_ = static_cast<float>(haze_distance_m);
}

RowRays BackgroundShader::rowRays(const Eigen::Matrix3d& R_WC, double fx_px, double fy_px, double cx_px, double cy_px,
                                  int v) {
  RowRays rays;
  rays.d0 = (R_WC * Eigen::Vector3d((0.5 - cx_px) / fx_px, (v + 0.5 - cy_px) / fy_px, 1.0)).cast<float>();
  rays.step = (R_WC.col(0) / fx_px).cast<float>();
  return rays;
}

void BackgroundShader::shadeSpan(const RowRays& rays, int u0, int u1, cv::Vec3b* row) {
  if (u0 >= u1) return;
  // A ray goes down where its z, d0.z + u step.z, is negative: monotonic in u (so in float too), so
  // ground and sky split a span at most once, found by bisection with the same per-pixel test
  // shadePixel() makes.
  const auto ground = [&](int u) {
    return above_ground_ && rays.d0.z() + static_cast<float>(u) * rays.step.z() < 0.0F;
  };
  const bool first = ground(u0);
  if (ground(u1 - 1) == first) {
    if (first) {
      groundSpan(rays, u0, u1, row);
    } else {
      skySpan(rays, u0, u1, row);
    }
    return;
  }
  int lo = u0, hi = u1 - 1;  // ground(lo) == first, ground(hi) != first
  while (hi - lo > 1) {
    const int mid = lo + (hi - lo) / 2;
    if (ground(mid) == first) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  if (first) {
    groundSpan(rays, u0, hi, row);
    skySpan(rays, hi, u1, row);
  } else {
    skySpan(rays, u0, hi, row);
    groundSpan(rays, hi, u1, row);
  }
}

void BackgroundShader::groundSpan(const RowRays& rays, int u0, int u1, cv::Vec3b* row) {
  auto& [tx, ty, lvl, keep] = buffers_;
  for (int c0 = u0; c0 < u1; c0 += kChunk) {
    const int n = std::min(kChunk, u1 - c0);
    const float d0x = rays.d0.x(), d0y = rays.d0.y(), d0z = rays.d0.z();
    const float sx = rays.step.x(), sy = rays.step.y(), sz = rays.step.z();
    // Pass 1, branch-free (vectorised): where the ray meets the ground, the pixel's footprint there
    // (range / f, stretched by the grazing angle range / height, at most 20x) and the haze.
    for (int k = 0; k < n; ++k) {
      const auto u = static_cast<float>(c0 + k);
      const float dx = d0x + u * sx, dy = d0y + u * sy, dz = d0z + u * sz;
      const float t = -o_z_ / dz;
      const float range_m = t * std::sqrt(dx * dx + dy * dy + dz * dz);
      const float t_texel = minF(t, kMaxGroundRayM);
      const float x = o_x_ + t_texel * dx, y = o_y_ + t_texel * dy;
      const float stretch = minF(range_m * inv_height_, 20.0F);
      lvl[k] = levelFor(range_m * stretch * footprint_scale_);
      // Level-0 texel coordinates; level l's are these shifted right by l (floor of a division by
      // 2^l), which is exactly floor(x / texel_l) since texel_l = 2^l texel_0.
      tx[k] = floorToInt(x * kInvTexel0);
      ty[k] = floorToInt(y * kInvTexel0);
      keep[k] = haze_m_ / (range_m + haze_m_);  // 1 - haze
    }
    // Pass 2: the texture lookups and the colour.
    cv::Vec3b* out = row + c0;
    for (int k = 0; k < n; ++k) {
      const int l = lvl[k];
      const int mask = (GroundTexture::kSize >> l) - 1;
      const auto i = static_cast<std::size_t>((tx[k] >> l) & mask);
      const auto j = static_cast<std::size_t>((ty[k] >> l) & mask);
      const float shade = level_data_[static_cast<std::size_t>(l)][(j << static_cast<unsigned>(kTopLevel - l)) + i];
      for (std::size_t ch = 0; ch < 3; ++ch)
        out[k][static_cast<int>(ch)] = toByte(keep[k] * (shade * kGrass[ch] - kSkyHorizonBgr[ch]) + kSkyHorizonBgr[ch]);
    }
  }
}

void BackgroundShader::skySpan(const RowRays& rays, int u0, int u1, cv::Vec3b* row) {
  auto& elevation = buffers_.keep;  // the sky's pass needs one buffer: groundSpan's 1 - haze
  const float d0x = rays.d0.x(), d0y = rays.d0.y(), d0z = rays.d0.z();
  const float sx = rays.step.x(), sy = rays.step.y(), sz = rays.step.z();
  for (int c0 = u0; c0 < u1; c0 += kChunk) {
    const int n = std::min(kChunk, u1 - c0);
    for (int k = 0; k < n; ++k) {  // vectorised: sine of the elevation, 0 at the horizon, 1 at the zenith
      const auto u = static_cast<float>(c0 + k);
      const float dx = d0x + u * sx, dy = d0y + u * sy, dz = d0z + u * sz;
      elevation[static_cast<std::size_t>(k)] = maxF(0.0F, dz) / std::sqrt(dx * dx + dy * dy + dz * dz);
    }
    cv::Vec3b* out = row + c0;
    for (int k = 0; k < n; ++k) {
      const float s = elevation[static_cast<std::size_t>(k)];
      for (std::size_t ch = 0; ch < 3; ++ch)
        out[k][static_cast<int>(ch)] = toByte(kSkyHorizonBgr[ch] + s * (kSkyZenith[ch] - kSkyHorizonBgr[ch]));
    }
  }
}

cv::Vec3b BackgroundShader::shadePixel(float dx, float dy, float dz) const {
  cv::Vec3b px;
  const float norm = std::sqrt(dx * dx + dy * dy + dz * dz);
  if (above_ground_ && dz < 0.0F) {
    const float t = -o_z_ / dz;
    const float x = o_x_ + t * dx, y = o_y_ + t * dy;
    const float range_m = t * norm;
    const float texels = range_m * std::min(range_m * inv_height_, 20.0F) * footprint_scale_;
    const int level =
        texels < 1.0F ? 0
                      : std::min(kTopLevel, static_cast<int>(std::floor(std::log2(static_cast<double>(texels)))) + 1);
    const int size = GroundTexture::kSize >> level;
    const float inv_texel = static_cast<float>(1.0 / std::ldexp(GroundTexture::kTexelM, level));
    const auto texel = [&](float coord) {
      const double scaled = std::clamp(static_cast<double>(coord * inv_texel), -1e12, 1e12);
      const auto index = static_cast<long long>(std::floor(scaled)) % size;
      return static_cast<std::size_t>(index < 0 ? index + size : index);
    };
    const float shade =
        ground_->levels[static_cast<std::size_t>(level)][texel(y) * static_cast<std::size_t>(size) + texel(x)];
    const float haze = range_m / (range_m + haze_m_);
    for (std::size_t ch = 0; ch < 3; ++ch)
      px[static_cast<int>(ch)] = toByte((1.0F - haze) * shade * kGrass[ch] + haze * kSkyHorizonBgr[ch]);
    return px;
  }
  const float s = std::max(0.0F, dz) / norm;
  for (std::size_t ch = 0; ch < 3; ++ch)
    px[static_cast<int>(ch)] = toByte(kSkyHorizonBgr[ch] + s * (kSkyZenith[ch] - kSkyHorizonBgr[ch]));
  return px;
}

}  // namespace aerotrack::hal::sim
