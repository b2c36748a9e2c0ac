// Image-mode scene renderer: sky and textured ground per pixel, obstacles ray cast over their
// projected bounds into a z-buffer, the person sprite placed by the projected torso and depth-tested
// per pixel. See scene_renderer.hpp.
#include "aerotrack/hal/sim/scene_renderer.hpp"

#include "aerotrack/hal/sim/background_shader.hpp"
#include "aerotrack/hal/sim/depth_camera.hpp"
#include "render_hash.hpp"
#include "render_math.hpp"

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

/// One row's rays from o, and the light.
struct RowShading {
  RowRays rays;
  Eigen::Vector3f o, sun;
  float haze_m = 0.0F;
};

/// An obstacle span's per-pass buffers (reused across spans and rows): hit points, 1 - haze, the
/// light, texture cells and their hashes, and the colour's channels.
struct ObstacleSpanBuffers {
  std::array<float, BackgroundShader::kChunk> px, py, pz, keep, light, cell_hash;
  std::array<int, BackgroundShader::kChunk> cell1, cell2;
  std::array<std::uint8_t, BackgroundShader::kChunk> b, g, r;
};

/// The shared first pass of an obstacle span: hit points along the rays d0 + u step from o at depths
/// depth_row[u], and 1 - haze. Branch-free (vectorised).
void hitPoints(const RowShading& frame, const float* depth_row, int c0, int n, ObstacleSpanBuffers& buffers) {
  const Eigen::Vector3f &o = frame.o, &d0 = frame.rays.d0, &step = frame.rays.step;
  const float haze_m = frame.haze_m;
  auto& [px, py, pz, keep, light, cell_hash, cell1, cell2, b, g, r] = buffers;
  for (int k = 0; k < n; ++k) {
    const auto u = static_cast<float>(c0 + k);
    const float dx = d0.x() + u * step.x(), dy = d0.y() + u * step.y(), dz = d0.z() + u * step.z();
    const float t = depth_row[c0 + k];
    px[k] = o.x() + t * dx, py[k] = o.y() + t * dy, pz[k] = o.z() + t * dz;
    const float range_m = t * std::sqrt(dx * dx + dy * dy + dz * dz);
    keep[k] = haze_m / (range_m + haze_m);  // 1 - haze
  }
}

/// The last passes of an obstacle span: the colour from albedo x light, hazed (vectorised), then the
/// bytes written to the row.
void writeColours(const Eigen::Vector3f& base, float albedo0, float hash_gain, float hash_offset, int c0, int n,
                  cv::Vec3b* row, ObstacleSpanBuffers& buffers) {
  const Eigen::Vector3f horizon(kSkyHorizonBgr.data());
  auto& [px, py, pz, keep, light, cell_hash, cell1, cell2, b, g, r] = buffers;
  for (int k = 0; k < n; ++k) {
    const float shade = albedo0 * (hash_offset + hash_gain * cell_hash[k]) * light[k];
    const float lit = keep[k] * shade, hazed = 1.0F - keep[k];
    b[k] = toByte(lit * base.x() + hazed * horizon.x());
    g[k] = toByte(lit * base.y() + hazed * horizon.y());
    r[k] = toByte(lit * base.z() + hazed * horizon.z());
  }
  for (int k = 0; k < n; ++k) row[c0 + k] = cv::Vec3b(b[k], g[k], r[k]);
}

