// Unit tests of LocalGrid's synchronisation with OctoMap: applyChanges after point-cloud insertions and
// random flips equals a full rebuild (and brute force from the tree on a small window); pruned (coarse)
// octree leaves are expanded to cells by every path; the window follows the drone, keeps the cells that
// stay inside without re-reading them, and ends up exactly as a rebuild after random inserts and several
// recentres; resolution mismatches and bad centres are reported as errors.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <random>

#include "aerotrack/mapping/local_grid.hpp"
#include "grid_test_util.hpp"

namespace aerotrack::mapping {
namespace {

using test::makeGrid;
using test::makeTree;
using test::setCell;

// One depth frame: rays from the sensor origin to n random points within range_m (free along the ray,
// occupied at the end), inserted the way the mapper does (which also prunes the tree).
void insertFrame(octomap::OcTree& tree, const Eigen::Vector3d& origin_W_m, int n, double range_m, std::mt19937& rng) {
  std::normal_distribution<double> dir(0.0, 1.0);
  std::uniform_real_distribution<double> dist(0.3, range_m);
  octomap::Pointcloud cloud;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = origin_W_m + dist(rng) * Eigen::Vector3d(dir(rng), dir(rng), 0.3 * dir(rng)).normalized();
    cloud.push_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
  }
  const octomap::point3d origin(static_cast<float>(origin_W_m.x()), static_cast<float>(origin_W_m.y()),
                                static_cast<float>(origin_W_m.z()));
  tree.insertPointCloud(cloud, origin);
}

int minLeafDepth(const octomap::OcTree& tree) {
  int depth = 16;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    depth = std::min(depth, static_cast<int>(it.getDepth()));
  }
  return depth;
}

LocalGridParams smallParams() {
  LocalGridParams params;
  params.size_m = Eigen::Vector3d(2.4, 2.0, 1.2);
  return params;
}

TEST(LocalGridSync, GivenPointCloudFramesWhenChangesAreAppliedThenTheGridEqualsRebuildAndTheTree) {
  auto tree = makeTree();
  LocalGrid grid = makeGrid(smallParams());
  std::mt19937 rng(11);
  for (int frame = 0; frame < 12; ++frame) {
    insertFrame(tree, Eigen::Vector3d(0.3 * (frame % 3), -0.2, 0.1), 150, 1.6, rng);
    ASSERT_GT(tree.numChangesDetected(), 0u);
    ASSERT_TRUE(grid.applyChanges(tree).has_value());
    tree.resetChangeDetection();
    test::expectSameGrid(grid, test::rebuiltAt(grid, tree), "frame " + std::to_string(frame));
  }
  test::expectMatchesTree(grid, tree, "after 12 frames");
}

TEST(LocalGridSync, GivenRandomFlipsWhenChangesAreAppliedThenTheGridEqualsRebuild) {
  auto tree = makeTree();
  LocalGridParams params = smallParams();
  params.inflation_radius_m = 0.35;  // a larger stencil: 179 cells
  LocalGrid grid = makeGrid(params);
  std::mt19937 rng(12);
  std::uniform_int_distribution<int> x(-14, 13);  // the window is [-12, 12): some changes land outside
  std::uniform_int_distribution<int> z(-8, 7);
  std::uniform_int_distribution<int> kind(0, 3);
  for (int round = 0; round < 20; ++round) {
    for (int i = 0; i < 300; ++i) {
      const CellIndex cell(x(rng), x(rng), z(rng));
      switch (kind(rng)) {
        case 0:
          setCell(tree, cell, true);
          break;
        case 1:
          setCell(tree, cell, false);
          break;
        case 2:
          tree.updateNode(test::keyOf(cell), true);  // log-odds steps: may or may not flip
          break;
        default:
          tree.updateNode(test::keyOf(cell), false);
          break;
      }
    }
    ASSERT_TRUE(grid.applyChanges(tree).has_value());
    tree.resetChangeDetection();
    test::expectSameGrid(grid, test::rebuiltAt(grid, tree), "round " + std::to_string(round));
  }
  test::expectMatchesTree(grid, tree, "after 20 rounds");
}

