// Unit tests of LocalGrid's parameters, cell indexing, inflation, point queries, the unknown policy,
// copyFrom and the allocation-free promise of queries and applyChanges. Expectations are hand-computed
// (0.1 m cells, 0.25 m radius: the 81 offsets with dx^2 + dy^2 + dz^2 <= 6) or brute force.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <random>

#include "aerotrack/mapping/local_grid.hpp"
#include "grid_test_util.hpp"

// Counts heap allocations so that tests can check the "no allocation" promises (test binary only).
namespace {
std::atomic<long> g_allocations{0};
}  // namespace

// GCC cannot see that these replacements pair malloc with free (a false -Wmismatched-new-delete).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
#pragma GCC diagnostic pop

namespace aerotrack::mapping {
namespace {

using test::makeGrid;
using test::makeTree;
using test::setCell;

LocalGridParams smallParams() {
  LocalGridParams params;
  params.size_m = Eigen::Vector3d(3.0, 3.0, 2.0);
  return params;
}

TEST(LocalGridParams, GivenDefaultsWhenCreatedThenWindowIs200By200By50CellsWithA2CellMargin) {
  const LocalGrid grid = makeGrid(LocalGridParams{});
  EXPECT_EQ(grid.windowSizeCells(), CellIndex(200, 200, 50));
  EXPECT_EQ(grid.marginCells(), 2);   // floor(0.25 / 0.1)
  EXPECT_EQ(grid.stencilSize(), 81);  // integer offsets with |d|^2 <= 6.25
  EXPECT_EQ(grid.storageBytes(), std::size_t{204} * 204 * 54 * 2);
  EXPECT_EQ(grid.windowMinCell(), CellIndex(-100, -100, -25));
  EXPECT_TRUE(grid.windowCenterM().isZero(1e-12));
}

TEST(LocalGridParams, GivenInvalidValuesWhenCreatedThenEachIsRejectedWithItsField) {
  const auto rejected = [](LocalGridParams params, const std::string& field) {
    auto grid = LocalGrid::create(params);
    ASSERT_FALSE(grid.has_value()) << field;
    EXPECT_NE(grid.error().message.find(field), std::string::npos) << grid.error().message;
  };
  LocalGridParams p;
  p.resolution_m = 0.0;
  rejected(p, "resolution_m");
  p = {};
  p.resolution_m = std::nan("");
  rejected(p, "resolution_m");
  p = {};
  p.size_m.x() = 20.05;  // not a whole number of 0.1 m cells
  rejected(p, "size_m[0]");
  p = {};
  p.size_m.z() = -1.0;
  rejected(p, "size_m[2]");
  p = {};
  p.inflation_radius_m = -0.1;
  rejected(p, "inflation_radius_m");
  p = {};
  p.recenter_distance_m = std::nan("");
  rejected(p, "recenter_distance_m");
  p = {};
  p.size_m = Eigen::Vector3d(1000.0, 1000.0, 100.0);  // 10^10 cells
  rejected(p, "size_m");
}

TEST(LocalGridIndexing, GivenRandomPointsWhenIndexedThenCellMatchesOctomapKeyAndCentreRoundTrips) {
  const LocalGrid grid = makeGrid(LocalGridParams{});
  const octomap::OcTree tree = makeTree();
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> coord(-50.0, 50.0);
  for (int i = 0; i < 10000; ++i) {
    const Eigen::Vector3d p(coord(rng), coord(rng), coord(rng));
    const CellIndex cell = grid.cellIndex(p);
    const octomap::OcTreeKey key = tree.coordToKey(
        octomap::point3d(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())));
    // OctoMap converts through float; away from cell boundaries (1e-4 m) both agree.
    const Eigen::Vector3d frac = p * 10.0 - (p * 10.0).array().floor().matrix();
    if ((frac.array() > 1e-3).all() && (frac.array() < 1.0 - 1e-3).all()) {
      EXPECT_EQ(cell, CellIndex(key[0] - 32768, key[1] - 32768, key[2] - 32768)) << p.transpose();
    }
    const Eigen::Vector3d center = grid.cellCenterM(cell);
    EXPECT_LE((center - p).cwiseAbs().maxCoeff(), 0.05 + 1e-12);  // within half a cell
    EXPECT_EQ(grid.cellIndex(center), cell);
  }
  // Hand-computed: floor(p / 0.1).
  EXPECT_EQ(grid.cellIndex(Eigen::Vector3d(0.05, -0.05, 1.23)), CellIndex(0, -1, 12));
  EXPECT_TRUE(grid.cellCenterM(CellIndex(0, -1, 12)).isApprox(Eigen::Vector3d(0.05, -0.05, 1.25), 1e-12));
}

TEST(LocalGridInflation, GivenOneOccupiedVoxelWhenAppliedThenExactlyCellsWithinRadiusAreInflated) {
  auto tree = makeTree();
  LocalGrid grid = makeGrid(smallParams());
  const CellIndex voxel(3, -2, 4);
  setCell(tree, voxel, true);
  ASSERT_TRUE(grid.applyChanges(tree).has_value());
  tree.resetChangeDetection();

  // Hand-computed distances between centres (0.1 m cells, radius 0.25 m).
  EXPECT_EQ(grid.inflationCount(voxel), 1);
  EXPECT_EQ(grid.inflationCount(voxel + CellIndex(2, 0, 0)), 1);   // 0.200 m
  EXPECT_EQ(grid.inflationCount(voxel + CellIndex(2, 1, 0)), 1);   // 0.224 m
  EXPECT_EQ(grid.inflationCount(voxel + CellIndex(-2, 1, 1)), 1);  // 0.245 m
  EXPECT_EQ(grid.inflationCount(voxel + CellIndex(2, 2, 0)), 0);   // 0.283 m
  EXPECT_EQ(grid.inflationCount(voxel + CellIndex(0, 0, 3)), 0);   // 0.300 m
  EXPECT_EQ(grid.cellState(voxel), CellState::kOccupied);
  EXPECT_EQ(grid.cellState(voxel + CellIndex(1, 0, 0)), CellState::kUnknown);

  // Brute force over the whole window: count = 1 exactly where the centre distance is <= 0.25 m.
  int inflated = 0;
  const CellBox box = grid.windowBox();
  for (int z = box.lo.z(); z < box.hi.z(); ++z) {
    for (int y = box.lo.y(); y < box.hi.y(); ++y) {
      for (int x = box.lo.x(); x < box.hi.x(); ++x) {
        const CellIndex cell(x, y, z);
        const double distance_m = (grid.cellCenterM(cell) - grid.cellCenterM(voxel)).norm();
        const int expected = distance_m <= 0.25 + 1e-9 ? 1 : 0;
        ASSERT_EQ(grid.inflationCount(cell), expected) << cell.transpose();
        inflated += expected;
        EXPECT_EQ(grid.isOccupied(grid.cellCenterM(cell)), expected == 1);
      }
    }
  }
  EXPECT_EQ(inflated, 81);

  // Removing it (the voxel becomes free) restores zero counts everywhere.
  setCell(tree, voxel, false);
  ASSERT_TRUE(grid.applyChanges(tree).has_value());
  for (int z = box.lo.z(); z < box.hi.z(); ++z) {
    for (int y = box.lo.y(); y < box.hi.y(); ++y) {
      for (int x = box.lo.x(); x < box.hi.x(); ++x) ASSERT_EQ(grid.inflationCount(CellIndex(x, y, z)), 0);
    }
  }
  EXPECT_EQ(grid.cellState(voxel), CellState::kFree);
  EXPECT_TRUE(grid.isFree(grid.cellCenterM(voxel)));
}

TEST(LocalGridInflation, GivenVoxelsJustOutsideTheWindowWhenRebuiltThenTheyInflateCellsInside) {
  auto tree = makeTree();
  LocalGrid grid = makeGrid(smallParams());   // x cells [-15, 15)
  setCell(tree, CellIndex(15, 0, 0), true);   // first cell outside, +x side
  setCell(tree, CellIndex(-18, 0, 0), true);  // 3 cells outside: too far to inflate anything inside
  ASSERT_TRUE(grid.rebuild(tree).has_value());
  EXPECT_FALSE(grid.cellInWindow(CellIndex(15, 0, 0)));
  EXPECT_EQ(grid.inflationCount(CellIndex(14, 0, 0)), 1);
  EXPECT_EQ(grid.inflationCount(CellIndex(13, 0, 0)), 1);
  EXPECT_EQ(grid.inflationCount(CellIndex(12, 0, 0)), 0);
  EXPECT_EQ(grid.inflationCount(CellIndex(-15, 0, 0)), 0);
  test::expectMatchesTree(grid, tree, "rebuild");
}

TEST(LocalGridQueries, GivenStatesWhenQueriedThenOccupiedFreeAndStateFollowTheDefinitions) {
  auto tree = makeTree();
  LocalGrid grid = makeGrid(smallParams());
  setCell(tree, CellIndex(0, 0, 0), true);
  for (int x = 3; x <= 8; ++x) setCell(tree, CellIndex(x, 0, 0), false);
  ASSERT_TRUE(grid.applyChanges(tree).has_value());

  const Eigen::Vector3d occupied(0.05, 0.05, 0.05);
  const Eigen::Vector3d inflated_free(0.25, 0.05, 0.05);  // cell 2: never observed, inflated
  const Eigen::Vector3d near_free(0.35, 0.05, 0.05);      // cell 3: free, 0.3 m away: not inflated
  const Eigen::Vector3d unknown(-0.55, 0.05, 0.05);
  EXPECT_TRUE(grid.isOccupied(occupied));
  EXPECT_FALSE(grid.isFree(occupied));
  EXPECT_EQ(grid.state(occupied), CellState::kOccupied);
  EXPECT_TRUE(grid.isOccupied(inflated_free));
  EXPECT_FALSE(grid.isFree(inflated_free));
  EXPECT_EQ(grid.state(inflated_free), CellState::kUnknown);
  EXPECT_FALSE(grid.isOccupied(near_free));
  EXPECT_TRUE(grid.isFree(near_free));
  EXPECT_EQ(grid.state(near_free), CellState::kFree);
  EXPECT_FALSE(grid.isOccupied(unknown));  // unknown is free by default
  EXPECT_FALSE(grid.isFree(unknown));      // but not known free
  EXPECT_TRUE(grid.inWindow(unknown));
  const Eigen::Vector3d outside(1.6, 0.0, 0.0);
  EXPECT_FALSE(grid.inWindow(outside));
  EXPECT_FALSE(grid.isOccupied(outside));
  EXPECT_FALSE(grid.isFree(outside));
  EXPECT_EQ(grid.state(outside), CellState::kUnknown);
  const double nan = std::nan("");
  EXPECT_FALSE(grid.inWindow(Eigen::Vector3d(nan, 0.0, 0.0)));
  // Window bounds are half-open: [-1.5, 1.5) in x.
  EXPECT_TRUE(grid.inWindow(Eigen::Vector3d(-1.5, 0.0, 0.0)));
  EXPECT_FALSE(grid.inWindow(Eigen::Vector3d(1.5, 0.0, 0.0)));
}

TEST(LocalGridQueries, GivenUnknownIsOccupiedWhenQueriedThenUnknownAndOutsideBlockButSightDoesNot) {
  auto tree = makeTree();
  LocalGridParams params = smallParams();
  params.unknown_is_occupied = true;
  LocalGrid grid = makeGrid(params);
  for (int x = -5; x <= 5; ++x) setCell(tree, CellIndex(x, 0, 0), false);  // a free corridor along x
  ASSERT_TRUE(grid.applyChanges(tree).has_value());
  const Eigen::Vector3d free(0.05, 0.05, 0.05);
  const Eigen::Vector3d unknown(0.05, 0.35, 0.05);
  EXPECT_FALSE(grid.isOccupied(free));
  EXPECT_TRUE(grid.isFree(free));
  EXPECT_TRUE(grid.isOccupied(unknown));
  EXPECT_TRUE(grid.isOccupied(Eigen::Vector3d(5.0, 0.0, 0.0)));  // outside the window
  // Along the corridor: free both ways; leaving it into unknown blocks a path but not sight.
  EXPECT_TRUE(grid.segmentFree(Eigen::Vector3d(-0.45, 0.05, 0.05), Eigen::Vector3d(0.55, 0.05, 0.05)));
  EXPECT_FALSE(grid.segmentFree(Eigen::Vector3d(-0.45, 0.05, 0.05), Eigen::Vector3d(0.55, 0.35, 0.05)));
  EXPECT_TRUE(grid.lineOfSight(Eigen::Vector3d(-0.45, 0.05, 0.05), Eigen::Vector3d(0.55, 0.35, 0.05)));
  EXPECT_FALSE(grid.segmentFree(Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3d(3.0, 0.05, 0.05)));
  EXPECT_TRUE(grid.lineOfSight(Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3d(3.0, 0.05, 0.05)));

  // The same grid with the default policy: unknown and outside are free for paths too.
  LocalGrid free_policy = makeGrid(smallParams());
  ASSERT_TRUE(free_policy.rebuild(tree).has_value());
  EXPECT_FALSE(free_policy.isOccupied(unknown));
  EXPECT_FALSE(free_policy.isOccupied(Eigen::Vector3d(5.0, 0.0, 0.0)));
  EXPECT_TRUE(free_policy.segmentFree(Eigen::Vector3d(-0.45, 0.05, 0.05), Eigen::Vector3d(0.55, 0.35, 0.05)));
  EXPECT_TRUE(free_policy.segmentFree(Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3d(3.0, 0.05, 0.05)));
}

TEST(LocalGridSnapshot, GivenAPoolGridWhenCopiedFromTheMapperThenContentsMatchWithoutAllocation) {
  auto tree = makeTree();
  LocalGrid mapper = makeGrid(LocalGridParams{});
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> xy(-100, 99);
  std::uniform_int_distribution<int> z(-25, 24);
  for (int i = 0; i < 2000; ++i) setCell(tree, CellIndex(xy(rng), xy(rng), z(rng)), i % 3 != 0);
  ASSERT_TRUE(mapper.applyChanges(tree).has_value());
  tree.resetChangeDetection();
  ASSERT_TRUE(mapper.recenter(Eigen::Vector3d(3.0, -2.5, 0.4), tree).value());

  LocalGrid snapshot = makeGrid(LocalGridParams{});  // same size: storage is reused
  const long before = g_allocations.load();
  snapshot.copyFrom(mapper);
  const long allocations = g_allocations.load() - before;
  EXPECT_EQ(allocations, 0);
  test::expectSameGrid(snapshot, mapper, "copyFrom");
  EXPECT_EQ(snapshot.windowCenterM(), mapper.windowCenterM());

  // A different size is copied too (reallocating).
  LocalGridParams small = smallParams();
  LocalGrid other = makeGrid(small);
  other.copyFrom(mapper);
  test::expectSameGrid(other, mapper, "copyFrom other size");
}

TEST(LocalGridSnapshot, GivenThreePoolGridsCopiedInTurnWhileTheGridChangesThenEachIncrementalCopyEqualsIt) {
  // The mapper's pattern: one grid changes frame after frame (flips, window moves, a refill) and
  // three published grids take turns to catch up with it, each lagging by a few frames.
  auto tree = makeTree();
  LocalGridParams params = smallParams();
  params.size_m = Eigen::Vector3d(3.0, 2.4, 1.2);
  params.recenter_distance_m = 0.2;
  LocalGrid grid = makeGrid(params);
  ASSERT_TRUE(grid.rebuild(tree).has_value());
  std::vector<LocalGrid> pool(3, grid);
  LocalGrid stranger = makeGrid(params);  // another source: its copies must not be taken as increments
  std::mt19937 rng(21);
  std::uniform_int_distribution<int> xy(-25, 24);
  std::uniform_int_distribution<int> z(-8, 7);
  Eigen::Vector3d centre_W_m = Eigen::Vector3d::Zero();
  for (int frame = 0; frame < 60; ++frame) {
    for (int i = 0; i < 40; ++i) {
      const CellIndex cell(xy(rng), xy(rng), z(rng));
      const bool occupied = (rng() % 3) != 0;
      setCell(tree, cell, occupied);
      grid.setVoxel(test::keyOf(cell), occupied ? CellState::kOccupied : CellState::kFree);
    }
    centre_W_m += Eigen::Vector3d(0.07, -0.05, 0.01 * std::sin(frame));
    ASSERT_TRUE(grid.recenter(centre_W_m, tree).has_value());
    if (frame == 33) {
      ASSERT_TRUE(grid.rebuild(tree).has_value());  // a whole refill
    }
    LocalGrid& snapshot = pool[static_cast<std::size_t>(frame) % pool.size()];
    if (frame == 45) snapshot.copyFrom(stranger);  // last copied from elsewhere: must copy whole
    const long before = g_allocations.load();
    snapshot.copyChangesFrom(grid);
    EXPECT_EQ(g_allocations.load() - before, 0);
    test::expectSameGrid(snapshot, grid, "frame " + std::to_string(frame));
    test::expectSameGrid(grid, test::rebuiltAt(grid, tree), "grid itself, frame " + std::to_string(frame));
  }
}

TEST(LocalGridAllocation, GivenASyncedGridWhenQueriedAndChangesAppliedThenNothingIsAllocated) {
  auto tree = makeTree();
  LocalGrid grid = makeGrid(LocalGridParams{});
  ASSERT_TRUE(grid.rebuild(tree).has_value());
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> xy(-100, 99);
  for (int i = 0; i < 500; ++i) setCell(tree, CellIndex(xy(rng), xy(rng), 5), true);
  const long before = g_allocations.load();
  const bool applied = grid.applyChanges(tree).has_value();
  int sum = 0;
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector3d a(0.01 * i - 5.0, -3.0, 0.55);
    const Eigen::Vector3d b(5.0, 0.01 * i - 4.0, 0.55);
    sum += grid.isOccupied(a) + grid.isFree(b) + grid.inWindow(a) + static_cast<int>(grid.state(b));
    sum += grid.lineOfSight(a, b) + grid.segmentFree(a, b) + grid.firstHit(a, b).has_value();
  }
  const long allocations = g_allocations.load() - before;
  EXPECT_TRUE(applied);
  EXPECT_EQ(allocations, 0);
  EXPECT_GT(sum, 0);
}

}  // namespace
}  // namespace aerotrack::mapping
