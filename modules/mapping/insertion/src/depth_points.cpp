// Depth image to world hit / miss points: pinhole back-projection with decimation (see
// depth_points.hpp for the conventions).
#include "aerotrack/mapping/depth_points.hpp"

#include <cmath>
#include <string>

#include <opencv2/core.hpp>

namespace aerotrack::mapping {

rt::Status validate(const DepthPointsParams& params) {
  if (params.decimation < 1) {
    return rt::Error{"depth points: decimation must be >= 1, got " + std::to_string(params.decimation)};
  }
  if (!(params.min_range_m >= 0.0) || !(params.min_range_m < params.max_range_m) ||
      !std::isfinite(params.max_range_m)) {
    return rt::Error{"depth points: need 0 <= min_range_m < max_range_m < inf, got " +
                     std::to_string(params.min_range_m) + " and " + std::to_string(params.max_range_m)};
  }
  return rt::ok();
}

namespace {

rt::Status validateFrame(const hal::DepthFrame& frame, const Eigen::Isometry3d& T_WC) {
  const cv::Mat& depth = frame.depth_m;
  const hal::CameraIntrinsics& k = frame.intrinsics;
  if (depth.empty() || depth.type() != CV_32FC1 || depth.dims != 2) {
    return rt::Error{"depth points: depth image must be a non-empty CV_32FC1 image"};
  }
  if (depth.cols != k.width_px || depth.rows != k.height_px) {
    return rt::Error{"depth points: depth image is " + std::to_string(depth.cols) + " x " + std::to_string(depth.rows) +
                     " px but its intrinsics say " + std::to_string(k.width_px) + " x " + std::to_string(k.height_px)};
  }
  if (!(k.fx_px > 0.0) || !(k.fy_px > 0.0) || !std::isfinite(k.fx_px) || !std::isfinite(k.fy_px) ||
      !std::isfinite(k.cx_px) || !std::isfinite(k.cy_px)) {
    return rt::Error{"depth points: focal lengths must be finite and > 0, principal point finite"};
  }
  if (!T_WC.matrix().allFinite()) return rt::Error{"depth points: T_WC is not finite"};
  return rt::ok();
}

}  // namespace

rt::Expected<DepthPointsStats> depthToPoints(const hal::DepthFrame& frame, const Eigen::Isometry3d& T_WC,
                                             const DepthPointsParams& params, octomap::Pointcloud& hits_W,
                                             octomap::Pointcloud& misses_W, std::span<const ExcludedBody> excluded) {
  hits_W.clear();
  misses_W.clear();
  if (rt::Status status = validate(params); !status) return status.error();
  if (rt::Status status = validateFrame(frame, T_WC); !status) return status.error();

  const cv::Mat& depth = frame.depth_m;
  const hal::CameraIntrinsics& k = frame.intrinsics;
  const int step = params.decimation;
  const std::size_t cols = static_cast<std::size_t>((depth.cols + step - 1) / step);
  const std::size_t rows = static_cast<std::size_t>((depth.rows + step - 1) / step);
  // Reserve the worst case once; no-ops when the clouds already hold that much.
  hits_W.reserve(cols * rows);
  misses_W.reserve(cols * rows);

  const Eigen::Matrix3d R_WC = T_WC.linear();
  const Eigen::Vector3d p_WC_m = T_WC.translation();
  const double inv_fx = 1.0 / k.fx_px;
  const double inv_fy = 1.0 / k.fy_px;
  const double min_range_m = params.min_range_m;
  const double max_range_m = params.max_range_m;

  DepthPointsStats stats;
  stats.pixels_visited = cols * rows;
  const auto append = [&R_WC, &p_WC_m](octomap::Pointcloud& cloud, const Eigen::Vector3d& p_C_m) {
    const Eigen::Vector3d p_W_m = R_WC * p_C_m + p_WC_m;
    cloud.push_back(static_cast<float>(p_W_m.x()), static_cast<float>(p_W_m.y()), static_cast<float>(p_W_m.z()));
  };
  const auto is_excluded = [&R_WC, &p_WC_m, excluded](const Eigen::Vector3d& p_C_m) {
    if (excluded.empty()) return false;
    const Eigen::Vector3d p_W_m = R_WC * p_C_m + p_WC_m;
    for (const ExcludedBody& body : excluded) {
      if (p_W_m.z() >= body.min_z_m && p_W_m.z() <= body.max_z_m &&
          (p_W_m.head<2>() - body.center_W_m).squaredNorm() < body.radius_m * body.radius_m)
        return true;
    }
    return false;
  };
  for (int v = 0; v < depth.rows; v += step) {
    const float* row = depth.ptr<float>(v);
    const double y_n = (v + 0.5 - k.cy_px) * inv_fy;  // Normalised image coordinate y / z.
    for (int u = 0; u < depth.cols; u += step) {
      const double z_m = static_cast<double>(row[u]);
      if (!(z_m > 0.0) || !std::isfinite(z_m)) {  // 0, negative, NaN, inf: no data.
        ++stats.no_data;
        continue;
      }
      const double x_n = (u + 0.5 - k.cx_px) * inv_fx;
      const double ray_norm = std::sqrt(x_n * x_n + y_n * y_n + 1.0);  // |(x, y, z)| / z.
      const double range_m = z_m * ray_norm;
      if (range_m < min_range_m) {
        ++stats.too_near;
      } else if (range_m <= max_range_m) {
        const Eigen::Vector3d p_C_m(x_n * z_m, y_n * z_m, z_m);
        if (is_excluded(p_C_m)) {
          append(misses_W, p_C_m);
          ++stats.excluded;
        } else {
          append(hits_W, p_C_m);
          ++stats.hits;
        }
      } else {
        const double z_at_max_m = max_range_m / ray_norm;
        append(misses_W, Eigen::Vector3d(x_n * z_at_max_m, y_n * z_at_max_m, z_at_max_m));
        ++stats.misses;
      }
    }
  }
  return stats;
}

}  // namespace aerotrack::mapping
