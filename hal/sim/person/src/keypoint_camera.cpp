// Keypoint-mode camera: pinhole projection of the COCO keypoints with visibility, misses, torso-scaled
// Gaussian pixel noise and scores, as a MoveNet detector would report them. Model: keypoint_camera.hpp.
#include "aerotrack/hal/sim/keypoint_camera.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace aerotrack::hal::sim {
namespace {

constexpr double kMinDepthM = 1e-3;
constexpr double kMinMatchDepthM = 0.1;  // nearer, a person fills more than the image
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// A uniform draw in (0, 1] from the top 53 bits of one engine output (platform independent, unlike
// std::uniform_real_distribution).
double uniform01(std::mt19937_64& rng) {
  return static_cast<double>((rng() >> 11) + 1) * 0x1.0p-53;
}

}  // namespace

Eigen::Matrix3d opticalAxesInFlu() {
  Eigen::Matrix3d R;
  R << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return R;
}

Eigen::Isometry3d cameraLookingAt(const Eigen::Vector3d& eye_W, const Eigen::Vector3d& target_W) {
  const Eigen::Vector3d z = (target_W - eye_W).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();
  T_WC.linear() << x, z.cross(x), z;
  T_WC.translation() = eye_W;
  return T_WC;
}

CameraIntrinsics pinholeIntrinsics(int width_px, int height_px, double horizontal_fov_rad) {
  CameraIntrinsics k;
  k.width_px = width_px;
  k.height_px = height_px;
  k.fx_px = 0.5 * width_px / std::tan(0.5 * horizontal_fov_rad);
  k.fy_px = k.fx_px;
  k.cx_px = 0.5 * width_px;
  k.cy_px = 0.5 * height_px;
  return k;
}

rt::Status validate(const KeypointCameraParams& p) {
  const CameraIntrinsics& k = p.intrinsics;
  if (k.width_px <= 0 || k.height_px <= 0) return rt::Error{"KeypointCameraParams.intrinsics: image size must be > 0"};
  if (!std::isfinite(k.fx_px) || !std::isfinite(k.fy_px) || k.fx_px <= 0.0 || k.fy_px <= 0.0) {
    return rt::Error{"KeypointCameraParams.intrinsics: focal lengths must be finite and > 0"};
  }
  if (!std::isfinite(k.cx_px) || !std::isfinite(k.cy_px)) {
    return rt::Error{"KeypointCameraParams.intrinsics: principal point must be finite"};
  }
  for (double d : k.distortion) {
    if (d != 0.0) return rt::Error{"KeypointCameraParams.intrinsics: distortion is not modelled; it must be zero"};
  }
  if (!std::isfinite(p.pixel_noise_torso_fraction) || p.pixel_noise_torso_fraction < 0.0) {
    return rt::Error{"KeypointCameraParams.pixel_noise_torso_fraction must be >= 0"};
  }
  if (!(p.keypoint_miss_probability >= 0.0 && p.keypoint_miss_probability <= 1.0)) {
    return rt::Error{"KeypointCameraParams.keypoint_miss_probability must be in [0, 1]"};
  }
  if (p.min_visible_keypoints < 1 || p.min_visible_keypoints > static_cast<int>(kNumKeypoints)) {
    return rt::Error{"KeypointCameraParams.min_visible_keypoints must be in [1, 17], got " +
                     std::to_string(p.min_visible_keypoints)};
  }
  if (!(p.min_score > 0.0 && p.min_score <= p.max_score && p.max_score <= 1.0)) {
    return rt::Error{"KeypointCameraParams: need 0 < min_score <= max_score <= 1"};
  }
  if (!std::isfinite(p.bbox_margin_fraction) || p.bbox_margin_fraction < 0.0) {
    return rt::Error{"KeypointCameraParams.bbox_margin_fraction must be >= 0"};
  }
  if (!(p.cut_guess_reach_torso >= 0.0 && p.cut_guess_reach_torso <= 10.0))
    return rt::Error{"KeypointCameraParams.cut_guess_reach_torso must be in [0, 10]"};
  if (!(p.cut_guess_min_inset_torso >= 0.0 && p.cut_guess_min_inset_torso <= p.cut_guess_max_inset_torso &&
        p.cut_guess_max_inset_torso <= 1.0))
    return rt::Error{"KeypointCameraParams: need 0 <= cut_guess_min_inset_torso <= cut_guess_max_inset_torso <= 1"};
  if (!(p.cut_guess_min_score > 0.0 && p.cut_guess_min_score <= p.cut_guess_max_score && p.cut_guess_max_score <= 1.0))
    return rt::Error{"KeypointCameraParams: need 0 < cut_guess_min_score <= cut_guess_max_score <= 1"};
  return rt::ok();
}