TEST(LocalGridSync, GivenPrunedCoarseLeavesWhenSyncedThenTheyAreExpandedToCellsByEveryPath) {
  auto tree = makeTree();
  LocalGrid changes = makeGrid(smallParams());
  // An aligned 4 x 4 x 4 block (cells 4..7 are keys 32772..32775: one depth-14 node) occupied, and an
  // aligned 8 x 8 x 8 free block (keys 32760..32767: one depth-13 node), each set voxel by voxel.
  for (int z = 4; z < 8; ++z) {
    for (int y = 4; y < 8; ++y) {
      for (int x = 4; x < 8; ++x) setCell(tree, CellIndex(x, y, z), true);
    }
  }
  for (int z = -8; z < 0; ++z) {
    for (int y = -8; y < 0; ++y) {
      for (int x = -8; x < 0; ++x) setCell(tree, CellIndex(x, y, z), false);
    }
  }
  ASSERT_LE(minLeafDepth(tree), 13) << "OctoMap should have pruned the blocks";
  const CellIndex inside_occupied(5, 6, 5);
  ASSERT_TRUE(tree.isNodeOccupied(tree.search(test::keyOf(inside_occupied))));

  // 1. applyChanges: each changed full-depth key is found at its coarse node.
  ASSERT_TRUE(changes.applyChanges(tree).has_value());
  tree.resetChangeDetection();
  EXPECT_EQ(changes.cellState(inside_occupied), CellState::kOccupied);
  EXPECT_EQ(changes.cellState(CellIndex(-3, -5, -4)), CellState::kFree);
  // 2. rebuild: the leaf iterator yields the coarse leaves, expanded to all their cells.
  LocalGrid rebuilt = makeGrid(smallParams());
  ASSERT_TRUE(rebuilt.rebuild(tree).has_value());
  test::expectSameGrid(changes, rebuilt, "applyChanges vs rebuild");
  test::expectMatchesTree(rebuilt, tree, "rebuild with coarse leaves");
  // 3. recenter: a window that arrives over the blocks fills them from the coarse leaves.
  LocalGridParams params = smallParams();
  params.recenter_distance_m = 0.0;
  LocalGrid moved = makeGrid(params);
  ASSERT_TRUE(moved.recenter(Eigen::Vector3d(30.0, 0.0, 0.0), tree).value());
  ASSERT_TRUE(moved.rebuild(tree).has_value());
  ASSERT_TRUE(moved.recenter(Eigen::Vector3d(0.05, 0.05, 0.05), tree).value());
  test::expectSameGrid(moved, rebuilt, "recentred over coarse leaves");
  ASSERT_TRUE(moved.recenter(Eigen::Vector3d(0.75, 0.35, 0.25), tree).value());  // partly overlapping
  test::expectSameGrid(moved, test::rebuiltAt(moved, tree), "partial move over coarse leaves");

  // 4. One voxel inside a coarse free node becomes occupied: OctoMap expands the node, the grid
  // updates just that voxel; then the last free voxel of an occupied 2 x 2 x 2 group gets pruned.
  setCell(tree, CellIndex(-4, -4, -4), true);
  for (int i = 0; i < 7; ++i) setCell(tree, CellIndex(-8 + (i & 1), -6 + ((i >> 1) & 1), -2 + (i >> 2)), true);
  ASSERT_TRUE(changes.applyChanges(tree).has_value());
  tree.resetChangeDetection();
  setCell(tree, CellIndex(-7, -5, -1), true);  // the 8th: the group prunes into one depth-15 node
  ASSERT_FALSE(tree.nodeHasChildren(tree.search(test::keyOf(CellIndex(-7, -5, -1)))));
  ASSERT_TRUE(changes.applyChanges(tree).has_value());
  tree.resetChangeDetection();
  EXPECT_EQ(changes.cellState(CellIndex(-4, -4, -4)), CellState::kOccupied);
  EXPECT_EQ(changes.cellState(CellIndex(-7, -5, -1)), CellState::kOccupied);
  test::expectMatchesTree(changes, tree, "after expanding and re-pruning");
}

