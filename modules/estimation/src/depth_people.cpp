// People found in the depth camera's image: see depth_people.hpp.
#include "aerotrack/estimation/depth_people.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/core/mat.hpp>

namespace aerotrack::estimation {

rt::Status validate(const DepthPeopleParams& p) {
  const bool finite = std::isfinite(p.max_range_m) && std::isfinite(p.min_z_m) && std::isfinite(p.min_top_m) &&
                      std::isfinite(p.max_top_m) && std::isfinite(p.max_width_m) && std::isfinite(p.max_depth_m) &&
                      std::isfinite(p.depth_jump_m) && std::isfinite(p.centre_behind_m) && std::isfinite(p.std_m) &&
                      std::isfinite(p.std_per_m2);
  if (!finite) return rt::Error{"depth_people: every value must be finite"};
  if (p.stride_px < 1) return rt::Error{"depth_people: stride_px must be at least 1"};
  if (!(p.max_range_m > 0.0)) return rt::Error{"depth_people: max_range_m must be positive"};
  if (!(p.min_z_m > 0.0 && p.min_z_m < p.min_top_m && p.min_top_m < p.max_top_m))
    return rt::Error{"depth_people: needs 0 < min_z_m < min_top_m < max_top_m"};
  if (!(p.max_width_m > 0.0 && p.max_depth_m > 0.0 && p.depth_jump_m > 0.0))
    return rt::Error{"depth_people: max_width_m, max_depth_m and depth_jump_m must be positive"};
  if (!std::isfinite(p.min_area_m2) || p.min_area_m2 < 0.0)
    return rt::Error{"depth_people: min_area_m2 must be finite and not negative"};
  if (!std::isfinite(p.feed_max_std_m) || p.feed_max_std_m < 0.0)
    return rt::Error{"depth_people: feed_max_std_m must be finite and not negative"};
  if (p.centre_behind_m < 0.0 || !(p.std_m > 0.0) || p.std_per_m2 < 0.0)
    return rt::Error{"depth_people: needs centre_behind_m >= 0, std_m > 0, std_per_m2 >= 0"};
  return {};
}

DepthPeopleParams parseDepthPeopleParams(const rt::ConfigNode& node) {
  DepthPeopleParams p;
  p.enabled = node.getBool("enabled");
  p.stride_px = node.getInt("stride_px", 1, 64);
  p.max_range_m = node.getDouble("max_range_m", 0.5, 100.0);
  p.min_z_m = node.getDouble("min_z_m", 0.01, 3.0);
  p.min_top_m = node.getDouble("min_top_m", 0.1, 3.0);
  if (p.min_top_m <= p.min_z_m) node.fail("min_top_m", "must exceed min_z_m");
  p.max_top_m = node.getDouble("max_top_m", 0.2, 5.0);
  if (p.max_top_m <= p.min_top_m) node.fail("max_top_m", "must exceed min_top_m");
  p.max_width_m = node.getDouble("max_width_m", 0.05, 5.0);
  p.max_depth_m = node.getDouble("max_depth_m", 0.05, 5.0);
  p.depth_jump_m = node.getDouble("depth_jump_m", 0.01, 5.0);
  p.min_area_m2 = node.getDouble("min_area_m2", 0.0, 100.0);
  p.centre_behind_m = node.getDouble("centre_behind_m", 0.0, 2.0);
  p.std_m = node.getDouble("std_m", 0.001, 10.0);
  p.std_per_m2 = node.getDouble("std_per_m2", 0.0, 1.0);
  p.feed_followed = node.getBool("feed_followed");
  p.feed_max_std_m = node.getDouble("feed_max_std_m", 0.0, 10.0);
  node.finish();
  return p;
}

std::size_t DepthPeopleFinder::find(const hal::DepthFrame& depth, const Eigen::Isometry3d& T_WD,
                                    std::span<DepthPerson> out) {
  const cv::Mat& image = depth.depth_m;
  const hal::CameraIntrinsics& k = depth.intrinsics;
  if (image.empty() || image.type() != CV_32FC1 || image.cols != k.width_px || image.rows != k.height_px ||
      !(k.fx_px > 0.0) || !(k.fy_px > 0.0) || !T_WD.matrix().allFinite() || out.empty())
    return 0;
  const int s = params_.stride_px;
  const int cols = (image.cols + s - 1) / s;
  const int rows = (image.rows + s - 1) / s;
  const auto n = static_cast<std::size_t>(cols) * static_cast<std::size_t>(rows);
  if (label_.size() < n) {  // the first frame of this size: every buffer at its largest
    points_W_.resize(n);
    depth_.resize(n);
    label_.resize(n);
    stack_.resize(n);
    components_.reserve(n);
  }
  // Each sampled pixel's point in W (the pixel's centre: pixel u covers [u, u + 1), HAL convention); a body pixel
  // stands above the ground. A pixel without data, or beyond max_range_m, is nobody's.
  const Eigen::Matrix3f R = T_WD.linear().cast<float>();
  const Eigen::Vector3f t = T_WD.translation().cast<float>();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int r = 0; r < rows; ++r) {
    const float* row = image.ptr<float>(r * s);
    for (int c = 0; c < cols; ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(c);
      const float z = row[static_cast<std::ptrdiff_t>(c) * s];
      label_[i] = -1;
      if (!(z > 0.0F) || !(static_cast<double>(z) <= params_.max_range_m)) {  // NaN fails both
        depth_[i] = 0.0F;
        points_W_[i].setConstant(nan);
        continue;
      }
      const Eigen::Vector3f q(static_cast<float>((c * s + 0.5 - k.cx_px) / k.fx_px) * z,
                              static_cast<float>((r * s + 0.5 - k.cy_px) / k.fy_px) * z, z);
      const Eigen::Vector3f p = R * q + t;
      depth_[i] = z;
      points_W_[i] = static_cast<double>(p.z()) >= params_.min_z_m ? p : Eigen::Vector3f::Constant(nan);
    }
  }
  // A pixel's footprint at depth z, per z^2 (the sampled pixel stands for stride^2 of them).
  const double pixel_area_per_z2 = static_cast<double>(s) * s / (k.fx_px * k.fy_px);
  // Connected components of body pixels, 4-neighbours whose depths differ by less than depth_jump_m.
  components_.clear();
  const auto body = [&](std::size_t i) { return !std::isnan(points_W_[i].x()); };
  for (std::size_t seed = 0; seed < n; ++seed) {
    if (!body(seed) || label_[seed] >= 0) continue;
    const auto id = static_cast<std::int32_t>(components_.size());
    Component comp;
    comp.first = static_cast<std::int32_t>(seed);
    comp.min_depth = comp.max_depth = static_cast<double>(depth_[seed]);
    std::size_t top = 0;
    stack_[top++] = static_cast<std::int32_t>(seed);
    label_[seed] = id;
    while (top > 0) {
      const auto i = static_cast<std::size_t>(stack_[--top]);
      const int r = static_cast<int>(i) / cols;
      const int c = static_cast<int>(i) % cols;
      const Eigen::Vector3f& p = points_W_[i];
      ++comp.pixels;
      const auto z = static_cast<double>(depth_[i]);
      comp.area_m2 += pixel_area_per_z2 * z * z;
      comp.sum_W += p.cast<double>();
      comp.top_m = std::max(comp.top_m, static_cast<double>(p.z()));
      comp.too_tall = comp.too_tall || static_cast<double>(p.z()) > params_.max_top_m;
      comp.cut = comp.cut || r == 0 || c == 0 || c == cols - 1;
      comp.min_depth = std::min(comp.min_depth, static_cast<double>(depth_[i]));
      comp.max_depth = std::max(comp.max_depth, static_cast<double>(depth_[i]));
      const auto visit = [&](int rr, int cc) {
        if (rr < 0 || rr >= rows || cc < 0 || cc >= cols) return;
        const std::size_t j =
            static_cast<std::size_t>(rr) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(cc);
        if (label_[j] >= 0 || !body(j)) return;
        const double step_m = std::abs(static_cast<double>(depth_[j]) - z);
        // The difference of two pixels' stereo noise: sqrt(2) k z^2; three of its standard deviations.
        if (step_m > params_.depth_jump_m + 3.0 * std::sqrt(2.0) * params_.std_per_m2 * z * z) return;
        label_[j] = id;
        stack_[top++] = static_cast<std::int32_t>(j);
      };
      visit(r - 1, c);
      visit(r + 1, c);
      visit(r, c - 1);
      visit(r, c + 1);
    }
    components_.push_back(comp);
  }
  // The shape of a person, then each one's width across the line of sight to its mean (a second pass over its
  // pixels: the components' pixels are not stored apart).
  const Eigen::Vector2d camera_W = T_WD.translation().head<2>();
  std::size_t found = 0;
  for (Component& comp : components_) {
    if (comp.area_m2 < params_.min_area_m2 || comp.too_tall || comp.cut || comp.top_m < params_.min_top_m) continue;
    const Eigen::Vector2d mean_W = comp.sum_W.head<2>() / comp.pixels;
    const Eigen::Vector2d line = mean_W - camera_W;
    const double range = line.norm();
    if (!(range > 1e-6)) continue;
    const Eigen::Vector2d along = line / range;
    const Eigen::Vector2d across(-along.y(), along.x());
    double lo = std::numeric_limits<double>::infinity(), hi = -lo, near = lo, far = -lo;
    const auto id = label_[static_cast<std::size_t>(comp.first)];
    for (std::size_t i = static_cast<std::size_t>(comp.first); i < n; ++i) {
      if (label_[i] != id) continue;
      const Eigen::Vector2d d = points_W_[i].head<2>().cast<double>() - camera_W;
      lo = std::min(lo, d.dot(across));
      hi = std::max(hi, d.dot(across));
      near = std::min(near, d.dot(along));
      far = std::max(far, d.dot(along));
    }
    if (hi - lo > params_.max_width_m || far - near > params_.max_depth_m) continue;
    DepthPerson person;
    person.p_W_m = mean_W + params_.centre_behind_m * along;
    person.range_m = range + params_.centre_behind_m;
    person.top_m = comp.top_m;
    person.pixels = comp.pixels;
    person.area_m2 = comp.area_m2;
    const double stereo_m = params_.std_per_m2 * comp.min_depth * comp.min_depth;
    person.std_m = std::hypot(params_.std_m, stereo_m);
    // Nearest first: kept when `out` is too small for everyone.
    std::size_t at = std::min(found, out.size() - 1);
    if (found >= out.size() && !(person.range_m < out[at].range_m)) continue;
    while (at > 0 && person.range_m < out[at - 1].range_m) {
      out[at] = out[at - 1];
      --at;
    }
    out[at] = person;
    found = std::min(found + 1, out.size());
  }
  return found;
}

}  // namespace aerotrack::estimation