std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p_C_m, const CameraIntrinsics& intrinsics) {
  if (!(p_C_m.z() > kMinDepthM)) return std::nullopt;
  return Eigen::Vector2d(intrinsics.cx_px + intrinsics.fx_px * p_C_m.x() / p_C_m.z(),
                         intrinsics.cy_px + intrinsics.fy_px * p_C_m.y() / p_C_m.z());
}

std::optional<double> keypointMatchError(const PersonDetection& detection,
                                         const std::array<Eigen::Vector3d, kNumKeypoints>& keypoints_C_m,
                                         const CameraIntrinsics& intrinsics) {
  using K = CocoKeypoint;
  const auto mid = [&](K a, K b) { return 0.5 * (keypoints_C_m[index(a)] + keypoints_C_m[index(b)]); };
  const Eigen::Vector3d neck_C_m = mid(K::kLeftShoulder, K::kRightShoulder);
  const Eigen::Vector3d hip_C_m = mid(K::kLeftHip, K::kRightHip);
  if (!(neck_C_m.z() > kMinMatchDepthM && hip_C_m.z() > kMinMatchDepthM)) return std::nullopt;
  const auto neck = project(neck_C_m, intrinsics);
  const auto hip = project(hip_C_m, intrinsics);
  const auto inImage = [&](const Eigen::Vector2d& uv) {
    return uv.x() >= 0.0 && uv.y() >= 0.0 && uv.x() <= intrinsics.width_px && uv.y() <= intrinsics.height_px;
  };
  // One end may be cut off by the frame (the network then guesses it at the border), not both.
  if (!neck || !hip || !(inImage(*neck) || inImage(*hip))) return std::nullopt;
  const double torso_px = (*neck - *hip).norm();
  if (!(torso_px > 0.0)) return std::nullopt;

  std::array<std::optional<Eigen::Vector2d>, kNumKeypoints> truth_px;
  for (std::size_t i = 0; i < kNumKeypoints; ++i) truth_px[i] = project(keypoints_C_m[i], intrinsics);
  double straight_px = 0.0;
  double exchanged_px = 0.0;
  int compared = 0;
  for (std::size_t i = 0; i < kNumKeypoints; ++i) {
    const Keypoint2D& kp = detection.keypoints[i];
    if (kp.score <= 0.0) continue;
    // COCO puts each left keypoint right before its right twin, from the eyes (1, 2) on.
    const std::size_t twin = i == 0 ? 0 : (i % 2 == 1 ? i + 1 : i - 1);
    if (!truth_px[i] || !truth_px[twin]) return std::nullopt;
    const Eigen::Vector2d uv(kp.u_px, kp.v_px);
    straight_px += (uv - *truth_px[i]).norm();
    exchanged_px += (uv - *truth_px[twin]).norm();
    ++compared;
  }
  if (compared == 0) return std::nullopt;
  return std::min(straight_px, exchanged_px) / compared / torso_px;
}

