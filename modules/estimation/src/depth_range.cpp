// The person's distance from the depth camera: see depth_range.hpp.
#include "aerotrack/estimation/depth_range.hpp"

#include <cmath>
#include <string>

#include <opencv2/core/mat.hpp>

namespace aerotrack::estimation {

rt::Status validate(const DepthRangeParams& p) {
  const bool finite =
      std::isfinite(p.body_offset_m) && std::isfinite(p.step_m) && std::isfinite(p.surface_tolerance_m) &&
      std::isfinite(p.min_range_m) && std::isfinite(p.max_range_m) && std::isfinite(p.max_ratio) &&
      std::isfinite(p.max_offset_s) && std::isfinite(p.range_std_m) && std::isfinite(p.range_std_per_m2) &&
      std::isfinite(p.cross_std_per_m) && std::isfinite(p.person_speed_mps) && std::isfinite(p.scale_rate);
  if (!finite) return rt::Error{"depth range: every parameter must be finite"};
  if (!(p.step_m > 0.0) || !(p.step_m <= p.surface_tolerance_m))
    return rt::Error{"depth range: need 0 < step_m <= surface_tolerance_m (a step must not jump over a surface)"};
  if (!(p.min_range_m >= 0.0) || !(p.min_range_m < p.max_range_m))
    return rt::Error{"depth range: need 0 <= min_range_m < max_range_m"};
  if (!(p.max_ratio >= 1.0)) return rt::Error{"depth range: max_ratio must be >= 1"};
  if (p.body_offset_m < 0.0 || p.max_offset_s < 0.0 || p.range_std_m < 0.0 || p.range_std_per_m2 < 0.0 ||
      p.cross_std_per_m < 0.0 || p.person_speed_mps < 0.0)
    return rt::Error{"depth range: offsets and noises must be >= 0"};
  if (!(p.scale_rate >= 0.0 && p.scale_rate <= 1.0)) return rt::Error{"depth range: need 0 <= scale_rate <= 1"};
  return rt::ok();
}

DepthRangeParams parseDepthRangeParams(const rt::ConfigNode& node) {
  DepthRangeParams p;
  p.enabled = node.getBool("enabled");
  p.body_offset_m = node.getDouble("body_offset_m", 0.0, 1.0);
  p.step_m = node.getDouble("step_m", 0.005, 1.0);
  p.surface_tolerance_m = node.getDouble("surface_tolerance_m", 0.005, 2.0);
  if (p.step_m > p.surface_tolerance_m) node.fail("step_m", "must not exceed surface_tolerance_m");
  p.min_range_m = node.getDouble("min_range_m", 0.0, 100.0);
  p.max_range_m = node.getDouble("max_range_m", 0.1, 100.0);
  if (p.max_range_m <= p.min_range_m) node.fail("max_range_m", "must exceed min_range_m");
  p.max_ratio = node.getDouble("max_ratio", 1.0, 10.0);
  p.max_offset_s = node.getDouble("max_offset_s", 0.0, 1.0);
  p.range_std_m = node.getDouble("range_std_m", 0.0, 5.0);
  p.range_std_per_m2 = node.getDouble("range_std_per_m2", 0.0, 1.0);
  p.cross_std_per_m = node.getDouble("cross_std_per_m", 0.0, 1.0);
  p.person_speed_mps = node.getDouble("person_speed_mps", 0.0, 20.0);
  // Optional (absent: off), so that a dataset recorded before it replays with its own configuration.
  if (node.has("scale_rate")) p.scale_rate = node.getDouble("scale_rate", 0.0, 1.0);
  node.finish();
  return p;
}

const char* toString(DepthRangeStatus status) {
  switch (status) {
    case DepthRangeStatus::kFound:
      return "found";
    case DepthRangeStatus::kOutOfView:
      return "out of the depth camera's view";
    case DepthRangeStatus::kOccluded:
      return "occluded from the depth camera";
    case DepthRangeStatus::kNoSurface:
      return "no surface along the line of sight";
  }
  return "unknown";
}

DepthSurface surfaceAlongLine(const hal::DepthFrame& depth, const Eigen::Isometry3d& T_WD,
                              const Eigen::Vector3d& origin_W, const Eigen::Vector3d& dir_W,
                              const DepthRangeParams& params) {
  DepthSurface result;
  const cv::Mat& image = depth.depth_m;
  const hal::CameraIntrinsics& k = depth.intrinsics;
  if (image.empty() || image.type() != CV_32FC1 || image.cols != k.width_px || image.rows != k.height_px ||
      !(k.fx_px > 0.0) || !(k.fy_px > 0.0) || !T_WD.matrix().allFinite() || !origin_W.allFinite() ||
      !dir_W.allFinite() || !(params.step_m > 0.0))
    return result;
  // The line in the depth camera's frame: q(s) = q0 + s dq.
  const Eigen::Isometry3d T_DW = T_WD.inverse();
  const Eigen::Vector3d q0 = T_DW * origin_W;
  const Eigen::Vector3d dq = T_DW.linear() * dir_W;
  constexpr double kMinDepthM = 0.05;  // nearer than this the projection is meaningless
  bool seen = false;
  const int steps = static_cast<int>(std::floor((params.max_range_m - params.min_range_m) / params.step_m)) + 1;
  for (int i = 0; i < steps; ++i) {
    const double s = params.min_range_m + i * params.step_m;
    const Eigen::Vector3d q = q0 + s * dq;
    if (!(q.z() > kMinDepthM)) continue;
    const double u = k.fx_px * q.x() / q.z() + k.cx_px;  // pixel (u, v) covers [u, u + 1) (HAL convention)
    const double v = k.fy_px * q.y() / q.z() + k.cy_px;
    if (!(u >= 0.0 && u < k.width_px && v >= 0.0 && v < k.height_px)) continue;
    const auto z_image_m = static_cast<double>(image.at<float>(static_cast<int>(v), static_cast<int>(u)));
    if (!(z_image_m > 0.0) || !std::isfinite(z_image_m)) continue;  // no data here
    seen = true;
    const double above_m = q.z() - z_image_m;             // > 0: the point lies behind what the camera sees there
    if (above_m < -params.surface_tolerance_m) continue;  // free space in front of the surface
    if (above_m > params.surface_tolerance_m) {
      result.status = DepthRangeStatus::kOccluded;
      return result;
    }
    result.status = DepthRangeStatus::kFound;
    // Where the line's depth equals the image's (the line is straight; the surface taken flat over the step).
    result.range_m = dq.z() > 0.1 ? s - above_m / dq.z() : s;
    return result;
  }
  result.status = seen ? DepthRangeStatus::kNoSurface : DepthRangeStatus::kOutOfView;
  return result;
}

Eigen::Vector2d bodyCentreBehind(const Eigen::Vector3d& origin_W, const Eigen::Vector3d& dir_W, double range_m,
                                 const DepthRangeParams& params) {
  const Eigen::Vector3d front_W = origin_W + range_m * dir_W;
  const Eigen::Vector2d horizontal = dir_W.head<2>();
  const double norm = horizontal.norm();
  if (!(norm > 1e-9)) return front_W.head<2>();
  return front_W.head<2>() + params.body_offset_m * horizontal / norm;
}

double depthRangeStdM(double range_m, const DepthRangeParams& params) {
  const double stereo_m = params.range_std_per_m2 * range_m * range_m;
  return std::sqrt(params.range_std_m * params.range_std_m + stereo_m * stereo_m);
}

}  // namespace aerotrack::estimation
