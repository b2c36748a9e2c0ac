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
  if (!std::isfinite(p.split_seam_m) || p.split_seam_m < 0.0)
    return rt::Error{"depth_people: split_seam_m must be finite and not negative"};
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
  p.split_two = node.getBool("split_two");
  p.split_seam_m = node.getDouble("split_seam_m", 0.0, 1.0);
  p.centre_behind_m = node.getDouble("centre_behind_m", 0.0, 2.0);
  p.std_m = node.getDouble("std_m", 0.001, 10.0);
  p.std_per_m2 = node.getDouble("std_per_m2", 0.0, 1.0);
  p.feed_followed = node.getBool("feed_followed");
  p.feed_max_std_m = node.getDouble("feed_max_std_m", 0.0, 10.0);
  node.finish();
  return p;
}

namespace {
// The seam's bins are at least this wide (and at least a sampled pixel's footprint at the component's far side, so
// that no bin inside a body is empty), and each side of a seam at least this wide: half of a body seen side on.
constexpr double kSeamBinMinM = 0.05;
constexpr double kSeamSideMinM = 0.2;
}  // namespace

DepthPeopleFinder::Extent DepthPeopleFinder::extent(const Component& comp, const Axes& axes, double from_m, double to_m,
                                                    double pixel_area_per_z2, std::size_t n) const {
  const double inf = std::numeric_limits<double>::infinity();
  Extent e;
  e.min_depth = inf;
  e.lo = e.near = inf;
  e.hi = e.far = -inf;
  const Eigen::Vector2d across = axes.across();
  const auto id = label_[static_cast<std::size_t>(comp.first)];
  for (std::size_t i = static_cast<std::size_t>(comp.first); i < n; ++i) {
    if (label_[i] != id) continue;
    const Eigen::Vector3f& p = points_W_[i];
    const Eigen::Vector2d d = p.head<2>().cast<double>() - axes.camera_W;
    const double a = d.dot(across);
    if (a < from_m || a >= to_m) continue;
    const double b = d.dot(axes.along);
    const auto z = static_cast<double>(depth_[i]);
    ++e.pixels;
    e.area_m2 += pixel_area_per_z2 * z * z;
    e.sum_W += p.cast<double>();
    e.top_m = std::max(e.top_m, static_cast<double>(p.z()));
    e.min_depth = std::min(e.min_depth, z);
    e.lo = std::min(e.lo, a);
    e.hi = std::max(e.hi, a);
    e.near = std::min(e.near, b);
    e.far = std::max(e.far, b);
  }
  return e;
}

