// The simulator's static obstacles (axis-aligned boxes for walls and buildings, vertical
// cylinders for trees and poles; see geometry.hpp) and fast exact geometric queries against
// them: ray casting, segment visibility (line of sight to the person's keypoints) and Euclidean
// distance (collisions, clearance statistics).
//
// Spatial index: a uniform 2D grid over the XY footprint of all obstacles; each cell lists the
// obstacles whose footprint overlaps it (conservatively, padded by 1 um). Rays walk the grid with
// the 2D DDA of Amanatides & Woo, "A Fast Voxel Traversal Algorithm for Ray Tracing"
// (Eurographics 1987), test every obstacle listed in each visited cell (slab test for boxes,
// quadratic plus slab for cylinders) and stop once the nearest hit lies before the current
// cell's exit. distance() searches square rings of cells around the query outward and stops
// once a ring's lower bound is no nearer than the best obstacle found. An obstacle listed in
// several cells may be tested more than once; the tests are pure, so this never changes a result.
//
// The ObstacleWorld is immutable after create(): every const method is thread-safe (several
// threads may query one world) and queries allocate nothing.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "aerotrack/hal/sim/geometry.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::sim {

class ObstacleWorld {
 public:
  /// Most grid cells create() accepts (a larger footprint needs a larger cell_size_m).
  static constexpr std::int64_t kMaxCells = std::int64_t{1} << 24;

  /// Validates the obstacles (finite coordinates, min <= max, radius > 0, z_min <= z_max) and
  /// cell_size_m (finite, > 0), then builds the grid over the obstacles' footprint. No obstacles
  /// is valid (an empty world: only the ground). Allocates. Errors name the offending obstacle.
  static rt::Expected<ObstacleWorld> create(std::vector<Box> boxes, std::vector<Cylinder> cylinders,
                                            double cell_size_m = 1.0);

  /// Distance in metres along the ray origin_W_m + t * dir_W (t >= 0) to the first hit of an
  /// obstacle or, if hit_ground, the ground (the half-space z <= 0), when it is <= max_range_m;
  /// std::nullopt otherwise (no hit, max_range_m < 0, or a non-finite input).
  /// dir_W must be unit length (not checked: a longer dir_W scales t down accordingly).
  /// Obstacles and the ground are closed solids: an origin inside one or on its surface returns
  /// 0. Rays parallel to the axes, vertical rays, origins outside the grid and rays leaving it are
  /// all handled. Thread-safe, allocation-free.
  std::optional<double> raycast(const Eigen::Vector3d& origin_W_m, const Eigen::Vector3d& dir_W, double max_range_m,
                                bool hit_ground) const;

  /// True if no obstacle meets the closed segment [a_W_m, b_W_m] (the ground does not count):
  /// line of sight. Touching an obstacle's surface, or an end point inside one, blocks.
  /// Thread-safe, allocation-free.
  bool segmentClear(const Eigen::Vector3d& a_W_m, const Eigen::Vector3d& b_W_m) const;

  /// Exact Euclidean distance in metres from p_W_m to the nearest obstacle (0 on or inside one;
  /// the ground does not count); +infinity if there are no obstacles; NaN if p_W_m is not
  /// finite. Thread-safe, allocation-free.
  double distance(const Eigen::Vector3d& p_W_m) const;

  const std::vector<Box>& boxes() const { return boxes_; }
  const std::vector<Cylinder>& cylinders() const { return cylinders_; }
  /// Axis-aligned bounds of all obstacles in W; an empty world has min = +inf, max = -inf.
  const Box& bounds() const { return bounds_; }
  double cellSize() const { return cell_size_m_; }
  /// Grid cells along x and y (0 x 0 for an empty world).
  Eigen::Vector2i gridSize() const { return {nx_, ny_}; }

 private:
  ObstacleWorld() = default;

  /// Nearest obstacle hit with t in [0, t_end] (the grid walk).
  std::optional<double> castObstacles(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_end) const;
  double obstacleDistance(std::uint32_t id, const Eigen::Vector3d& p) const;

  std::vector<Box> boxes_;
  std::vector<Cylinder> cylinders_;
  Box bounds_;
  double cell_size_m_ = 1.0;
  Eigen::Vector2d grid_min_W_m_ = Eigen::Vector2d::Zero();  ///< Corner of cell (0, 0).
  int nx_ = 0;
  int ny_ = 0;
  /// Compressed cell lists: the obstacles of cell (i, j) are cell_items_[cell_begin_[c] ..
  /// cell_begin_[c + 1]) with c = j * nx_ + i. An id < boxes_.size() is a box, otherwise the
  /// cylinder id - boxes_.size().
  std::vector<std::uint32_t> cell_begin_;
  std::vector<std::uint32_t> cell_items_;
};

}  // namespace aerotrack::hal::sim
