// Drawing an articulated person: each body part of the photo warped onto the projected keypoints of
// the simulated person (scene_renderer.hpp, person_sprite.hpp).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

#include <Eigen/LU>  // inverse()

#include "aerotrack/hal/sim/scene_renderer.hpp"

namespace aerotrack::hal::sim {
namespace {

constexpr double kPersonNearM = 0.1;  // Every keypoint must be this far in front of the camera.
/// Seen from the side, the torso is drawn at least this fraction of the photo's width.
constexpr double kMinTorsoWidthFraction = 0.55;
/// A limb pointing at the camera keeps at least this fraction of its photo's length (so its map stays
/// invertible; the bone then looks like a short, foreshortened limb).
constexpr double kMinBoneFraction = 0.2;

/// Image right for an image "along" direction (u right, v down): down (0, 1) gives right (1, 0).
Eigen::Vector2d rightOf(const Eigen::Vector2d& along) {
  return {along.y(), -along.x()};
}

/// Affine map (as a 3x3) from the image to the sprite taking the image bone a_i -> b_i onto the sprite
/// bone a_s -> b_s along it, and image distances across it to sprite distances / across_scale, on the
/// same side (mirror +1) or the other (-1).
Eigen::Matrix3d boneMap(const Eigen::Vector2d& a_i, const Eigen::Vector2d& b_i, const Eigen::Vector2d& a_s,
                        const Eigen::Vector2d& b_s, double across_scale, double mirror,
                        const Eigen::Vector2d& fallback_dir) {
  const double len_s = std::max((b_s - a_s).norm(), 1e-6);
  const Eigen::Vector2d d_s = (b_s - a_s) / len_s;
  double len_i = (b_i - a_i).norm();
  const Eigen::Vector2d d_i = len_i > 1e-6 ? Eigen::Vector2d((b_i - a_i) / len_i) : fallback_dir;
  len_i = std::max(len_i, kMinBoneFraction * across_scale * len_s);
  // sprite = a_s + d_s (along . d_i) len_s / len_i + n_s mirror (across . n_i) / across_scale
  Eigen::Matrix2d A =
      d_s * d_i.transpose() * (len_s / len_i) + rightOf(d_s) * rightOf(d_i).transpose() * (mirror / across_scale);
  Eigen::Matrix3d H = Eigen::Matrix3d::Identity();
  H.topLeftCorner<2, 2>() = A;
  H.topRightCorner<2, 1>() = a_s - A * a_i;
  return H;
}

/// Image bounds of a sprite rectangle {u_min, v_min, u_max, v_max} under the inverse of H.
Eigen::Vector4d imageBounds(const Eigen::Matrix3d& H_sprite_image, const Eigen::Vector4d& sprite_box) {
  const Eigen::Matrix3d H_image_sprite = H_sprite_image.inverse();
  Eigen::Vector4d out(std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                      -std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity());
  for (const double u : {sprite_box[0], sprite_box[2]}) {
    for (const double v : {sprite_box[1], sprite_box[3]}) {
      const Eigen::Vector3d p = H_image_sprite * Eigen::Vector3d(u, v, 1.0);
      if (!(p.z() > 1e-9)) return Eigen::Vector4d::Zero();  // behind the quad's horizon: not drawn
      out[0] = std::min(out[0], p.x() / p.z()), out[1] = std::min(out[1], p.y() / p.z());
      out[2] = std::max(out[2], p.x() / p.z()), out[3] = std::max(out[3], p.y() / p.z());
    }
  }
  return out;
}

/// Bilinear sample of the sprite's premultiplied BGRA at continuous pixel coordinates (centres at
/// i + 0.5), from the taps of `part` and transparent taps only, renormalised over them: the warped
/// part shows none of its neighbours, and its own silhouette keeps its soft edge.
cv::Vec4f samplePart(const cv::Mat& img, const cv::Mat& labels, std::uint8_t part, double x, double y) {
  const double fx = x - 0.5, fy = y - 0.5;
  const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
  const float ax = static_cast<float>(fx - x0), ay = static_cast<float>(fy - y0);
  cv::Vec4f out(0.0F, 0.0F, 0.0F, 0.0F);
  const std::array<float, 4> w = {(1.0F - ax) * (1.0F - ay), ax * (1.0F - ay), (1.0F - ax) * ay, ax * ay};
  float kept = 0.0F;
  bool own = false;
  for (int n = 0; n < 4; ++n) {
    const int xi = x0 + (n & 1), yi = y0 + (n >> 1);
    const float weight = w[static_cast<std::size_t>(n)];
    if (xi < 0 || yi < 0 || xi >= img.cols || yi >= img.rows) {
      kept += weight;  // outside: transparent
      continue;
    }
    const std::uint8_t label = labels.at<std::uint8_t>(yi, xi);
    if (label != part && label != kNoPart) continue;
    own = own || label == part;
    kept += weight;
    out += weight * img.at<cv::Vec4f>(yi, xi);
  }
  if (!own || kept < 0.25F) return {0.0F, 0.0F, 0.0F, 0.0F};
  return out * (1.0F / kept);
}

std::uint8_t toPixelByte(float c) {
  return static_cast<std::uint8_t>(std::min(c, 255.0F) + 0.5F);  // NOLINT(bugprone-incorrect-roundings): c >= 0
}

}  // namespace

SpritePlacement SceneRenderer::placeSprite(const PersonState& person, const Eigen::Isometry3d& T_WC,
                                           std::size_t cast_index) const {
  SpritePlacement out;
  const CameraIntrinsics& k = params_.intrinsics;
  const Eigen::Isometry3d T_CW = T_WC.inverse(Eigen::Isometry);
  std::array<Eigen::Vector3d, kNumKeypoints> kp_C{};
  std::array<Eigen::Vector2d, kNumKeypoints> kp_px{};
  for (std::size_t i = 0; i < kNumKeypoints; ++i) {
    kp_C[i] = T_CW * person.keypoints_W_m[i];
    if (!(kp_C[i].z() >= kPersonNearM)) return out;
    kp_px[i] =
        Eigen::Vector2d(k.cx_px + k.fx_px * kp_C[i].x() / kp_C[i].z(), k.cy_px + k.fy_px * kp_C[i].y() / kp_C[i].z());
  }
  if ((T_CW * person.p_W_m).z() < kPersonNearM) return out;
  const PersonSprite& s = *sprites_.at(cast_index);
  const auto& kp_s = s.keypointsPx();
  const auto torso_i = bodyPartEnds(BodyPart::kTorso, kp_px);
  const auto torso_C = bodyPartEnds(BodyPart::kTorso, kp_C);
  const auto torso_s = bodyPartEnds(BodyPart::kTorso, kp_s);
  out.neck_px = torso_i[0];
  out.mid_hip_px = torso_i[1];
  out.depth_m = torso_C[1].z();
  // Across the body: the person's width at their depth. The photo's scale (m per sprite px) is the
  // simulated torso's length over the photo's.
  const double torso_m = (torso_C[0] - torso_C[1]).norm();
  const double torso_s_px = (torso_s[1] - torso_s[0]).norm();
  if (!(torso_m > 1e-3 && torso_s_px > 1.0)) return out;
  out.scale = k.fx_px * torso_m / (out.depth_m * torso_s_px);
  // Which side the camera sees: the person's facing direction against the camera's axis.
  const Eigen::Vector3d facing_C =
      T_CW.linear() * Eigen::Vector3d(std::cos(person.heading_rad), std::sin(person.heading_rad), 0.0);
  const bool seen_from_front = facing_C.z() < 0.0;
  out.mirrored = seen_from_front != (s.view() == PersonView::kFront);
  out.hair_over_face = !seen_from_front && s.view() == PersonView::kFront;
  const double mirror = out.mirrored ? -1.0 : 1.0;

  const Eigen::Vector2d torso_vec = out.mid_hip_px - out.neck_px;
  const Eigen::Vector2d down =
      torso_vec.norm() > 1e-6 ? Eigen::Vector2d(torso_vec.normalized()) : Eigen::Vector2d::UnitY();
  const Eigen::Vector2d right = rightOf(down);

  // Torso: along the neck -> mid-hip axis like a bone; across it, the projected width of shoulders
  // and hips over the photo's (the simulated build), at least a fraction of the photo's width at the
  // person's depth (seen from the side, a torso is about 0.6 as deep as wide).
  {
    const auto half_span = [&](const auto& kp, CocoKeypoint left, CocoKeypoint right_kp,
                               const Eigen::Vector2d& across) {
      return 0.5 * std::abs((kp[index(left)] - kp[index(right_kp)]).dot(across));
    };
    const Eigen::Vector2d d_s = (torso_s[1] - torso_s[0]) / torso_s_px;
    const double span_s = half_span(kp_s, CocoKeypoint::kLeftShoulder, CocoKeypoint::kRightShoulder, rightOf(d_s)) +
                          half_span(kp_s, CocoKeypoint::kLeftHip, CocoKeypoint::kRightHip, rightOf(d_s));
    const double span_i = half_span(kp_px, CocoKeypoint::kLeftShoulder, CocoKeypoint::kRightShoulder, right) +
                          half_span(kp_px, CocoKeypoint::kLeftHip, CocoKeypoint::kRightHip, right);
    const double across = std::max(span_i / std::max(span_s, 1.0), kMinTorsoWidthFraction * out.scale);
    PartPlacement& torso = out.parts[static_cast<std::size_t>(BodyPart::kTorso)];
    torso.H_sprite_image = boneMap(out.neck_px, out.mid_hip_px, torso_s[0], torso_s[1], across, mirror, down);
    torso.depth_m = 0.5 * (torso_C[0].z() + torso_C[1].z());
  }
  for (std::size_t p = 1; p < kPartCount; ++p) {
    const auto ends_i = bodyPartEnds(static_cast<BodyPart>(p), kp_px);
    const auto ends_s = bodyPartEnds(static_cast<BodyPart>(p), kp_s);
    const auto ends_C = bodyPartEnds(static_cast<BodyPart>(p), kp_C);
    PartPlacement& part = out.parts[p];
    part.H_sprite_image = boneMap(ends_i[0], ends_i[1], ends_s[0], ends_s[1], out.scale, mirror, down);
    part.depth_m = 0.5 * (ends_C[0].z() + ends_C[1].z());
  }
  // Bounds of each part, and of them all (clamped to a generous box around the person, so that a
  // near-degenerate map cannot ask for the whole image).
  const double reach = 3.0 * std::max(torso_vec.norm(), out.scale * torso_s_px);
  Eigen::Vector4d all(std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                      -std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity());
  for (std::size_t p = 0; p < kPartCount; ++p) {
    PartPlacement& part = out.parts[p];
    if (s.partPixels()[p] == 0) continue;
    Eigen::Vector4d b = imageBounds(part.H_sprite_image, s.partBoundsPx()[p]);
    if (b == Eigen::Vector4d::Zero()) continue;
    b[0] = std::max(b[0], out.mid_hip_px.x() - reach), b[1] = std::max(b[1], out.mid_hip_px.y() - reach);
    b[2] = std::min(b[2], out.mid_hip_px.x() + reach), b[3] = std::min(b[3], out.mid_hip_px.y() + reach);
    if (b[0] > b[2] || b[1] > b[3]) continue;
    part.bounds_px = b;
    part.drawn = true;
    all[0] = std::min(all[0], b[0]), all[1] = std::min(all[1], b[1]);
    all[2] = std::max(all[2], b[2]), all[3] = std::max(all[3], b[3]);
  }
  std::array<std::uint8_t, kPartCount> order{};
  std::iota(order.begin(), order.end(), std::uint8_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint8_t a, std::uint8_t b) { return out.parts[a].depth_m > out.parts[b].depth_m; });
  out.order = order;
  out.bounds_px = all;
  out.visible = all[0] <= all[2];
  return out;
}