TEST(LocalGridRecenter, GivenAThresholdWhenTheDroneMovesThenTheWindowMovesOnlyBeyondItSnappedToCells) {
  auto tree = makeTree();
  LocalGrid grid = makeGrid(LocalGridParams{});  // 2 m threshold
  auto moved = grid.recenter(Eigen::Vector3d(1.9, 0.0, 0.0), tree);
  ASSERT_TRUE(moved.has_value());
  EXPECT_FALSE(*moved);
  EXPECT_TRUE(grid.windowCenterM().isZero(1e-12));
  moved = grid.recenter(Eigen::Vector3d(1.5, 1.5, 0.3), tree);  // 2.14 m away
  ASSERT_TRUE(moved.has_value());
  EXPECT_TRUE(*moved);
  // Snapped: window min = floor(c / 0.1) - 100 = (-85, -85, -22) in cells (even sizes: the centre is
  // the corner of the cell holding c).
  EXPECT_EQ(grid.windowMinCell(), CellIndex(-85, -85, -22));
  EXPECT_TRUE(grid.windowCenterM().isApprox(Eigen::Vector3d(1.5, 1.5, 0.3), 1e-9));
  EXPECT_TRUE(grid.windowMinM().isApprox(Eigen::Vector3d(-8.5, -8.5, -2.2), 1e-9));
  EXPECT_TRUE(grid.windowMaxM().isApprox(Eigen::Vector3d(11.5, 11.5, 2.8), 1e-9));
}

TEST(LocalGridRecenter, GivenStaleKeptCellsWhenTheWindowMovesThenTheyAreKeptAndOnlyNewCellsAreRead) {
  auto tree = makeTree();
  LocalGridParams params = smallParams();  // x cells [-12, 12)
  params.recenter_distance_m = 0.0;
  LocalGrid grid = makeGrid(params);
  setCell(tree, CellIndex(0, 0, 0), true);
  setCell(tree, CellIndex(14, 0, 0), true);  // outside for now
  ASSERT_TRUE(grid.applyChanges(tree).has_value());
  tree.resetChangeDetection();
  // The tree changes but the grid is not told (changes reset): the grid's copy of cell 0 is stale.
  setCell(tree, CellIndex(0, 0, 0), false);
  tree.resetChangeDetection();
  ASSERT_TRUE(grid.recenter(Eigen::Vector3d(0.55, 0.05, 0.05), tree).value());  // x cells [-7, 17)
  EXPECT_EQ(grid.cellState(CellIndex(0, 0, 0)), CellState::kOccupied) << "kept cells are not re-read";
  EXPECT_EQ(grid.cellState(CellIndex(14, 0, 0)), CellState::kOccupied) << "new cells are read";
  EXPECT_EQ(grid.inflationCount(CellIndex(1, 0, 0)), 1);
  EXPECT_EQ(grid.inflationCount(CellIndex(12, 0, 0)), 1);
}