/// Pixels [u0, u1) of a row, all showing box `box`, at depths depth_row[u] along the rays d0 + u step from
/// o: a face's panels, lit by the sun, hazed with range. Single precision, in passes as the background
/// (background_shader.hpp): the hit points and haze branch-free (vectorised), then each pixel's face and
/// hashed panel (kept while it does not change), then the colour (vectorised).
void shadeBoxSpan(const Box& box, int id, const RowShading& frame, const float* depth_row, int u0, int u1,
                  cv::Vec3b* row, ObstacleSpanBuffers& buffers) {
  const auto albedo0 = static_cast<float>(0.85 + 0.3 * hash01(id, 0, 3));
  const Eigen::Vector3f lo = box.min_W_m.cast<float>(), hi = box.max_W_m.cast<float>();
  const Eigen::Vector3f sun = frame.sun;
  std::int64_t last_i1 = std::numeric_limits<std::int64_t>::min(), last_i2 = 0;
  int last_axis = -1;
  float last_hash = 0.0F;
  auto& [px, py, pz, keep, light, cell_hash, cell1, cell2, b, g, r] = buffers;
  for (int c0 = u0; c0 < u1; c0 += BackgroundShader::kChunk) {
    const int n = std::min(BackgroundShader::kChunk, u1 - c0);
    hitPoints(frame, depth_row, c0, n, buffers);
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector3f p(px[k], py[k], pz[k]);
      int axis = 0;
      float best = std::numeric_limits<float>::infinity(), sign = 1.0F;
      for (int a = 0; a < 3; ++a) {  // the face hit: the plane nearest the hit point
        const float dl = std::abs(p[a] - lo[a]);
        const float dh = std::abs(p[a] - hi[a]);
        if (dl < best) best = dl, axis = a, sign = -1.0F;
        if (dh < best) best = dh, axis = a, sign = 1.0F;
      }
      light[k] = 0.45F + 0.6F * std::max(0.0F, sign * sun[axis]);
      // Panels of 1 m with dark seams, each panel a little different: the seam as a hash of -1 (gain 1).
      const float s1 = p[(axis + 1) % 3], s2 = p[(axis + 2) % 3];
      const std::int64_t i1 = fastFloor(s1), i2 = fastFloor(s2);
      const bool seam = s1 - static_cast<float>(i1) < 0.03F || s2 - static_cast<float>(i2) < 0.03F;
      if (i1 != last_i1 || i2 != last_i2 || axis != last_axis) {
        last_i1 = i1, last_i2 = i2, last_axis = axis;
        last_hash = static_cast<float>(hash01(i1, i2, 5 + static_cast<std::uint64_t>(axis)));
      }
      // albedo x (0.9 + 0.2 h), or x 0.55 on a seam: 0.9 + 0.2 h' with h' = -1.75.
      cell_hash[k] = seam ? -1.75F : last_hash;
    }
    writeColours(kConcrete.cast<float>(), albedo0, 0.2F, 0.9F, c0, n, row, buffers);
  }
}

/// The same for cylinder `cyl` (a trunk): bark furrows by the normal's direction, broken into 0.4 m bands,
/// flat caps. Here the normal, light and texture cells are branch-free too (vectorised); only the cells'
/// hashes are looked up one pixel at a time, kept while the cell does not change.
void shadeCylinderSpan(const Cylinder& cyl, int id, const RowShading& frame, const float* depth_row, int u0, int u1,
                       cv::Vec3b* row, ObstacleSpanBuffers& buffers) {
  const auto albedo0 = static_cast<float>(0.85 + 0.3 * hash01(id, 0, 3));
  const auto inv_r = static_cast<float>(1.0 / cyl.radius_m);
  const auto cx = static_cast<float>(cyl.center_W_m.x()), cy = static_cast<float>(cyl.center_W_m.y());
  const float z_top = static_cast<float>(cyl.z_max_m) - 1e-4F, z_bottom = static_cast<float>(cyl.z_min_m) + 1e-4F;
  const float sx = frame.sun.x(), sy = frame.sun.y(), sz = frame.sun.z();
  int last_1 = std::numeric_limits<int>::min(), last_2 = 0;
  float last_hash = 0.0F;
  auto& [px, py, pz, keep, light, cell_hash, cell1, cell2, b, g, r] = buffers;
  for (int c0 = u0; c0 < u1; c0 += BackgroundShader::kChunk) {
    const int n = std::min(BackgroundShader::kChunk, u1 - c0);
    hitPoints(frame, depth_row, c0, n, buffers);
    for (int k = 0; k < n; ++k) {
      const bool top = pz[k] >= z_top, bottom = pz[k] <= z_bottom, side = !(top | bottom);
      // The outward normal: radial on the side, up or down on a cap.
      const float nx = side ? (px[k] - cx) * inv_r : 0.0F;
      const float ny = side ? (py[k] - cy) * inv_r : 0.0F;
      const float down = bottom ? -1.0F : 0.0F;
      const float nz = top ? 1.0F : down;
      light[k] = 0.45F + 0.6F * maxF(0.0F, nx * sx + ny * sy + nz * sz);
      cell1[k] = floorToInt((nx + 2.0F * ny) * 3.0F);
      cell2[k] = floorToInt(pz[k] * 2.5F);
    }
    for (int k = 0; k < n; ++k) {
      if (cell1[k] != last_1 || cell2[k] != last_2) {
        last_1 = cell1[k], last_2 = cell2[k];
        last_hash = static_cast<float>(hash01(last_1, last_2, 7));
      }
      cell_hash[k] = last_hash;
    }
    writeColours(kBark.cast<float>(), albedo0, 0.35F, 0.8F, c0, n, row, buffers);
  }
}

