// Test helpers for LocalGrid: octree construction, slow obvious references (cell state by tree
// search, inflation count by brute force over all voxels near a cell, the cells a segment passes
// through by splitting it at every grid-plane crossing), and a whole-window comparison of two grids.
#pragma once

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "../../../support/require.hpp"
#include "aerotrack/mapping/local_grid.hpp"

namespace aerotrack::mapping::test {

inline constexpr int kKeyOffset = 32768;
inline constexpr float kOccupiedLogOdds = 2.0f;  // clamped by OctoMap to its max (0.971)
inline constexpr float kFreeLogOdds = -2.0f;     // clamped to its min (0.1192)

inline octomap::OcTreeKey keyOf(const CellIndex& cell) {
  return octomap::OcTreeKey(static_cast<octomap::key_type>(cell.x() + kKeyOffset),
                            static_cast<octomap::key_type>(cell.y() + kKeyOffset),
                            static_cast<octomap::key_type>(cell.z() + kKeyOffset));
}

/// A tree with change detection on, as the mapper keeps it.
inline octomap::OcTree makeTree(double resolution_m = 0.1) {
  octomap::OcTree tree(resolution_m);
  tree.enableChangeDetection(true);
  return tree;
}

inline void setCell(octomap::OcTree& tree, const CellIndex& cell, bool occupied) {
  tree.setNodeValue(keyOf(cell), occupied ? kOccupiedLogOdds : kFreeLogOdds);
}

inline LocalGrid makeGrid(LocalGridParams params) {
  return aerotrack::test::require(LocalGrid::create(params), "LocalGrid::create");
}

/// Reference state: what a search of the tree says about the cell.
inline CellState treeState(const octomap::OcTree& tree, const CellIndex& cell) {
  const octomap::OcTreeNode* node = tree.search(keyOf(cell));
  if (node == nullptr) return CellState::kUnknown;
  return tree.isNodeOccupied(node) ? CellState::kOccupied : CellState::kFree;
}

/// Reference inflation count: occupied voxels whose centre is within radius of the cell's centre,
/// distances measured in metres between centres (the 1e-9 m slack keeps exact ties in).
inline int bruteCount(const octomap::OcTree& tree, const LocalGrid& grid, const CellIndex& cell) {
  const double radius = grid.params().inflation_radius_m;
  const int reach = static_cast<int>(std::ceil(radius / grid.params().resolution_m));
  int count = 0;
  for (int dz = -reach; dz <= reach; ++dz) {
    for (int dy = -reach; dy <= reach; ++dy) {
      for (int dx = -reach; dx <= reach; ++dx) {
        const CellIndex voxel = cell + CellIndex(dx, dy, dz);
        const double distance = (grid.cellCenterM(voxel) - grid.cellCenterM(cell)).norm();
        if (distance <= radius + 1e-9 && treeState(tree, voxel) == CellState::kOccupied) ++count;
      }
    }
  }
  return count;
}

/// Every window cell of `grid` has the reference state and count (small windows only: slow).
inline void expectMatchesTree(const LocalGrid& grid, const octomap::OcTree& tree, const std::string& what) {
  const CellBox box = grid.windowBox();
  int mismatches = 0;
  for (int z = box.lo.z(); z < box.hi.z(); ++z) {
    for (int y = box.lo.y(); y < box.hi.y(); ++y) {
      for (int x = box.lo.x(); x < box.hi.x(); ++x) {
        const CellIndex cell(x, y, z);
        if (grid.cellState(cell) != treeState(tree, cell) ||
            grid.inflationCount(cell) != bruteCount(tree, grid, cell)) {
          if (++mismatches <= 3) ADD_FAILURE() << what << ": cell " << cell.transpose() << " differs from the tree";
        }
      }
    }
  }
  EXPECT_EQ(mismatches, 0) << what;
}

/// Same window, and every window cell has the same state and the same inflation count.
inline void expectSameGrid(const LocalGrid& actual, const LocalGrid& expected, const std::string& what) {
  ASSERT_EQ(actual.windowMinCell(), expected.windowMinCell()) << what;
  ASSERT_EQ(actual.windowSizeCells(), expected.windowSizeCells()) << what;
  const CellBox box = expected.windowBox();
  long mismatches = 0;
  for (int z = box.lo.z(); z < box.hi.z(); ++z) {
    for (int y = box.lo.y(); y < box.hi.y(); ++y) {
      for (int x = box.lo.x(); x < box.hi.x(); ++x) {
        const CellIndex cell(x, y, z);
        const bool same = actual.cellState(cell) == expected.cellState(cell) &&
                          actual.inflationCount(cell) == expected.inflationCount(cell);
        if (!same && ++mismatches <= 3) {
          ADD_FAILURE() << what << ": cell " << cell.transpose() << " state "
                        << static_cast<int>(actual.cellState(cell)) << " vs "
                        << static_cast<int>(expected.cellState(cell)) << ", count " << actual.inflationCount(cell)
                        << " vs " << expected.inflationCount(cell);
        }
      }
    }
  }
  EXPECT_EQ(mismatches, 0) << what;
}

/// A grid like `like` whose window is at the same place, rebuilt from the tree (the reference).
inline LocalGrid rebuiltAt(const LocalGrid& like, const octomap::OcTree& tree) {
  LocalGridParams params = like.params();
  params.recenter_distance_m = 0.0;
  LocalGrid grid = makeGrid(params);
  // The centre of cell (min + size / 2) snaps back to exactly this window.
  const CellIndex center_cell = like.windowMinCell() + CellIndex(like.windowSizeCells().array() / 2);
  EXPECT_TRUE(grid.recenter(grid.cellCenterM(center_cell), tree).has_value());
  EXPECT_TRUE(grid.rebuild(tree).has_value());
  EXPECT_EQ(grid.windowMinCell(), like.windowMinCell());
  return grid;
}

/// Cells the segment a->b passes through, by splitting it at every crossing of a cell boundary plane:
/// each piece lies in one cell (the cell of its midpoint). `must` holds the cells of pieces longer than
/// 1e-7 cells; `may` also holds every cell whose closed box touches a piece of near-zero length (where the
/// segment grazes an edge or a corner, or ends on a face: either answer is right there). Window cells only.
struct SegmentCells {
  std::vector<CellIndex> must;
  std::vector<double> must_t_enter;  // where along a->b (0..1) each must cell is entered
  std::vector<CellIndex> may;
};

inline SegmentCells segmentCells(const LocalGrid& grid, const Eigen::Vector3d& a_W_m, const Eigen::Vector3d& b_W_m) {
  const double scale = 1.0 / grid.params().resolution_m;
  const Eigen::Vector3d a = a_W_m * scale;
  const Eigen::Vector3d d = b_W_m * scale - a;
  std::vector<double> ts = {0.0, 1.0};
  for (int axis = 0; axis < 3; ++axis) {
    if (d[axis] == 0.0) continue;
    const double from = std::min(a[axis], a[axis] + d[axis]);
    const double to = std::max(a[axis], a[axis] + d[axis]);
    for (double plane = std::ceil(from); plane <= to; plane += 1.0) ts.push_back((plane - a[axis]) / d[axis]);
  }
  std::sort(ts.begin(), ts.end());
  SegmentCells cells;
  for (std::size_t i = 0; i + 1 < ts.size(); ++i) {
    const double t0 = std::clamp(ts[i], 0.0, 1.0);
    const double t1 = std::clamp(ts[i + 1], 0.0, 1.0);
    const Eigen::Vector3d mid_W_m = a_W_m + 0.5 * (t0 + t1) * (b_W_m - a_W_m);
    if ((t1 - t0) * d.norm() > 1e-7) {
      const CellIndex cell = grid.cellIndex(mid_W_m);
      if (!grid.cellInWindow(cell)) continue;
      cells.must.push_back(cell);
      cells.must_t_enter.push_back(t0);
      cells.may.push_back(cell);
      continue;
    }
    // A point: every cell whose closed box contains it.
    const Eigen::Vector3d s = mid_W_m * scale;
    CellIndex lo;
    CellIndex hi;
    for (int axis = 0; axis < 3; ++axis) {
      const double nearest = std::round(s[axis]);
      const bool on_plane = std::abs(s[axis] - nearest) < 1e-7;
      hi[axis] = on_plane ? static_cast<int>(nearest) : static_cast<int>(std::floor(s[axis]));
      lo[axis] = on_plane ? hi[axis] - 1 : hi[axis];
    }
    for (int z = lo.z(); z <= hi.z(); ++z) {
      for (int y = lo.y(); y <= hi.y(); ++y) {
        for (int x = lo.x(); x <= hi.x(); ++x) {
          if (grid.cellInWindow(CellIndex(x, y, z))) cells.may.emplace_back(x, y, z);
        }
      }
    }
  }
  return cells;
}

}  // namespace aerotrack::mapping::test
