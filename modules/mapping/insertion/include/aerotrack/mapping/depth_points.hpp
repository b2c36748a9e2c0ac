// Depth image to world points for OctoMap insertion (issue 4). Every decimation-th pixel of a
// depth image is back-projected with the pinhole model, x = (u_c - cx) z / fx,
// y = (v_c - cy) z / fy in the camera frame C (OpenCV: x right, y down, z forward), and moved to
// the world frame W with T_WC. Pixel coordinates follow the HAL convention (the simulator's
// renderDepth, hal::Keypoint2D): the origin is the top-left corner of the top-left pixel, so the
// centre of pixel (u, v) is u_c = u + 0.5, v_c = v + 0.5. Distortion is ignored (depth images
// are rectified). Ranges are Euclidean distances from the camera centre along the pixel's ray,
// r = z * |(x/z, y/z, 1)| (the same measure as OctoMap's maxrange). A pixel within
// [min_range_m, max_range_m] gives a hit (an obstacle surface); a farther one gives a miss point
// on its ray at exactly max_range_m, so that the space in front of it is cleared without
// claiming an obstacle (OctoMap's maxrange semantics).
#pragma once

#include <cstddef>
#include <span>

#include <octomap/Pointcloud.h>
#include <Eigen/Geometry>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::mapping {

struct DepthPointsParams {
  int decimation = 4;        ///< Take every N-th pixel in u and in v, starting at (0, 0); >= 1.
  double min_range_m = 0.3;  ///< Nearer pixels are ignored (stereo minimum range); >= 0.
  double max_range_m = 6.0;  ///< Farther pixels become misses at this range; > min_range_m, finite.
};

/// A vertical cylinder in W (from min_z_m up to max_z_m) whose depth returns are not obstacles: the followed
/// person. The depth camera of a drone that follows someone sees them in most of its frames; mapped, their body
/// would be an obstacle where they stand and a wall across the sight line the planner keeps clear, and it would
/// stay behind them as a trail of ghosts (what a real D435 gives; the simulator renders the person in depth since
/// issue 22). A return inside the cylinder clears its ray up to the return, as a miss does, with no occupied end
/// (Fast-Tracker removes the target's points the same way).
struct ExcludedBody {
  Eigen::Vector2d center_W_m = Eigen::Vector2d::Zero();
  double radius_m = 0.0;  ///< <= 0 or not finite: excludes nothing.
  double min_z_m = 0.0;   ///< Returns below this stay obstacles (the ground under the person's feet).
  double max_z_m = 0.0;   ///< Returns above this stay obstacles (a ceiling over the person).
};

/// Ok if decimation >= 1 and 0 <= min_range_m < max_range_m < inf.
rt::Status validate(const DepthPointsParams& params);

/// What one conversion did with the pixels it visited.
struct DepthPointsStats {
  std::size_t pixels_visited = 0;  ///< ceil(width / N) * ceil(height / N).
  std::size_t hits = 0;            ///< Points appended to hits_W.
  std::size_t misses = 0;          ///< Points appended to misses_W.
  std::size_t no_data = 0;         ///< Depth 0, negative, NaN or inf.
  std::size_t too_near = 0;        ///< Range below min_range_m.
  std::size_t excluded = 0;        ///< Returns inside an ExcludedBody (appended to misses_W).
};

/// Converts one depth frame (hal::DepthFrame::depth_m, CV_32FC1 metres along the optical axis)
/// seen from camera pose T_WC (camera C in world W) into world-frame hit and miss points. The two
/// clouds are cleared first and refilled; their memory is reused (the first call, or a larger
/// image, reserves; later calls do not allocate). Errors (nothing is appended): invalid params,
/// a depth image that is empty, not CV_32FC1 or not the size in frame.intrinsics, non-positive or
/// non-finite focal lengths, or a non-finite T_WC.
/// A return within [min_range_m, max_range_m] inside one of `excluded` becomes a miss point at the return.
/// Cost: O(pixels visited x (1 + excluded bodies)). Thread safety: reentrant (no shared state).
rt::Expected<DepthPointsStats> depthToPoints(const hal::DepthFrame& frame, const Eigen::Isometry3d& T_WC,
                                             const DepthPointsParams& params, octomap::Pointcloud& hits_W,
                                             octomap::Pointcloud& misses_W,
                                             std::span<const ExcludedBody> excluded = {});

}  // namespace aerotrack::mapping
