// Simulated D435-like depth camera (see depth_camera.hpp). Rendering exploits that all pixel rays
// share one origin: the ground is analytic per pixel, and each obstacle within range is tested
// (with the exact ray tests of geometry.hpp) only against the pixels its bounding box projects
// onto, keeping the nearest depth per pixel (a z-buffer, as in rasterization). The result is
// what ObstacleWorld::raycast gives per pixel, at a cost that grows with the pixels the
// obstacles cover rather than with ray length. Then the D400 noise model sigma = k z^2 and
// random dropout.
#include "aerotrack/hal/sim/depth_camera.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <string>

#include "aerotrack/hal/depth_units.hpp"

namespace aerotrack::hal::sim {
namespace {

constexpr int kMaxSidePx = 8192;
constexpr double kNoHit = std::numeric_limits<double>::infinity();

/// The camera's pixel rays: pixel (u, v) looks along (x, y, 1) in C through its centre
/// (u + 0.5, v + 0.5), i.e. along R_WC * (x, y, 1) / |(x, y, 1)| in W.
struct PixelRays {
  PixelRays(const Eigen::Isometry3d& T_WC, const hal::CameraIntrinsics& intrinsics)
      : R_WC(T_WC.linear()), p_WC_m(T_WC.translation()), k(intrinsics) {}

  Eigen::Vector3d dirC(int u, int v) const {
    return {(u + 0.5 - k.cx_px) / k.fx_px, (v + 0.5 - k.cy_px) / k.fy_px, 1.0};
  }
  double norm(int u, int v) const { return dirC(u, v).norm(); }