void SceneRenderer::drawPerson(const SpritePlacement& pl, cv::Mat& bgr, const cv::Mat& depth_m,
                               const RenderedPerson& look) const {
  const CameraIntrinsics& k = params_.intrinsics;
  const PersonSprite& s = *sprites_.at(look.person);
  // Pyramid level: the finest whose pixels are at least as large as an image pixel's footprint / 2.
  const int level = std::clamp(static_cast<int>(std::floor(std::log2(std::max(1.0 / pl.scale, 1.0)))), 0,
                               static_cast<int>(s.levels().size()) - 1);
  const cv::Mat& img = s.levels()[static_cast<std::size_t>(level)];
  const cv::Mat& labels = s.labels()[static_cast<std::size_t>(level)];
  const double level_scale = std::ldexp(1.0, -level);
  const float inv_head_luminance = 1.0F / std::max(s.headLuminance(), 0.02F);
  for (const std::uint8_t p : pl.order) {
    const PartPlacement& part = pl.parts[p];
    if (!part.drawn) continue;
    const int u0 = std::max(0, static_cast<int>(std::floor(part.bounds_px[0])) - 1);
    const int v0 = std::max(0, static_cast<int>(std::floor(part.bounds_px[1])) - 1);
    const int u1 = std::min(k.width_px - 1, static_cast<int>(std::ceil(part.bounds_px[2])) + 1);
    const int v1 = std::min(k.height_px - 1, static_cast<int>(std::ceil(part.bounds_px[3])) + 1);
    const float depth = static_cast<float>(part.depth_m);
    const Eigen::Matrix3d H = part.H_sprite_image;
    const bool head = p == static_cast<std::uint8_t>(BodyPart::kHead);
    const bool paint_hair = head && pl.hair_over_face;
    const bool recolour = look.recolour && !head;
    for (int v = v0; v <= v1; ++v) {
      cv::Vec3b* row = bgr.ptr<cv::Vec3b>(v);
      const float* depth_row = depth_m.ptr<float>(v);
      Eigen::Vector3d q = H * Eigen::Vector3d(u0 + 0.5, v + 0.5, 1.0);
      for (int u = u0; u <= u1; ++u, q += H.col(0)) {
        if (depth_row[u] <= depth) continue;  // an obstacle is in front
        const double w = q.z();
        if (!(w > 1e-9)) continue;
        cv::Vec4f c = samplePart(img, labels, p, q.x() / w * level_scale, q.y() / w * level_scale);
        if (c[3] <= 1e-3F) continue;
        if (paint_hair) {  // the back of the head: hair, shaded like the face was
          const float luminance = (0.114F * c[0] + 0.587F * c[1] + 0.299F * c[2]) / c[3];
          const float shade = std::clamp(luminance * inv_head_luminance, 0.6F, 1.4F);
          for (int ch = 0; ch < 3; ++ch) c[ch] = std::min(c[3], c[3] * shade * s.hairBgr()[ch]);
        } else if (recolour) {
          const float luminance = 0.114F * c[0] + 0.587F * c[1] + 0.299F * c[2];
          for (int ch = 0; ch < 3; ++ch) c[ch] = std::min(c[3], 1.6F * luminance * look.clothing_bgr[ch]);
        }
        cv::Vec3b& px = row[u];
        for (int ch = 0; ch < 3; ++ch)
          px[ch] = toPixelByte(255.0F * c[ch] + (1.0F - c[3]) * static_cast<float>(px[ch]));
      }
    }
  }
}

}  // namespace aerotrack::hal::sim