std::optional<double> DepthPeopleFinder::seamAcross(const Component& comp, const Axes& axes, const Extent& whole,
                                                    double fx_px, std::size_t n) {
  const double bin_m = std::max(kSeamBinMinM, params_.stride_px * whole.far / fx_px);
  const std::size_t bins = std::min(seam_near_.size(), static_cast<std::size_t>((whole.hi - whole.lo) / bin_m) + 1);
  if (bins < 3) return std::nullopt;
  const double inf = std::numeric_limits<double>::infinity();
  std::fill_n(seam_near_.begin(), bins, inf);
  const Eigen::Vector2d across = axes.across();
  const auto id = label_[static_cast<std::size_t>(comp.first)];
  for (std::size_t i = static_cast<std::size_t>(comp.first); i < n; ++i) {
    if (label_[i] != id) continue;
    const Eigen::Vector2d d = points_W_[i].head<2>().cast<double>() - axes.camera_W;
    const auto b = std::min(bins - 1, static_cast<std::size_t>(std::max(0.0, (d.dot(across) - whole.lo) / bin_m)));
    seam_near_[b] = std::min(seam_near_[b], d.dot(axes.along));
  }
  // The seam: the bin whose nearest surface lies farthest behind the chord between the nearest points on its two
  // sides (each body's front is convex, nearest at its middle; the seam between two is concave, and where one body
  // stands behind the other, the nearer one's side hides part of it: a step, not a peak), with room for a body's side
  // on each. An empty bin inside is a gap, the clearest seam.
  const double stereo_m = params_.std_per_m2 * whole.far * whole.far;
  const double needed_m = params_.split_seam_m + 2.0 * stereo_m;
  double best_m = -inf;
  std::optional<double> seam;
  std::size_t left = 0;  // the nearest bin left of b
  for (std::size_t b = 1; b + 1 < bins; ++b) {
    if (seam_near_[b - 1] < seam_near_[left]) left = b - 1;
    const double from_lo_m = static_cast<double>(b) * bin_m;
    if (from_lo_m < kSeamSideMinM || whole.hi - whole.lo - from_lo_m - bin_m < kSeamSideMinM) continue;
    const auto right =
        static_cast<std::size_t>(std::min_element(seam_near_.begin() + static_cast<std::ptrdiff_t>(b) + 1,
                                                  seam_near_.begin() + static_cast<std::ptrdiff_t>(bins)) -
                                 seam_near_.begin());
    const double w = static_cast<double>(b - left) / static_cast<double>(right - left);
    const double behind_m = seam_near_[b] - ((1.0 - w) * seam_near_[left] + w * seam_near_[right]);
    if (behind_m >= needed_m && behind_m > best_m) {
      best_m = behind_m;
      seam = whole.lo + from_lo_m + 0.5 * bin_m;
    }
  }
  return seam;
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
  if (seam_near_.empty()) seam_near_.resize(static_cast<std::size_t>(2.0 * params_.max_width_m / kSeamBinMinM) + 2);
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
  // The shape of a person; then each one's extent across and along the line of sight to its mean, and a component
  // too wide for one body split at the seam between two (more passes over its pixels: they are not stored apart).
  const Eigen::Vector2d camera_W = T_WD.translation().head<2>();
  std::size_t found = 0;
  const auto place = [&](const Extent& e) {
    if (e.pixels == 0 || e.area_m2 < params_.min_area_m2 || e.top_m < params_.min_top_m) return;
    if (e.hi - e.lo > params_.max_width_m || e.far - e.near > params_.max_depth_m) return;
    const Eigen::Vector2d mean_W = e.sum_W.head<2>() / e.pixels;
    const Eigen::Vector2d line = mean_W - camera_W;
    const double range = line.norm();
    if (!(range > 1e-6)) return;
    DepthPerson person;
    person.p_W_m = mean_W + params_.centre_behind_m * line / range;
    person.range_m = range + params_.centre_behind_m;
    person.top_m = e.top_m;
    person.pixels = e.pixels;
    person.area_m2 = e.area_m2;
    const double stereo_m = params_.std_per_m2 * e.min_depth * e.min_depth;
    person.std_m = std::hypot(params_.std_m, stereo_m);
    // Nearest first: kept when `out` is too small for everyone.
    std::size_t at = std::min(found, out.size() - 1);
    if (found >= out.size() && !(person.range_m < out[at].range_m)) return;
    while (at > 0 && person.range_m < out[at - 1].range_m) {
      out[at] = out[at - 1];
      --at;
    }
    out[at] = person;
    found = std::min(found + 1, out.size());
  };
  for (const Component& comp : components_) {
    if (comp.area_m2 < params_.min_area_m2 || comp.too_tall || comp.cut || comp.top_m < params_.min_top_m) continue;
    const Eigen::Vector2d line = comp.sum_W.head<2>() / comp.pixels - camera_W;
    const double range = line.norm();
    if (!(range > 1e-6)) continue;
    const Axes axes{camera_W, line / range};
    const double inf = std::numeric_limits<double>::infinity();
    const Extent whole = extent(comp, axes, -inf, inf, pixel_area_per_z2, n);
    const double width_m = whole.hi - whole.lo;
    if (width_m <= params_.max_width_m || !params_.split_two) {
      place(whole);
      continue;
    }
    if (width_m > 2.0 * params_.max_width_m) continue;  // wider than two bodies: a wall, a hedge, a crowd
    const std::optional<double> seam = seamAcross(comp, axes, whole, k.fx_px, n);
    if (!seam) continue;  // one wide thing (a wall, a box, a bin): no person
    place(extent(comp, axes, -inf, *seam, pixel_area_per_z2, n));
    place(extent(comp, axes, *seam, inf, pixel_area_per_z2, n));
  }
  return found;
}

}  // namespace aerotrack::estimation