  Eigen::Matrix3d R_WC;
  Eigen::Vector3d p_WC_m;
  hal::CameraIntrinsics k;
};

double tanHalf(double fov_deg) {
  return std::tan(0.5 * fov_deg * std::numbers::pi / 180.0);
}

}  // namespace

bool projectBoxToPixels(const Box& box, const Eigen::Matrix3d& R_CW, const Eigen::Vector3d& p_WC_m,
                        const hal::CameraIntrinsics& k, double near_m, PixelRect& rect) {
  std::array<Eigen::Vector3d, 8> corner_C;
  for (std::size_t i = 0; i < corner_C.size(); ++i) {
    const Eigen::Vector3d corner_W((i & 1U) ? box.max_W_m.x() : box.min_W_m.x(),
                                   (i & 2U) ? box.max_W_m.y() : box.min_W_m.y(),
                                   (i & 4U) ? box.max_W_m.z() : box.min_W_m.z());
    corner_C[i] = R_CW * (corner_W - p_WC_m);
  }
  double u_min = kNoHit;
  double u_max = -kNoHit;
  double v_min = kNoHit;
  double v_max = -kNoHit;
  const auto add = [&](const Eigen::Vector3d& q_C) {
    const double u = k.fx_px * q_C.x() / q_C.z() + k.cx_px;
    const double v = k.fy_px * q_C.y() / q_C.z() + k.cy_px;
    u_min = std::min(u_min, u);
    u_max = std::max(u_max, u);
    v_min = std::min(v_min, v);
    v_max = std::max(v_max, v);
  };
  for (std::size_t i = 0; i < corner_C.size(); ++i) {
    if (corner_C[i].z() >= near_m) add(corner_C[i]);
    for (const std::size_t bit : {1U, 2U, 4U}) {  // The box edges from corner i.
      const std::size_t j = i | bit;
      if (j == i || (corner_C[i].z() >= near_m) == (corner_C[j].z() >= near_m)) continue;
      const double s = (near_m - corner_C[i].z()) / (corner_C[j].z() - corner_C[i].z());
      Eigen::Vector3d cut_C = corner_C[i] + s * (corner_C[j] - corner_C[i]);
      cut_C.z() = near_m;
      add(cut_C);
    }
  }
  if (!(u_min <= u_max)) return false;  // Nothing in front.
  // Pixel u's centre is at u + 0.5: it is in range if u_min <= u + 0.5 <= u_max.
  const auto range = [](double lo, double hi, int size, int& first, int& last) {
    const double a = std::floor(lo - 0.5) - 1.0;
    const double b = std::ceil(hi - 0.5) + 1.0;
    if (b < 0.0 || a > size - 1.0) return false;
    first = static_cast<int>(std::max(a, 0.0));
    last = static_cast<int>(std::min(b, size - 1.0));
    return true;
  };
  return range(u_min, u_max, k.width_px, rect.u0, rect.u1) && range(v_min, v_max, k.height_px, rect.v0, rect.v1);
}

rt::Status DepthCameraParams::validate(const DepthCameraParams& params) {
  const auto fail = [](const std::string& what) { return rt::Status(rt::Error{"depth camera: " + what}); };
  if (params.width_px < 1 || params.width_px > kMaxSidePx || params.height_px < 1 || params.height_px > kMaxSidePx) {
    return fail("width_px and height_px must be in [1, " + std::to_string(kMaxSidePx) + "], got " +
                std::to_string(params.width_px) + " x " + std::to_string(params.height_px));
  }
  if (!(params.hfov_deg > 0.0 && params.hfov_deg < 180.0) || !(params.vfov_deg > 0.0 && params.vfov_deg < 180.0)) {
    return fail("hfov_deg and vfov_deg must be in (0, 180), got " + std::to_string(params.hfov_deg) + " and " +
                std::to_string(params.vfov_deg));
  }
  if (!(params.min_range_m >= 0.0) || !(params.min_range_m < params.max_range_m) ||
      !std::isfinite(params.max_range_m)) {
    return fail("need 0 <= min_range_m < max_range_m < inf, got " + std::to_string(params.min_range_m) + " and " +
                std::to_string(params.max_range_m));
  }
  if (!(params.noise_coeff_per_m >= 0.0) || !std::isfinite(params.noise_coeff_per_m)) {
    return fail("noise_coeff_per_m must be finite and >= 0, got " + std::to_string(params.noise_coeff_per_m));
  }
  if (!(params.dropout_probability >= 0.0 && params.dropout_probability <= 1.0)) {
    return fail("dropout_probability must be in [0, 1], got " + std::to_string(params.dropout_probability));
  }
  return rt::ok();
}

hal::CameraIntrinsics depthIntrinsics(const DepthCameraParams& params) {
  hal::CameraIntrinsics k;
  k.width_px = params.width_px;
  k.height_px = params.height_px;
  k.cx_px = 0.5 * params.width_px;
  k.cy_px = 0.5 * params.height_px;
  k.fx_px = k.cx_px / tanHalf(params.hfov_deg);
  k.fy_px = k.cy_px / tanHalf(params.vfov_deg);
  return k;
}

void renderDepth(const ObstacleWorld& world, const Eigen::Isometry3d& T_WC, const DepthCameraParams& params,
                 std::mt19937_64& rng, cv::Mat& depth_m, std::span<const Cylinder> extra_cylinders) {
  depth_m.create(params.height_px, params.width_px, CV_32FC1);
  const PixelRays rays(T_WC, depthIntrinsics(params));
  const double max_range_m = params.max_range_m;
  // Longest pixel ray direction (x, y, 1): a corner's. A hit at ray length t has depth t / norm.
  const double norm_max = rays.norm(0, 0);

  // 1. The ground (the half-space z <= 0) per pixel, as camera-frame z; +inf: nothing in range.
  const double height_m = rays.p_WC_m.z();
  for (int v = 0; v < params.height_px; ++v) {
    float* row = depth_m.ptr<float>(v);
    for (int u = 0; u < params.width_px; ++u) {
      const Eigen::Vector3d ray_C = rays.dirC(u, v);
      const double norm = ray_C.norm();
      const double dir_z_W = rays.R_WC.row(2).dot(ray_C) / norm;
      double z_m = kNoHit;
      if (height_m <= 0.0) {
        z_m = 0.0;
      } else if (dir_z_W < 0.0) {
        const double t_m = height_m / -dir_z_W;
        if (t_m <= max_range_m * norm) z_m = t_m / norm;
      }
      row[u] = static_cast<float>(z_m);
    }
  }

  // 2. Each obstacle within range, over the pixels its bounding box can cover: the pixel's ray
  // against the obstacle, keeping the nearer depth (a z-buffer in depth_m).
  const auto splat = [&](const auto& obstacle, const Box& aabb) {
    const double gap_m = distanceTo(aabb, rays.p_WC_m);
    if (gap_m > max_range_m * norm_max) return;
    PixelRect rect{0, params.width_px - 1, 0, params.height_px - 1};
    // Every hit is >= gap_m from the camera, so its depth is >= gap_m / norm_max: clip there.
    if (gap_m > 0.0 &&
        !projectBoxToPixels(aabb, rays.R_WC.transpose(), rays.p_WC_m, rays.k, 0.5 * gap_m / norm_max, rect))
      return;
    for (int v = rect.v0; v <= rect.v1; ++v) {
      float* row = depth_m.ptr<float>(v);
      for (int u = rect.u0; u <= rect.u1; ++u) {
        const Eigen::Vector3d ray_C = rays.dirC(u, v);
        const double norm = ray_C.norm();
        const Ray ray(rays.p_WC_m, rays.R_WC * (ray_C / norm));
        const double t_max_m = std::min(static_cast<double>(row[u]), max_range_m) * norm;
        if (const auto t_m = firstHit(obstacle, ray, t_max_m)) {
          row[u] = std::min(row[u], static_cast<float>(*t_m / norm));
        }
      }
    }
  };
  for (const Box& box : world.boxes()) splat(box, box);
  for (const Cylinder& cyl : world.cylinders()) splat(cyl, boundingBox(cyl));
  for (const Cylinder& cyl : extra_cylinders) splat(cyl, boundingBox(cyl));

  // 3. Sensor effects in row-major order: range limits, dropout, noise.
  std::normal_distribution<double> normal(0.0, 1.0);
  const bool noise = params.noise_coeff_per_m > 0.0;
  // Dropout without a draw per pixel: the number of valid pixels kept before the next dropped
  // one is geometric(p), drawn once per dropout (p = 0: never; p = 1: always).
  const double p_drop = params.dropout_probability;
  std::geometric_distribution<std::int64_t> kept_run(p_drop > 0.0 && p_drop < 1.0 ? p_drop : 0.5);
  const auto nextRun = [&]() -> std::int64_t {
    if (p_drop <= 0.0) return std::numeric_limits<std::int64_t>::max();
    if (p_drop >= 1.0) return 0;
    return kept_run(rng);
  };
  std::int64_t keep = nextRun();  // Valid pixels still to keep before the next dropout.
  for (int v = 0; v < params.height_px; ++v) {
    float* row = depth_m.ptr<float>(v);
    for (int u = 0; u < params.width_px; ++u) {
      double z_m = static_cast<double>(row[u]);
      float out = 0.0F;
      if (z_m >= params.min_range_m && z_m <= max_range_m) {
        if (keep == 0) {
          keep = nextRun();  // Dropped: stays 0.
        } else {
          --keep;
          if (noise) z_m += params.noise_coeff_per_m * z_m * z_m * normal(rng);
          out = depthFromZ16(depthToZ16(z_m));  // the D435's Z16 output: whole millimetres
        }
      }
      row[u] = out;
    }
  }
}

}  // namespace aerotrack::hal::sim
