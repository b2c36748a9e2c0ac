// Image-mode scene renderer: sky and textured ground per pixel, obstacles ray cast over their
// projected bounds into a z-buffer, the person sprite placed by the projected torso and depth-tested
// per pixel. See scene_renderer.hpp.
#include "aerotrack/hal/sim/scene_renderer.hpp"

#include "aerotrack/hal/sim/background_shader.hpp"
#include "aerotrack/hal/sim/depth_camera.hpp"
#include "render_hash.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace aerotrack::hal::sim {
namespace {

constexpr double kNearM = 0.05;  // Obstacle parts nearer than this (camera z) are clipped.
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr double kNoHit = std::numeric_limits<double>::infinity();

using Colour = Eigen::Vector3d;  // B, G, R in [0, 255].

const Colour kBark(48.0, 68.0, 96.0);
const Colour kConcrete(150.0, 158.0, 166.0);

/// floor() as an integer, without a library call (x within +-9e18).
std::int64_t fastFloor(float x) {
  const auto i = static_cast<std::int64_t>(x);
  return static_cast<float>(i) > x ? i - 1 : i;
}

/// Rounds a colour channel; every colour drawn is a non-negative blend, so only the top needs a clamp.
std::uint8_t toByteF(float c) {
  return static_cast<std::uint8_t>(std::min(c, 255.0F) + 0.5F);  // NOLINT(bugprone-incorrect-roundings): c >= 0
}

/// One row's rays from o, and the light.
struct RowShading {
  RowRays rays;
  Eigen::Vector3f o, sun;
  float haze_m = 0.0F;
};

/// An obstacle span's per-pass buffers: hit points and 1 - haze (reused across spans and rows).
struct ObstacleSpanBuffers {
  std::array<float, BackgroundShader::kChunk> px, py, pz, keep;
};

/// Pixels [u0, u1) of a row, all showing obstacle `id` at depths depth_row[u] along the rays
/// d0 + u step from o: a face's panels or bark, lit by the sun, hazed with range. Single precision,
/// in two passes as the background (background_shader.hpp): the hit points and haze branch-free
/// (vectorised), then each pixel's face, texture cell and colour.
void shadeObstacleSpan(const ObstacleWorld& world, int id, const RowShading& frame, const float* depth_row, int u0,
                       int u1, cv::Vec3b* row, ObstacleSpanBuffers& buffers) {
  const std::size_t box_count = world.boxes().size();
  const bool is_box = static_cast<std::size_t>(id) < box_count;
  const Box* box = is_box ? &world.boxes()[static_cast<std::size_t>(id)] : nullptr;
  const Cylinder* cyl = is_box ? nullptr : &world.cylinders()[static_cast<std::size_t>(id) - box_count];
  const Eigen::Vector3f base = (is_box ? kConcrete : kBark).cast<float>();
  const Eigen::Vector3f horizon(kSkyHorizonBgr.data());
  const Eigen::Vector3f& sun = frame.sun;
  const Eigen::Vector3f &o = frame.o, &d0 = frame.rays.d0, &step = frame.rays.step;
  const float haze_m = frame.haze_m;
  const auto albedo0 = static_cast<float>(0.85 + 0.3 * hash01(id, 0, 3));
  // The texture's hashed cell (a box's panel, a trunk's furrow and band) changes every few pixels at
  // most: its last value is kept.
  std::int64_t last_i1 = std::numeric_limits<std::int64_t>::min(), last_i2 = 0;
  std::uint64_t last_salt = 0;
  float last_hash = 0.0F;
  const auto cellHash = [&](std::int64_t i1, std::int64_t i2, std::uint64_t salt) {
    if (i1 != last_i1 || i2 != last_i2 || salt != last_salt) {
      last_i1 = i1, last_i2 = i2, last_salt = salt;
      last_hash = static_cast<float>(hash01(i1, i2, salt));
    }
    return last_hash;
  };
  auto& [px, py, pz, keep] = buffers;
  for (int c0 = u0; c0 < u1; c0 += BackgroundShader::kChunk) {
    const int n = std::min(BackgroundShader::kChunk, u1 - c0);
    for (int k = 0; k < n; ++k) {
      const auto u = static_cast<float>(c0 + k);
      const float dx = d0.x() + u * step.x(), dy = d0.y() + u * step.y(), dz = d0.z() + u * step.z();
      const float t = depth_row[c0 + k];
      px[k] = o.x() + t * dx, py[k] = o.y() + t * dy, pz[k] = o.z() + t * dz;
      const float range_m = t * std::sqrt(dx * dx + dy * dy + dz * dz);
      keep[k] = haze_m / (range_m + haze_m);  // 1 - haze
    }
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector3f p(px[k], py[k], pz[k]);
      float albedo = albedo0;
      float lit = 0.0F;  // the normal's cosine to the sun
      if (box != nullptr) {
        int axis = 0;
        float best = std::numeric_limits<float>::infinity(), sign = 1.0F;
        for (int a = 0; a < 3; ++a) {  // the face hit: the plane nearest the hit point
          const float dl = std::abs(p[a] - static_cast<float>(box->min_W_m[a]));
          const float dh = std::abs(p[a] - static_cast<float>(box->max_W_m[a]));
          if (dl < best) best = dl, axis = a, sign = -1.0F;
          if (dh < best) best = dh, axis = a, sign = 1.0F;
        }
        lit = sign * sun[axis];
        // Panels of 1 m with dark seams, each panel a little different.
        const float s1 = p[(axis + 1) % 3], s2 = p[(axis + 2) % 3];
        const std::int64_t i1 = fastFloor(s1), i2 = fastFloor(s2);
        const bool seam = s1 - static_cast<float>(i1) < 0.03F || s2 - static_cast<float>(i2) < 0.03F;
        albedo *= seam ? 0.55F : 0.9F + 0.2F * cellHash(i1, i2, 5 + static_cast<std::uint64_t>(axis));
      } else {
        Eigen::Vector3f n_W = Eigen::Vector3f::Zero();
        if (p.z() >= static_cast<float>(cyl->z_max_m) - 1e-4F) {
          n_W.z() = 1.0F;
        } else if (p.z() <= static_cast<float>(cyl->z_min_m) + 1e-4F) {
          n_W.z() = -1.0F;
        } else {
          const auto inv_r = static_cast<float>(1.0 / cyl->radius_m);
          n_W.x() = (p.x() - static_cast<float>(cyl->center_W_m.x())) * inv_r;
          n_W.y() = (p.y() - static_cast<float>(cyl->center_W_m.y())) * inv_r;
        }
        lit = n_W.dot(sun);
        // Bark: furrows (by the normal's direction) broken into 0.4 m bands.
        albedo *= 0.8F + 0.35F * cellHash(fastFloor((n_W.x() + 2.0F * n_W.y()) * 3.0F), fastFloor(p.z() * 2.5F), 7);
      }
      const float shade = albedo * (0.45F + 0.6F * std::max(0.0F, lit));
      const Eigen::Vector3f colour = keep[k] * shade * base + (1.0F - keep[k]) * horizon;
      cv::Vec3b& out = row[c0 + k];
      for (int ch = 0; ch < 3; ++ch) out[ch] = toByteF(colour[ch]);
    }
  }
}

}  // namespace