std::optional<PersonDetection> observe(const std::array<Eigen::Vector3d, kNumKeypoints>& keypoints_W_m,
                                       const Eigen::Isometry3d& T_WC, const KeypointCameraParams& params,
                                       const LineOfSight& line_of_sight, std::mt19937_64& rng) {
  const CameraIntrinsics& k = params.intrinsics;
  const Eigen::Isometry3d T_CW = T_WC.inverse(Eigen::Isometry);
  const Eigen::Vector3d centre_W_m = T_WC.translation();

  std::array<std::optional<Eigen::Vector2d>, kNumKeypoints> uv;
  for (std::size_t i = 0; i < kNumKeypoints; ++i) uv[i] = project(T_CW * keypoints_W_m[i], k);

  // Noise scale: the true projected torso, as the localizer would measure it from 2D keypoints.
  using K = CocoKeypoint;
  const std::size_t ls = index(K::kLeftShoulder), rs = index(K::kRightShoulder);
  const std::size_t lh = index(K::kLeftHip), rh = index(K::kRightHip);
  double torso_px = 0.0;
  if (uv[ls] && uv[rs] && uv[lh] && uv[rh]) {
    torso_px = (0.5 * (*uv[ls] + *uv[rs]) - 0.5 * (*uv[lh] + *uv[rh])).norm();
  } else {  // torso partly behind the camera: scale by the torso's mean depth
    const Eigen::Vector3d neck_C = T_CW * (0.5 * (keypoints_W_m[ls] + keypoints_W_m[rs]));
    const Eigen::Vector3d hips_C = T_CW * (0.5 * (keypoints_W_m[lh] + keypoints_W_m[rh]));
    const double z = std::max(0.5 * (neck_C.z() + hips_C.z()), 0.1);
    torso_px = k.fx_px * (neck_C - hips_C).norm() / z;
  }
  const double sigma_px = params.pixel_noise_torso_fraction * torso_px;
  const double w = k.width_px, h = k.height_px;

  PersonDetection det;
  int visible = 0;
  double score_sum = 0.0;
  double u_min = std::numeric_limits<double>::infinity(), v_min = u_min;
  double u_max = -u_min, v_max = -u_min;
  for (std::size_t i = 0; i < kNumKeypoints; ++i) {
    const double miss_draw = uniform01(rng);
    const double r = std::sqrt(-2.0 * std::log(uniform01(rng)));
    const double phi = kTwoPi * uniform01(rng);
    const double score_draw = uniform01(rng);
    if (!uv[i]) continue;
    const Eigen::Vector2d& q = *uv[i];
    const double outside_px = std::max({-q.x(), q.x() - w, -q.y(), q.y() - h});
    const bool cut = outside_px > 0.0;
    if (cut && !(outside_px <= params.cut_guess_reach_torso * torso_px)) continue;
    if (miss_draw <= params.keypoint_miss_probability) continue;
    if (line_of_sight && !line_of_sight(centre_W_m, keypoints_W_m[i])) continue;
    Keypoint2D& out = det.keypoints[i];
    if (cut) {  // guessed inside the nearest edge; the same draws as a seen keypoint (phi for the inset)
      const double inset_px =
          torso_px * (params.cut_guess_min_inset_torso +
                      (params.cut_guess_max_inset_torso - params.cut_guess_min_inset_torso) * phi / kTwoPi);
      out.u_px = std::clamp(q.x(), std::min(inset_px, 0.5 * w), std::max(w - inset_px, 0.5 * w));
      out.v_px = std::clamp(q.y(), std::min(inset_px, 0.5 * h), std::max(h - inset_px, 0.5 * h));
      out.score = params.cut_guess_min_score +
                  (params.cut_guess_max_score - params.cut_guess_min_score) * (score_draw - 0x1.0p-53);
    } else {
      out.u_px = std::clamp(q.x() + sigma_px * r * std::cos(phi), 0.0, w);
      out.v_px = std::clamp(q.y() + sigma_px * r * std::sin(phi), 0.0, h);
      out.score = params.min_score + (params.max_score - params.min_score) * (score_draw - 0x1.0p-53);
    }
    ++visible;
    score_sum += out.score;
    u_min = std::min(u_min, out.u_px);
    u_max = std::max(u_max, out.u_px);
    v_min = std::min(v_min, out.v_px);
    v_max = std::max(v_max, out.v_px);
  }
  if (visible < params.min_visible_keypoints || visible == 0) return std::nullopt;

  const double margin = params.bbox_margin_fraction * std::max(u_max - u_min, v_max - v_min);
  const double u0 = std::max(0.0, u_min - margin), u1 = std::min(w, u_max + margin);
  const double v0 = std::max(0.0, v_min - margin), v1 = std::min(h, v_max + margin);
  det.bbox_u_px = u0;
  det.bbox_v_px = v0;
  det.bbox_w_px = u1 - u0;
  det.bbox_h_px = v1 - v0;
  det.score = score_sum / visible;
  return det;
}

}  // namespace aerotrack::hal::sim