TEST(LocalGridRecenter, GivenRandomInsertsAndSeveralRecentresThenTheGridEqualsAFullRebuild) {
  auto tree = makeTree();
  LocalGridParams params;
  params.size_m = Eigen::Vector3d(6.0, 5.0, 2.5);
  params.recenter_distance_m = 0.7;
  LocalGrid grid = makeGrid(params);
  ASSERT_TRUE(grid.rebuild(tree).has_value());
  std::mt19937 rng(21);
  // A flight: along x, diagonally, down, back, a jump farther than the window, then back to old ground.
  const std::vector<Eigen::Vector3d> path = {{0.0, 0.0, 0.0},   {0.8, 0.0, 0.0},  {1.7, 0.6, 0.2}, {2.5, 1.5, -0.4},
                                             {2.0, 2.4, -1.1},  {1.1, 2.0, -0.2}, {0.2, 1.1, 0.5}, {-0.9, 0.3, 0.9},
                                             {-1.8, -0.9, 0.4}, {9.0, 9.0, 0.0},  {8.3, 8.6, 0.3}, {0.4, -0.3, 0.0},
                                             {1.0, -1.0, 0.2}};
  int moves = 0;
  for (std::size_t step = 0; step < path.size(); ++step) {
    insertFrame(tree, path[step], 400, 3.5, rng);
    ASSERT_TRUE(grid.applyChanges(tree).has_value());
    tree.resetChangeDetection();
    auto moved = grid.recenter(path[step], tree);
    ASSERT_TRUE(moved.has_value()) << moved.error().message;
    moves += *moved ? 1 : 0;
    test::expectSameGrid(grid, test::rebuiltAt(grid, tree), "step " + std::to_string(step));
  }
  EXPECT_GE(moves, 8);
}

TEST(LocalGridRecenter, GivenTheDefaultGridWhenItFollowsAFlightThenItEqualsAFullRebuild) {
  auto tree = makeTree();
  LocalGrid grid = makeGrid(LocalGridParams{});
  std::mt19937 rng(22);
  Eigen::Vector3d drone(0.0, 0.0, 1.0);
  for (int step = 0; step < 6; ++step) {
    for (int frame = 0; frame < 2; ++frame) insertFrame(tree, drone, 1000, 6.0, rng);
    ASSERT_TRUE(grid.applyChanges(tree).has_value());
    tree.resetChangeDetection();
    ASSERT_TRUE(grid.recenter(drone, tree).has_value());
    drone += Eigen::Vector3d(1.3, -0.9, step % 2 == 0 ? 0.6 : -0.6);
  }
  test::expectSameGrid(grid, test::rebuiltAt(grid, tree), "default grid after a flight");
}

TEST(LocalGridErrors, GivenBadInputsWhenSyncingThenErrorsAreReturnedAndTheGridIsUntouched) {
  auto coarse_tree = makeTree(0.2);
  setCell(coarse_tree, CellIndex(0, 0, 0), true);
  auto tree = makeTree();
  setCell(tree, CellIndex(0, 0, 0), true);
  LocalGrid grid = makeGrid(smallParams());
  ASSERT_TRUE(grid.applyChanges(tree).has_value());

  const auto applied = grid.applyChanges(coarse_tree);
  ASSERT_FALSE(applied.has_value());
  EXPECT_NE(applied.error().message.find("resolution 0.2 m differs from the grid's 0.1 m"), std::string::npos)
      << applied.error().message;
  EXPECT_FALSE(grid.rebuild(coarse_tree).has_value());
  EXPECT_FALSE(grid.recenter(Eigen::Vector3d(5.0, 0.0, 0.0), coarse_tree).has_value());
  EXPECT_FALSE(grid.recenter(Eigen::Vector3d(std::nan(""), 0.0, 0.0), tree).has_value());
  EXPECT_FALSE(grid.recenter(Eigen::Vector3d(1e5, 0.0, 0.0), tree).has_value());
  EXPECT_FALSE(grid.recenter(Eigen::Vector3d(3276.75, 0.0, 0.0), tree).has_value());  // window past the keys
  EXPECT_TRUE(grid.windowCenterM().isZero(1e-12));
  EXPECT_EQ(grid.cellState(CellIndex(0, 0, 0)), CellState::kOccupied);
  EXPECT_EQ(grid.inflationCount(CellIndex(1, 1, 1)), 1);
}

}  // namespace
}  // namespace aerotrack::mapping