rt::Status validate(const SceneRenderParams& p) {
  const auto fail = [](const std::string& what) { return rt::Status(rt::Error{"scene renderer: " + what}); };
  const CameraIntrinsics& k = p.intrinsics;
  if (k.width_px < 1 || k.height_px < 1 || k.width_px > 8192 || k.height_px > 8192)
    return fail("image size must be 1..8192 px");
  if (!(std::isfinite(k.fx_px) && std::isfinite(k.fy_px) && k.fx_px > 0.0 && k.fy_px > 0.0))
    return fail("focal lengths must be finite and > 0");
  if (!(std::isfinite(k.cx_px) && std::isfinite(k.cy_px))) return fail("principal point must be finite");
  for (const double d : k.distortion) {
    if (d != 0.0) return fail("distortion is not modelled; it must be zero");
  }
  if (!(p.max_range_m > 1.0 && p.max_range_m <= 1e4)) return fail("max_range_m must be in (1, 1e4]");
  if (!(p.haze_distance_m > 0.0 && std::isfinite(p.haze_distance_m))) return fail("haze_distance_m must be > 0");
  if (!(std::abs(p.sun_dir_W.norm() - 1.0) < 1e-6)) return fail("sun_dir_W must be a unit vector");
  return rt::ok();
}

rt::Expected<SceneRenderer> SceneRenderer::create(const SceneRenderParams& params, const PersonCastSpec& cast) {
  if (auto status = validate(params); !status) return status.error();
  auto loaded = loadCast(cast);
  if (!loaded) return loaded.error();
  return SceneRenderer(params, std::move(loaded.value()), GroundTexture::make());
}

