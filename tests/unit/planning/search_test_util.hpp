// Test helpers for the kinodynamic search: LocalGrids built from axis-aligned occupied boxes (through an
// OctoMap tree, as the mapper fills them), and a dense check of a returned path against the grid and the
// dynamic limits.
#pragma once

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <utility>
#include <vector>

#include "../mapping/grid/grid_test_util.hpp"
#include "aerotrack/mapping/local_grid.hpp"
#include "aerotrack/planning/kinodynamic_search.hpp"

namespace aerotrack::planning::test {

struct OccupiedBox {
  Eigen::Vector3d min_W_m;
  Eigen::Vector3d max_W_m;
};

/// Whether point c lies in the box (faces included).
inline bool inBox(const OccupiedBox& box, const Eigen::Vector3d& c) {
  return (c.array() >= box.min_W_m.array()).all() && (c.array() <= box.max_W_m.array()).all();
}

/// Marks occupied, in `tree`, every cell of edge resolution_m whose centre lies in one of the boxes.
inline void markBoxes(octomap::OcTree& tree, const std::vector<OccupiedBox>& boxes, double resolution_m) {
  for (const OccupiedBox& box : boxes) {
    const mapping::CellIndex lo = (box.min_W_m / resolution_m).array().floor().cast<int>();
    const mapping::CellIndex hi = (box.max_W_m / resolution_m).array().ceil().cast<int>();
    for (int z = lo.z(); z < hi.z(); ++z) {
      for (int y = lo.y(); y < hi.y(); ++y) {
        for (int x = lo.x(); x < hi.x(); ++x) {
          const Eigen::Vector3d c = (Eigen::Vector3d(x, y, z).array() + 0.5) * resolution_m;
          if (inBox(box, c)) mapping::test::setCell(tree, mapping::CellIndex(x, y, z), true);
        }
      }
    }
  }
}

/// A grid whose window (size_m, centred on center_W_m) has the cells whose centres lie in the boxes
/// occupied, and every other cell unknown (planned through as free: unknown_is_occupied = false).
inline mapping::LocalGrid makeBoxGrid(const Eigen::Vector3d& size_m, const Eigen::Vector3d& center_W_m,
                                      const std::vector<OccupiedBox>& boxes, double inflation_radius_m = 0.25) {
  mapping::LocalGridParams params;
  params.resolution_m = 0.1;
  params.size_m = size_m;
  params.inflation_radius_m = inflation_radius_m;
  params.recenter_distance_m = 0.0;
  octomap::OcTree tree = mapping::test::makeTree(params.resolution_m);
  markBoxes(tree, boxes, params.resolution_m);
  mapping::LocalGrid grid = mapping::test::makeGrid(params);
  EXPECT_TRUE(grid.recenter(center_W_m, tree).has_value());
  EXPECT_TRUE(grid.rebuild(tree).has_value());
  return grid;
}

struct PathCheck {
  double max_speed_axis_mps = 0.0;
  double max_acceleration_axis_mps2 = 0.0;
  int blocked_samples = 0;
  int samples = 0;
};

/// Samples the path every 2 ms: the largest per-axis speed and acceleration, and how many samples are
/// blocked in the grid (isOccupied or outside the window).
inline PathCheck checkPath(const SearchPath& path, const mapping::LocalGrid& grid) {
  PathCheck check;
  const int n = std::max(1, static_cast<int>(std::ceil(path.duration_s / 0.002)));
  for (int i = 0; i <= n; ++i) {
    const double t = path.duration_s * i / n;
    const KinematicState s = path.stateAt(t);
    check.max_speed_axis_mps = std::max(check.max_speed_axis_mps, s.v_W_mps.cwiseAbs().maxCoeff());
    check.max_acceleration_axis_mps2 =
        std::max(check.max_acceleration_axis_mps2, path.accelerationAt(t).cwiseAbs().maxCoeff());
    if (!grid.inWindow(s.p_W_m) || grid.isOccupied(s.p_W_m)) ++check.blocked_samples;
    ++check.samples;
  }
  return check;
}

}  // namespace aerotrack::planning::test