/// A trunk's depths along one row, seen from outside its footprint (the common case, the forest's): for
/// pixels [u0, u0 + n) of rays d0 + k step (origin at (ox, oy, oz), the axis at x = y = 0), the side's
/// first hit, or -1 where the ray passes over or under the side and may meet a cap, or infinity (a miss).
/// Branch-free single precision (vectorised); the discriminant in Lagrange's form, a r^2 - (o x d)^2,
/// without b^2 - a c's cancellation far from the trunk.
void cylinderSideHits(const Eigen::Vector3f& d0, const Eigen::Vector3f& step, float ox, float oy, float oz, float r2,
                      float z_min, float z_max, int n, float* t_out) {
  // Locals, not references: t_out could alias them, and GCC would not vectorise the loop.
  const float d0x = d0.x(), d0y = d0.y(), d0z = d0.z(), sx = step.x(), sy = step.y(), sz = step.z();
  for (int k = 0; k < n; ++k) {
    const auto kf = static_cast<float>(k);
    const float dx = d0x + kf * sx, dy = d0y + kf * sy, dz = d0z + kf * sz;
    const float b = ox * dx + oy * dy;  // < 0: towards the axis
    const float a = dx * dx + dy * dy;
    const float cross = ox * dy - oy * dx;
    const float disc = a * r2 - cross * cross;
    const float t = (-b - std::sqrt(maxF(disc, 0.0F))) / a;
    const float z = oz + t * dz;
    // Bitwise, not short-circuit: no branch, so GCC vectorises the loop.
    const bool meets = (b < 0.0F) & (disc >= 0.0F) & (a > 0.0F);
    const bool on_side = (z >= z_min) & (z <= z_max);
    const float side_or_cap = on_side ? t : -1.0F;
    t_out[k] = meets ? side_or_cap : kInf;  // NOLINT(bugprone-narrowing-conversions): float to float (a clang-tidy 14
                                            // false positive on infinity)
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
    const int label = static_cast<int>(id);
    if (cyl != nullptr && (o_W.head<2>() - cyl->center_W_m).squaredNorm() > cyl->radius_m * cyl->radius_m) {
      rasterCylinderFromOutside(*cyl, label, T_WC, rect, scratch);
      continue;
    }
    for (int v = rect.v0; v <= rect.v1; ++v) {
      float* depth_row = scratch.depth_m.ptr<float>(v);
      int* id_row = scratch.obstacle_id.ptr<int>(v);
      Eigen::Vector3d d_W =
          R_WC * Eigen::Vector3d((rect.u0 + 0.5 - k.cx_px) / k.fx_px, (v + 0.5 - k.cy_px) / k.fy_px, 1.0);
      for (int u = rect.u0; u <= rect.u1; ++u, d_W += step_W) {
        const double t_max = std::min(static_cast<double>(depth_row[u]), max_range);
        const Ray ray(o_W, d_W);
        const std::optional<double> hit = is_box ? firstHit(aabb, ray, t_max) : firstHit(*cyl, ray, t_max);
        if (!hit || *hit < kNearM || *hit >= t_max) continue;
        depth_row[u] = static_cast<float>(*hit);
        id_row[u] = label;
      }
    }
  }
}