void SceneRenderer::render(const ObstacleWorld& world, const Eigen::Isometry3d& T_WC, const PersonState* person,
                           cv::Mat& bgr, RenderScratch& scratch, std::size_t cast_index) const {
  const CameraIntrinsics& k = params_.intrinsics;
  bgr.create(k.height_px, k.width_px, CV_8UC3);
  scratch.depth_m.create(k.height_px, k.width_px, CV_32FC1);
  scratch.obstacle_id.create(k.height_px, k.width_px, CV_32SC1);
  scratch.depth_m.setTo(cv::Scalar(static_cast<double>(kInf)));
  scratch.obstacle_id.setTo(cv::Scalar(-1));
  rasterObstacles(world, T_WC, scratch);
  shade(world, T_WC, scratch, bgr);
  if (person != nullptr && cast_index < sprites_.size()) {
    const SpritePlacement placement = placeSprite(*person, T_WC, cast_index);
    if (placement.visible) drawPerson(placement, bgr, scratch.depth_m, RenderedPerson{person, cast_index});
  }
}

void SceneRenderer::render(const ObstacleWorld& world, const Eigen::Isometry3d& T_WC,
                           std::span<const RenderedPerson> persons, cv::Mat& bgr, RenderScratch& scratch) const {
  render(world, T_WC, nullptr, bgr, scratch);
  constexpr std::size_t kMaxDrawn = 32;
  std::array<SpritePlacement, kMaxDrawn> placements;
  std::array<std::size_t, kMaxDrawn> order{};
  std::size_t count = 0;
  for (std::size_t i = 0; i < persons.size() && count < kMaxDrawn; ++i) {
    if (persons[i].state == nullptr) continue;
    if (persons[i].person >= sprites_.size()) continue;
    placements[count] = placeSprite(*persons[i].state, T_WC, persons[i].person);
    if (!placements[count].visible) continue;
    order[count] = i;
    ++count;
  }
  // Farthest first (ties: listed order), so that nearer persons are drawn over farther ones.
  std::array<std::size_t, kMaxDrawn> slots{};
  for (std::size_t i = 0; i < count; ++i) slots[i] = i;
  std::stable_sort(slots.begin(), slots.begin() + static_cast<std::ptrdiff_t>(count),
                   [&](std::size_t a, std::size_t b) { return placements[a].depth_m > placements[b].depth_m; });
  for (std::size_t i = 0; i < count; ++i)
    drawPerson(placements[slots[i]], bgr, scratch.depth_m, persons[order[slots[i]]]);
}

