#include "aerotrack/hal/depth_view.hpp"

#include <array>
#include <cmath>

namespace aerotrack::hal {

bool isBlankDepth(const DepthFrame& frame) {
  constexpr int kStride = 8;
  if (frame.depth_m.type() != CV_32FC1) return true;
  std::size_t sampled = 0;
  std::size_t valid = 0;
  for (int v = 0; v < frame.depth_m.rows; v += kStride) {
    const float* row = frame.depth_m.ptr<float>(v);
    for (int u = 0; u < frame.depth_m.cols; u += kStride, ++sampled)
      if (row[u] > 0.0F && std::isfinite(row[u])) ++valid;
  }
  return valid * 200 < sampled || sampled == 0;  // under 0.5 %
}

bool viewHoldsGroundWithin(const Eigen::Isometry3d& T_WC, const CameraIntrinsics& k, double reach_m) {
  const double height_m = T_WC.translation().z();
  if (!(height_m > 0.0)) return true;
  if (!(k.fx_px > 0.0) || !(k.fy_px > 0.0) || !(reach_m > 0.0)) return false;
  const double w = k.width_px, h = k.height_px;
  const std::array<Eigen::Vector2d, 9> pixels = {
      {{0, 0}, {w, 0}, {0, h}, {w, h}, {0.5 * w, 0}, {0.5 * w, h}, {0, 0.5 * h}, {w, 0.5 * h}, {k.cx_px, k.cy_px}}};
  for (const Eigen::Vector2d& px : pixels) {
    const Eigen::Vector3d ray_C((px.x() - k.cx_px) / k.fx_px, (px.y() - k.cy_px) / k.fy_px, 1.0);
    const Eigen::Vector3d dir_W = (T_WC.linear() * ray_C).normalized();
    if (dir_W.z() < 0.0 && height_m / -dir_W.z() <= reach_m) return true;
  }
  return false;
}

}  // namespace aerotrack::hal