void SceneRenderer::rasterCylinderFromOutside(const Cylinder& cyl, int label, const Eigen::Isometry3d& T_WC,
                                              const PixelRect& rect, RenderScratch& scratch) const {
  const CameraIntrinsics& k = params_.intrinsics;
  const Eigen::Matrix3d& R_WC = T_WC.linear();
  const Eigen::Vector3d o_W = T_WC.translation();
  const auto max_range = static_cast<float>(params_.max_range_m);
  const auto near_m = static_cast<float>(kNearM);
  // The camera relative to the trunk's axis (in double, then float: small numbers near the trunk).
  const double ox = o_W.x() - cyl.center_W_m.x(), oy = o_W.y() - cyl.center_W_m.y();
  const double r2 = cyl.radius_m * cyl.radius_m;
  const Eigen::Vector3d step_W = R_WC.col(0) / k.fx_px;  // one pixel to the right
  const Eigen::Vector3f step = step_W.cast<float>();
  std::array<float, BackgroundShader::kChunk> t_side{};
  for (int v = rect.v0; v <= rect.v1; ++v) {
    float* depth_row = scratch.depth_m.ptr<float>(v);
    int* id_row = scratch.obstacle_id.ptr<int>(v);
    const Eigen::Vector3d d_row =
        R_WC * Eigen::Vector3d((rect.u0 + 0.5 - k.cx_px) / k.fx_px, (v + 0.5 - k.cy_px) / k.fy_px, 1.0);
    for (int c0 = rect.u0; c0 <= rect.u1; c0 += BackgroundShader::kChunk) {
      const int n = std::min(BackgroundShader::kChunk, rect.u1 + 1 - c0);
      const Eigen::Vector3f d0 = (d_row + static_cast<double>(c0 - rect.u0) * step_W).cast<float>();
      cylinderSideHits(d0, step, static_cast<float>(ox), static_cast<float>(oy), static_cast<float>(o_W.z()),
                       static_cast<float>(r2), static_cast<float>(cyl.z_min_m), static_cast<float>(cyl.z_max_m), n,
                       t_side.data());
      for (int j = 0; j < n; ++j) {
        float t = t_side[static_cast<std::size_t>(j)];
        if (t == kInf) continue;
        const int u = c0 + j;
        if (t < 0.0F) {  // over or under the side: through a cap? (rare: a trunk's top seen from above)
          const Eigen::Vector3d d_W = d_row + static_cast<double>(u - rect.u0) * step_W;
          t = kInf;
          const Ray ray(o_W, d_W);
          if (const std::optional<double> hit = firstHit(cyl, ray, static_cast<double>(max_range)))
            t = static_cast<float>(*hit);
        }
        if (t < near_m || t >= minF(depth_row[u], max_range)) continue;
        depth_row[u] = t;
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
      const auto obstacle = static_cast<std::size_t>(id);
      if (id < 0) {
        background.shadeSpan(frame.rays, u, end, row);
      } else if (obstacle < world.boxes().size()) {
        shadeBoxSpan(world.boxes()[obstacle], id, frame, depth_row, u, end, row, buffers);
      } else {
        shadeCylinderSpan(world.cylinders()[obstacle - world.boxes().size()], id, frame, depth_row, u, end, row,
                          buffers);
      }
      u = end;
    }
  }
}

}  // namespace aerotrack::hal::sim