void SceneRenderer::rasterObstacles(const ObstacleWorld& world, const Eigen::Isometry3d& T_WC,
                                    RenderScratch& scratch) const {
  const CameraIntrinsics& k = params_.intrinsics;
  const Eigen::Matrix3d& R_WC = T_WC.linear();
  const Eigen::Matrix3d R_CW = R_WC.transpose();
  const Eigen::Vector3d o_W = T_WC.translation();
  const Eigen::Vector3d step_W = R_WC.col(0) / k.fx_px;
  const double max_range = params_.max_range_m;
  const std::size_t box_count = world.boxes().size();
  const std::size_t count = box_count + world.cylinders().size();
  for (std::size_t id = 0; id < count; ++id) {
    const bool is_box = id < box_count;
    const Cylinder* cyl = is_box ? nullptr : &world.cylinders()[id - box_count];
    const Box aabb = is_box ? world.boxes()[id] : boundingBox(*cyl);
    if (distanceTo(aabb, o_W) > max_range) continue;
    PixelRect rect;
    if (!projectBoxToPixels(aabb, R_CW, o_W, k, kNearM, rect)) continue;
    // Cylinder seen from outside its footprint: the side by the 2D quadratic, then the caps.
    const double ox = cyl ? o_W.x() - cyl->center_W_m.x() : 0.0;
    const double oy = cyl ? o_W.y() - cyl->center_W_m.y() : 0.0;
    const double c = cyl ? ox * ox + oy * oy - cyl->radius_m * cyl->radius_m : 0.0;
    const bool fast_cylinder = cyl != nullptr && c > 0.0;
    const int label = static_cast<int>(id);
    for (int v = rect.v0; v <= rect.v1; ++v) {
      float* depth_row = scratch.depth_m.ptr<float>(v);
      int* id_row = scratch.obstacle_id.ptr<int>(v);
      Eigen::Vector3d d_W =
          R_WC * Eigen::Vector3d((rect.u0 + 0.5 - k.cx_px) / k.fx_px, (v + 0.5 - k.cy_px) / k.fy_px, 1.0);
      for (int u = rect.u0; u <= rect.u1; ++u, d_W += step_W) {
        const double t_max = std::min(static_cast<double>(depth_row[u]), max_range);
        double t = kNoHit;
        if (fast_cylinder) {
          const double b = ox * d_W.x() + oy * d_W.y();
          if (b >= 0.0) continue;  // moving away from the axis
          const double a = d_W.x() * d_W.x() + d_W.y() * d_W.y();
          const double disc = b * b - a * c;
          if (disc < 0.0) continue;
          const double t_side = (-b - std::sqrt(disc)) / a;
          const double z = o_W.z() + t_side * d_W.z();
          if (z >= cyl->z_min_m && z <= cyl->z_max_m) {
            t = t_side;
          } else if (d_W.z() != 0.0) {  // over or under the side: through a cap?
            const double z_cap = z > cyl->z_max_m ? cyl->z_max_m : cyl->z_min_m;
            const double t_cap = (z_cap - o_W.z()) / d_W.z();
            const double px = ox + t_cap * d_W.x(), py = oy + t_cap * d_W.y();
            if (t_cap > t_side && px * px + py * py <= cyl->radius_m * cyl->radius_m) t = t_cap;
          }
        } else {
          const Ray ray(o_W, d_W);
          const std::optional<double> hit = is_box ? firstHit(aabb, ray, t_max) : firstHit(*cyl, ray, t_max);
          if (hit) t = *hit;
        }
        if (t < kNearM || t >= t_max) continue;
        depth_row[u] = static_cast<float>(t);
        id_row[u] = label;
      }
    }
  }
}

void SceneRenderer::shade(const ObstacleWorld& world, const Eigen::Isometry3d& T_WC, const RenderScratch& scratch,
                          cv::Mat& bgr) const {
  const CameraIntrinsics& k = params_.intrinsics;
  const Eigen::Matrix3d& R_WC = T_WC.linear();
  const Eigen::Vector3d o_W = T_WC.translation();
  BackgroundShader background(*ground_, o_W, k.fx_px, params_.haze_distance_m);
  RowShading frame;
  frame.o = o_W.cast<float>();
  frame.sun = params_.sun_dir_W.cast<float>();
  frame.haze_m = static_cast<float>(params_.haze_distance_m);
  ObstacleSpanBuffers buffers{};
  for (int v = 0; v < k.height_px; ++v) {
    cv::Vec3b* row = bgr.ptr<cv::Vec3b>(v);
    const float* depth_row = scratch.depth_m.ptr<float>(v);
    const int* id_row = scratch.obstacle_id.ptr<int>(v);
    frame.rays = BackgroundShader::rowRays(R_WC, k.fx_px, k.fy_px, k.cx_px, k.cy_px, v);
    int u = 0;
    while (u < k.width_px) {  // runs of one obstacle, or of background, shaded together
      const int id = id_row[u];
      int end = u + 1;
      while (end < k.width_px && (id < 0 ? id_row[end] < 0 : id_row[end] == id)) ++end;
      if (id < 0) {
        background.shadeSpan(frame.rays, u, end, row);
      } else {
        shadeObstacleSpan(world, id, frame, depth_row, u, end, row, buffers);
      }
      u = end;
    }
  }
}

}  // namespace aerotrack::hal::sim
