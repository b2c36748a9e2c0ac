// Image-mode scene renderer: sky and textured ground per pixel, obstacles ray cast over their
// projected bounds into a z-buffer, the person sprite placed by the projected torso and depth-tested
// per pixel. See scene_renderer.hpp.
#include "aerotrack/hal/sim/scene_renderer.hpp"

#include "aerotrack/hal/sim/depth_camera.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace aerotrack::hal::sim {
namespace {

constexpr double kNearM = 0.05;  // Obstacle parts nearer than this (camera z) are clipped.
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr double kNoHit = std::numeric_limits<double>::infinity();
constexpr int kGroundSize = 512;        // texels along each side of the ground texture's period
constexpr double kGroundTexelM = 0.05;  // level 0

using Colour = Eigen::Vector3d;  // B, G, R in [0, 255].

const Colour kSkyHorizon(235.0, 218.0, 200.0);
const Colour kSkyZenith(205.0, 140.0, 80.0);
const Colour kGrass(52.0, 112.0, 70.0);
const Colour kBark(48.0, 68.0, 96.0);
const Colour kConcrete(150.0, 158.0, 166.0);

/// Uniform in [0, 1) from two integer cell coordinates and a salt (splitmix64 finaliser).
double hash01(std::int64_t i, std::int64_t j, std::uint64_t salt) {
  std::uint64_t z = static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ULL ^
                    (static_cast<std::uint64_t>(j) + 0x632BE59BD9B4E019ULL) * 0xC2B2AE3D27D4EB4FULL ^ salt;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53;
}

/// floor() as an integer, without a library call (x within +-9e18).
std::int64_t fastFloor(double x) {
  const auto i = static_cast<std::int64_t>(x);
  return static_cast<double>(i) > x ? i - 1 : i;
}

/// floor(log2(x)) for x >= 1, from the exponent bits.
int floorLog2(double x) {
  return static_cast<int>((std::bit_cast<std::uint64_t>(x) >> 52) & 0x7FF) - 1023;
}

/// Rounds a colour channel; every colour drawn is a non-negative blend, so only the top needs a clamp.
std::uint8_t toByte(double c) {
  return static_cast<std::uint8_t>(std::min(c, 255.0) + 0.5);  // NOLINT(bugprone-incorrect-roundings): c >= 0
}

std::uint8_t toByteF(float c) {
  return static_cast<std::uint8_t>(std::min(c, 255.0F) + 0.5F);  // NOLINT(bugprone-incorrect-roundings): c >= 0
}

void store(cv::Vec3b& px, const Colour& c) {
  px[0] = toByte(c[0]);
  px[1] = toByte(c[1]);
  px[2] = toByte(c[2]);
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
  // The ground texture: 1.6 m tiles, 0.2 m cells and 0.05 m texels of hashed brightness, periodic.
  auto ground = std::make_shared<GroundTexture>();
  std::vector<float> level(static_cast<std::size_t>(kGroundSize) * kGroundSize);
  for (int j = 0; j < kGroundSize; ++j) {
    for (int i = 0; i < kGroundSize; ++i) {
      double shade = (((i / 32) + (j / 32)) & 1) ? 1.06 : 0.94;
      shade += 0.22 * (hash01(i / 4, j / 4, 1) - 0.5);
      shade += 0.16 * (hash01(i, j, 2) - 0.5);
      level[static_cast<std::size_t>(j) * kGroundSize + static_cast<std::size_t>(i)] = static_cast<float>(shade);
    }
  }
  for (int size = kGroundSize; size >= 1; size /= 2) {
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
  return SceneRenderer(params, std::move(loaded.value()), std::move(ground));
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
  const Eigen::Vector3d step_W = R_WC.col(0) / k.fx_px;
  const double haze_m = params_.haze_distance_m;
  const double inv_f = 1.0 / k.fx_px;
  const std::size_t box_count = world.boxes().size();
  const bool above_ground = o_W.z() > 0.0;
  const double inv_height = above_ground ? 1.0 / o_W.z() : 0.0;
  const auto& levels = ground_->levels;
  const int top_level = static_cast<int>(levels.size()) - 1;
  const double footprint_scale = inv_f / kGroundTexelM;
  std::array<float, 16> inv_texel_f{};
  for (std::size_t l = 0; l < inv_texel_f.size(); ++l)
    inv_texel_f[l] = static_cast<float>(1.0 / std::ldexp(kGroundTexelM, static_cast<int>(l)));
  // The ground branch's constants in single precision. Coordinates wrap at the texture's 25.6 m
  // period, so the camera's x, y are taken modulo it first (float keeps mm resolution there).
  const double period_m = kGroundSize * kGroundTexelM;
  const float o_x = static_cast<float>(o_W.x() - period_m * std::floor(o_W.x() / period_m));
  const float o_y = static_cast<float>(o_W.y() - period_m * std::floor(o_W.y() / period_m));
  const float o_z = static_cast<float>(o_W.z());
  const float inv_height_f = static_cast<float>(inv_height);
  const float footprint_scale_f = static_cast<float>(footprint_scale);
  const float haze_f = static_cast<float>(haze_m);
  const std::array<float, 3> grass_f = {static_cast<float>(kGrass[0]), static_cast<float>(kGrass[1]),
                                        static_cast<float>(kGrass[2])};
  const std::array<float, 3> sky_f = {static_cast<float>(kSkyHorizon[0]), static_cast<float>(kSkyHorizon[1]),
                                      static_cast<float>(kSkyHorizon[2])};
  for (int v = 0; v < k.height_px; ++v) {
    cv::Vec3b* row = bgr.ptr<cv::Vec3b>(v);
    const float* depth_row = scratch.depth_m.ptr<float>(v);
    const int* id_row = scratch.obstacle_id.ptr<int>(v);
    // Pixel rays (x, y, 1) in C, i.e. with camera z = 1: a hit at ray parameter t has depth t.
    Eigen::Vector3d d_W = R_WC * Eigen::Vector3d((0.5 - k.cx_px) / k.fx_px, (v + 0.5 - k.cy_px) / k.fy_px, 1.0);
    for (int u = 0; u < k.width_px; ++u, d_W += step_W) {
      const int id = id_row[u];
      Colour colour;
      if (id >= 0) {
        const double t = static_cast<double>(depth_row[u]);
        const Eigen::Vector3d p_W = o_W + t * d_W;
        Eigen::Vector3d n_W = Eigen::Vector3d::Zero();
        double albedo = 0.85 + 0.3 * hash01(id, 0, 3);
        const Colour* base = &kBark;
        if (static_cast<std::size_t>(id) < box_count) {
          const Box& box = world.boxes()[static_cast<std::size_t>(id)];
          int axis = 0;
          double best = std::numeric_limits<double>::infinity(), sign = 1.0;
          for (int a = 0; a < 3; ++a) {  // the face hit: the plane nearest the hit point
            const double dl = std::abs(p_W[a] - box.min_W_m[a]), dh = std::abs(p_W[a] - box.max_W_m[a]);
            if (dl < best) best = dl, axis = a, sign = -1.0;
            if (dh < best) best = dh, axis = a, sign = 1.0;
          }
          n_W[axis] = sign;
          // Panels of 1 m with dark seams, each panel a little different.
          const double s1 = p_W[(axis + 1) % 3], s2 = p_W[(axis + 2) % 3];
          const std::int64_t i1 = fastFloor(s1), i2 = fastFloor(s2);
          const bool seam = s1 - static_cast<double>(i1) < 0.03 || s2 - static_cast<double>(i2) < 0.03;
          albedo *= seam ? 0.55 : 0.9 + 0.2 * hash01(i1, i2, 5 + static_cast<std::uint64_t>(axis));
          base = &kConcrete;
        } else {
          const Cylinder& cyl = world.cylinders()[static_cast<std::size_t>(id) - box_count];
          if (p_W.z() >= cyl.z_max_m - 1e-6) {
            n_W.z() = 1.0;
          } else if (p_W.z() <= cyl.z_min_m + 1e-6) {
            n_W.z() = -1.0;
          } else {
            n_W.x() = (p_W.x() - cyl.center_W_m.x()) / cyl.radius_m;
            n_W.y() = (p_W.y() - cyl.center_W_m.y()) / cyl.radius_m;
          }
          // Bark: furrows (by the normal's direction) broken into 0.4 m bands.
          albedo *= 0.8 + 0.35 * hash01(fastFloor((n_W.x() + 2.0 * n_W.y()) * 3.0), fastFloor(p_W.z() * 2.5), 7);
        }
        const double shade = albedo * (0.45 + 0.6 * std::max(0.0, n_W.dot(params_.sun_dir_W)));
        const double range_m = t * d_W.norm();
        const double haze = range_m / (range_m + haze_m);
        colour = (1.0 - haze) * shade * *base + haze * kSkyHorizon;
      } else if (above_ground && d_W.z() < 0.0) {
        // Plain single-precision scalars here: this branch runs for most pixels (double's divisions and
        // square roots cost twice as much, and a grass texel needs no more than float's 24 bits).
        const float dx = static_cast<float>(d_W.x()), dy = static_cast<float>(d_W.y());
        const float dz = static_cast<float>(d_W.z());
        const float t = -o_z / dz;
        const float x = o_x + t * dx, y = o_y + t * dy;
        const float range_m = t * std::sqrt(dx * dx + dy * dy + dz * dz);
        // The pixel's footprint on the ground (range / f, stretched by the grazing angle range / height,
        // at most 20x) in level-0 texels picks the texture level: the finest with texels >= footprint.
        const float texels = range_m * std::min(range_m * inv_height_f, 20.0F) * footprint_scale_f;
        const int level = texels < 1.0F ? 0 : std::min(top_level, floorLog2(static_cast<double>(texels)) + 1);
        const int size = kGroundSize >> level;
        const float inv_texel = inv_texel_f[static_cast<std::size_t>(level)];
        const int i = static_cast<int>(std::floor(x * inv_texel)) & (size - 1);
        const int j = static_cast<int>(std::floor(y * inv_texel)) & (size - 1);
        const float shade =
            levels[static_cast<std::size_t>(level)]
                  [static_cast<std::size_t>(j) * static_cast<std::size_t>(size) + static_cast<std::size_t>(i)];
        const float keep = haze_f / (range_m + haze_f);  // 1 - haze
        cv::Vec3b& px = row[u];
        for (int ch = 0; ch < 3; ++ch) px[ch] = toByteF(keep * (shade * grass_f[ch] - sky_f[ch]) + sky_f[ch]);
        continue;
      } else {
        // Sine of the elevation, from 0 at the horizon to 1 at the zenith.
        const double s = std::max(0.0, d_W.z()) / d_W.norm();
        cv::Vec3b& px = row[u];
        px[0] = toByte(kSkyHorizon[0] + s * (kSkyZenith[0] - kSkyHorizon[0]));
        px[1] = toByte(kSkyHorizon[1] + s * (kSkyZenith[1] - kSkyHorizon[1]));
        px[2] = toByte(kSkyHorizon[2] + s * (kSkyZenith[2] - kSkyHorizon[2]));
        continue;
      }
      store(row[u], colour);
    }
  }
}

}  // namespace aerotrack::hal::sim
