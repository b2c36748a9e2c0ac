// Tests of the flight corridor (corridor.hpp, paper Sect. V-C). Every built corridor is checked against the
// guarantees with slow, obvious references: every cell of every box is unblocked (all cells visited), every
// polyline point and every point sampled densely along the chords lies in the boxes (chord samples within
// corner_tolerance_m) in order (a sample may stay in the box of the previous one or move on to the next, and
// the path ends in the last box), the polyline points between two waypoint indices lie in their box,
// consecutive boxes share whole cells and hold their waypoint at least half a cell from the faces of the
// intersection, and no edge exceeds the cap. Cases: free space, an L round a block, a slalom between pillars,
// a path that doubles back, chords through and 1 mm into a blocked corner, many seeded random obstacle fields
// with paths from the kinodynamic search, scattered single voxels under several inflation radii (the sparse
// layer check and its dense fallback), unknown cells that block, the failure values, the parameters and the
// allocation claim. malloc is interposed in this test binary (Eigen and std::vector allocate through it) and
// counts calls while a flag is set; under AddressSanitizer or ThreadSanitizer (which own malloc) the
// allocation test is skipped.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "aerotrack/planning/corridor.hpp"
#include "aerotrack/planning/kinodynamic_search.hpp"
#include "search_test_util.hpp"
#include "support/require.hpp"

#include "../malloc_counter.hpp"

namespace aerotrack::planning {
namespace {

using test::makeBoxGrid;
using test::OccupiedBox;

constexpr double kResolutionM = 0.1;
constexpr double kBoundaryM = 1e-9;  // points exactly on a face may test outside by one rounding step
using Path = std::vector<Eigen::Vector3d>;

CorridorBuilder makeBuilder(const CorridorParams& params = CorridorParams{}) {
  return aerotrack::test::require(CorridorBuilder::create(params), "CorridorBuilder::create");
}

/// A polyline through `corners`, with points every step_m along each leg.
std::vector<Eigen::Vector3d> polyline(const std::vector<Eigen::Vector3d>& corners, double step_m = 0.05) {
  std::vector<Eigen::Vector3d> path{corners.front()};
  for (std::size_t i = 1; i < corners.size(); ++i) {
    const Eigen::Vector3d d = corners[i] - corners[i - 1];
    const int n = std::max(1, static_cast<int>(std::ceil(d.norm() / step_m)));
    for (int k = 1; k <= n; ++k) path.push_back(corners[i - 1] + d * (static_cast<double>(k) / n));
  }
  return path;
}

bool pathFree(const mapping::LocalGrid& grid, const std::vector<Eigen::Vector3d>& path) {
  for (std::size_t k = 0; k < path.size(); ++k) {
    if (!grid.inWindow(path[k]) || grid.isOccupied(path[k])) return false;
    if (k > 0 && !grid.segmentFree(path[k - 1], path[k])) return false;
  }
  return true;
}

bool cellBlocked(const mapping::LocalGrid& grid, const mapping::CellIndex& cell) {
  return !grid.cellInWindow(cell) || grid.isOccupied(grid.cellCenterM(cell));
}

/// Checks every guarantee of `corridor` for `path` in `grid` (see the file comment).
void expectValidCorridor(const mapping::LocalGrid& grid, const std::vector<Eigen::Vector3d>& path,
                         const Corridor& corridor, const CorridorParams& params, const std::string& what) {
  const std::size_t m = corridor.boxes.size();
  ASSERT_GE(m, 1u) << what;
  ASSERT_EQ(corridor.waypoints_W_m.size(), m - 1) << what;
  ASSERT_EQ(corridor.waypoint_path_index.size(), m - 1) << what;
  const Eigen::Vector3i cap_cells = (params.max_box_size_m / kResolutionM).array().floor().cast<int>();

  // Boxes: consistent bounds, within the cap, every cell unblocked.
  for (std::size_t i = 0; i < m; ++i) {
    const CorridorBox& box = corridor.boxes[i];
    ASSERT_FALSE(box.cells.empty()) << what << ": box " << i;
    EXPECT_TRUE(box.lo_W_m.isApprox(box.cells.lo.cast<double>() * kResolutionM)) << what << ": box " << i;
    EXPECT_TRUE(box.hi_W_m.isApprox(box.cells.hi.cast<double>() * kResolutionM)) << what << ": box " << i;
    EXPECT_TRUE(((box.cells.hi - box.cells.lo).array() <= cap_cells.array()).all())
        << what << ": box " << i << " extent " << (box.cells.hi - box.cells.lo).transpose();
    int blocked = 0;
    for (int z = box.cells.lo.z(); z < box.cells.hi.z(); ++z) {
      for (int y = box.cells.lo.y(); y < box.cells.hi.y(); ++y) {
        for (int x = box.cells.lo.x(); x < box.cells.hi.x(); ++x) blocked += cellBlocked(grid, {x, y, z}) ? 1 : 0;
      }
    }
    EXPECT_EQ(blocked, 0) << what << ": box " << i << " has blocked cells";
  }

  // Overlaps: whole cells shared; the waypoint half a cell inside the intersection.
  for (std::size_t i = 0; i + 1 < m; ++i) {
    const mapping::CellBox overlap{corridor.boxes[i].cells.lo.cwiseMax(corridor.boxes[i + 1].cells.lo),
                                   corridor.boxes[i].cells.hi.cwiseMin(corridor.boxes[i + 1].cells.hi)};
    EXPECT_FALSE(overlap.empty()) << what << ": boxes " << i << " and " << i + 1 << " do not share a cell";
    const Eigen::Vector3d& q = corridor.waypoints_W_m[i];
    EXPECT_TRUE(corridor.boxes[i].contains(q, 0.5 * kResolutionM - kBoundaryM)) << what << ": waypoint " << i;
    EXPECT_TRUE(corridor.boxes[i + 1].contains(q, 0.5 * kResolutionM - kBoundaryM)) << what << ": waypoint " << i;
    const int k = corridor.waypoint_path_index[i];
    ASSERT_GE(k, 0) << what;
    ASSERT_LT(static_cast<std::size_t>(k), path.size()) << what;
    if (i > 0) {
      EXPECT_GE(k, corridor.waypoint_path_index[i - 1]) << what << ": waypoint indices decrease";
    }
    // The waypoint is the centre of a cell that the chord from point k (to k + 1) passes through: some point
    // of the chord (sampled every 0.5 mm) is within half a cell of it on every axis.
    const Eigen::Vector3d& a = path[static_cast<std::size_t>(k)];
    const Eigen::Vector3d& b = path[std::min(path.size() - 1, static_cast<std::size_t>(k) + 1)];
    const int samples = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 0.0005)));
    double nearest_m = std::numeric_limits<double>::infinity();
    for (int s = 0; s <= samples; ++s) {
      const Eigen::Vector3d p = a + (b - a) * (static_cast<double>(s) / samples);
      nearest_m = std::min(nearest_m, (p - q).cwiseAbs().maxCoeff());
    }
    EXPECT_LE(nearest_m, 0.5 * kResolutionM + params.corner_tolerance_m + 0.0005)
        << what << ": waypoint " << i << " is off the chord from " << k;
  }

  // Polyline points between waypoint indices lie in their box; start and end in the first and last box.
  EXPECT_TRUE(corridor.boxes.front().contains(path.front(), -kBoundaryM)) << what;
  EXPECT_TRUE(corridor.boxes.back().contains(path.back(), -kBoundaryM)) << what;
  std::size_t box = 0;
  for (std::size_t k = 0; k < path.size(); ++k) {
    while (box + 1 < m && static_cast<int>(k) > corridor.waypoint_path_index[box]) ++box;
    EXPECT_TRUE(corridor.boxes[box].contains(path[k], -kBoundaryM)) << what << ": point " << k << " not in box " << box;
  }

  // Dense samples (every 5 mm) of every chord, in order: the boxes each sample may be assigned to, where a
  // sample may stay in the box of the previous one or move on to the next box, start with box 0 and must
  // end with the last box (an automaton over the box indices).
  const double chord_margin_m = -(params.corner_tolerance_m + kBoundaryM);  // chords may cut corners this much
  std::vector<char> feasible(m, 0);
  std::vector<char> next(m, 0);
  feasible.at(0) = corridor.boxes.front().contains(path.front(), -kBoundaryM) ? 1 : 0;
  int stuck = 0;
  for (std::size_t k = 1; k < path.size() && stuck == 0; ++k) {
    const Eigen::Vector3d& a = path[k - 1];
    const int n = std::max(1, static_cast<int>(std::ceil((path[k] - a).norm() / 0.005)));
    for (int s = 1; s <= n; ++s) {
      const Eigen::Vector3d p = a + (path[k] - a) * (static_cast<double>(s) / n);
      bool any = false;
      for (std::size_t b = 0; b < m; ++b) {
        next[b] =
            ((feasible[b] != 0 || (b > 0 && feasible[b - 1] != 0)) && corridor.boxes[b].contains(p, chord_margin_m))
                ? 1
                : 0;
        any = any || next[b] != 0;
      }
      feasible.swap(next);
      if (!any) {
        ++stuck;
        ADD_FAILURE() << what << ": sample " << p.transpose() << " of chord " << k
                      << " cannot be reached through the boxes in order";
        break;
      }
    }
  }
  EXPECT_EQ(stuck, 0) << what;
  EXPECT_NE(feasible[m - 1], 0) << what << ": the path does not end in the last box in order";
}

TEST(Corridor, GivenAStraightPathInFreeSpaceThenOneBoxGrownToTheCapHoldsIt) {
  const mapping::LocalGrid grid = makeBoxGrid(Eigen::Vector3d(10.0, 8.0, 4.0), Eigen::Vector3d(2.0, 0.0, 2.0), {});
  const std::vector<Eigen::Vector3d> path = polyline({{0.03, 0.02, 1.51}, {2.47, 0.02, 1.51}});
  CorridorBuilder builder = makeBuilder();
  Corridor corridor;
  ASSERT_TRUE(builder.build(grid, path, corridor).has_value());
  expectValidCorridor(grid, path, corridor, builder.params(), "straight");
  ASSERT_EQ(corridor.boxes.size(), 1u);
  EXPECT_EQ(corridor.boxes[0].cells.hi - corridor.boxes[0].cells.lo, Eigen::Vector3i(30, 30, 20))
      << "free space: every edge grows to its cap";

  // Longer than the cap: a few boxes, each as long as the cap allows along the path.
  const std::vector<Eigen::Vector3d> long_path = polyline({{-2.5, 0.0, 1.5}, {6.5, 0.3, 1.7}});
  ASSERT_TRUE(builder.build(grid, long_path, corridor).has_value());
  expectValidCorridor(grid, long_path, corridor, builder.params(), "long straight");
  EXPECT_GE(corridor.boxes.size(), 4u);  // 9 m with 3 m boxes that overlap
  EXPECT_LE(corridor.boxes.size(), 5u);
}

// Issue 21: the search's altitude band holds the boxes too (else the optimiser could take the path back under
// a crosser's torso); a path partly below the band keeps its own cells.
TEST(Corridor, GivenAnAltitudeBandThenBoxesGrowOnlyAcrossItsCellsAndThePathsOwn) {
  const mapping::LocalGrid grid = makeBoxGrid(Eigen::Vector3d(10.0, 8.0, 4.0), Eigen::Vector3d(2.0, 0.0, 2.0), {});
  const std::vector<Eigen::Vector3d> path = polyline({{0.03, 0.02, 1.51}, {2.47, 0.02, 1.51}});
  CorridorBuilder builder = makeBuilder();
  builder.setAltitudeBand(1.0, 2.0);
  Corridor corridor;
  ASSERT_TRUE(builder.build(grid, path, corridor).has_value());
  expectValidCorridor(grid, path, corridor, builder.params(), "banded");
  ASSERT_EQ(corridor.boxes.size(), 1u);
  EXPECT_EQ(corridor.boxes[0].cells.lo.z(), 10) << "the cell holding 1.0 m";
  EXPECT_EQ(corridor.boxes[0].cells.hi.z(), 21) << "one past the cell holding 2.0 m";

  const std::vector<Eigen::Vector3d> low = polyline({{0.03, 0.02, 0.75}, {2.47, 0.02, 1.51}});
  ASSERT_TRUE(builder.build(grid, low, corridor).has_value());
  expectValidCorridor(grid, low, corridor, builder.params(), "from below the band");
  for (const CorridorBox& box : corridor.boxes) {
    EXPECT_GE(box.cells.lo.z(), 7) << "never below the path's lowest cell";
    EXPECT_LE(box.cells.hi.z(), 21);
  }
}

TEST(Corridor, GivenASinglePointThenOneBoxAndNoWaypoints) {
  const mapping::LocalGrid grid = makeBoxGrid(Eigen::Vector3d(6.0, 6.0, 3.0), Eigen::Vector3d(0.0, 0.0, 1.5), {});
  const std::vector<Eigen::Vector3d> path{{0.5, 0.5, 1.0}};
  CorridorBuilder builder = makeBuilder();
  Corridor corridor;
  ASSERT_TRUE(builder.build(grid, path, corridor).has_value());
  expectValidCorridor(grid, path, corridor, builder.params(), "point");
  EXPECT_EQ(corridor.boxes.size(), 1u);
  EXPECT_TRUE(corridor.waypoints_W_m.empty());
}

TEST(Corridor, GivenAPathThatDoublesBackInsideOneCapThenTheRedundantBoxesArePruned) {
  const mapping::LocalGrid grid = makeBoxGrid(Eigen::Vector3d(8.0, 8.0, 3.0), Eigen::Vector3d(0.0, 0.0, 1.5), {});
  const std::vector<Eigen::Vector3d> path =
      polyline({{0.0, 0.0, 1.5}, {1.5, 0.2, 1.5}, {0.2, 0.4, 1.6}, {1.6, 1.2, 1.4}, {0.1, 1.0, 1.5}});
  CorridorBuilder builder = makeBuilder();
  Corridor corridor;
  ASSERT_TRUE(builder.build(grid, path, corridor).has_value());
  expectValidCorridor(grid, path, corridor, builder.params(), "doubling back");
  EXPECT_EQ(corridor.boxes.size(), 1u) << "the whole path fits in one capped box";
}

TEST(Corridor, GivenAnLShapedPathAroundABlockThenTheBoxesTurnTheCornerWithoutTouchingTheBlock) {
  // Block x in [1, 3], y in [-3, 1], the whole height; the path runs up its left side, then right along its
  // top (0.5 m clear of the block: 0.25 m beyond the inflation).
  const mapping::LocalGrid grid = makeBoxGrid(Eigen::Vector3d(10.0, 10.0, 3.0), Eigen::Vector3d(1.5, 0.0, 1.5),
                                              {{Eigen::Vector3d(1.0, -3.0, -1.0), Eigen::Vector3d(3.0, 1.0, 4.0)}});
  const std::vector<Eigen::Vector3d> path = polyline({{0.5, -2.5, 1.5}, {0.5, 1.5, 1.5}, {4.0, 1.5, 1.5}});
  ASSERT_TRUE(pathFree(grid, path));
  CorridorBuilder builder = makeBuilder();
  Corridor corridor;
  ASSERT_TRUE(builder.build(grid, path, corridor).has_value());
  expectValidCorridor(grid, path, corridor, builder.params(), "L");
  EXPECT_GE(corridor.boxes.size(), 2u);
  EXPECT_LE(corridor.boxes.size(), 4u);
  for (const CorridorBox& box : corridor.boxes) {
    const bool overlaps_block =
        box.lo_W_m.x() < 3.0 && box.hi_W_m.x() > 1.0 && box.lo_W_m.y() < 1.0 && box.hi_W_m.y() > -3.0;
    EXPECT_FALSE(overlaps_block) << box.lo_W_m.transpose() << " .. " << box.hi_W_m.transpose();
  }
}

TEST(Corridor, GivenASlalomBetweenPillarsThenEveryTurnGetsItsOwnBox) {
  // Pillars (0.3 m square, the whole height) at x = 1 .. 6, alternately at y = +0.5 and -0.5; the path
  // y = -0.5 cos(pi x) passes each on the far side.
  std::vector<OccupiedBox> pillars;
  for (int k = 1; k <= 6; ++k) {
    const Eigen::Vector3d c(k, (k % 2 == 0 ? 0.5 : -0.5), 0.0);
    pillars.push_back({c + Eigen::Vector3d(-0.15, -0.15, -1.0), c + Eigen::Vector3d(0.15, 0.15, 4.0)});
  }
  const mapping::LocalGrid grid = makeBoxGrid(Eigen::Vector3d(10.0, 6.0, 3.0), Eigen::Vector3d(3.5, 0.0, 1.5), pillars);
  std::vector<Eigen::Vector3d> path;
  for (double x = 0.0; x <= 7.0 + 1e-9; x += 0.04) path.emplace_back(x, -0.5 * std::cos(M_PI * x), 1.5);
  ASSERT_TRUE(pathFree(grid, path));
  CorridorBuilder builder = makeBuilder();
  Corridor corridor;
  ASSERT_TRUE(builder.build(grid, path, corridor).has_value());
  expectValidCorridor(grid, path, corridor, builder.params(), "slalom");
  EXPECT_GE(corridor.boxes.size(), 6u) << "a box cannot span two consecutive pillars' gaps";
  EXPECT_LE(corridor.boxes.size(), 14u);
}

TEST(Corridor, GivenSeededRandomObstacleFieldsAndSearchPathsThenEveryCorridorHoldsItsGuarantees) {
  KinodynamicSearchParams search_params;
  search_params.max_expansions = 2000;
  auto search = KinodynamicSearch::create(search_params);
  ASSERT_TRUE(search.has_value());
  CorridorBuilder builder = makeBuilder();
  Corridor corridor;
  SearchPath path;
  std::vector<Eigen::Vector3d> polyline_W_m;
  int built = 0;
  int searched = 0;
  int boxes = 0;
  for (int seed = 1; seed <= 60; ++seed) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
    std::uniform_real_distribution<double> xy(-5.0, 5.0);
    std::uniform_real_distribution<double> half(0.1, 0.4);
    std::uniform_real_distribution<double> z(0.3, 2.7);
    std::vector<OccupiedBox> obstacles;
    for (int i = 0; i < 14; ++i) {                     // pillars
      const Eigen::Vector3d c{xy(rng), xy(rng), 0.0};  // braces: drawn left to right
      const double r = half(rng);
      obstacles.push_back({c + Eigen::Vector3d(-r, -r, -1.0), c + Eigen::Vector3d(r, r, 5.0)});
    }
    for (int i = 0; i < 6; ++i) {  // floating blocks
      const Eigen::Vector3d c{xy(rng), xy(rng), z(rng)};
      const Eigen::Vector3d r{half(rng), half(rng), half(rng)};
      obstacles.push_back({c - r, c + r});
    }
    const mapping::LocalGrid grid =
        makeBoxGrid(Eigen::Vector3d(12.0, 12.0, 3.0), Eigen::Vector3d(0.0, 0.0, 1.5), obstacles);
    for (int query = 0; query < 4; ++query) {
      KinematicState start;
      KinematicState goal;
      start.p_W_m = Eigen::Vector3d{xy(rng), xy(rng), z(rng) * 0.5 + 0.75};
      goal.p_W_m = Eigen::Vector3d{xy(rng), xy(rng), z(rng) * 0.5 + 0.75};
      const double distance_m = (goal.p_W_m - start.p_W_m).norm();
      if (distance_m < 3.0 || distance_m > 8.0 || grid.isOccupied(start.p_W_m) || grid.isOccupied(goal.p_W_m)) {
        continue;
      }
      const SearchStatus status = search->search(grid, start, goal, 0.0, nullptr, path);
      if (status != SearchStatus::kReachedGoal && status != SearchStatus::kPartial) continue;
      ++searched;
      polyline_W_m.clear();
      const int n = std::max(1, static_cast<int>(std::ceil(path.duration_s / 0.02)));
      for (int i = 0; i <= n; ++i) polyline_W_m.push_back(path.stateAt(path.duration_s * i / n).p_W_m);
      const std::string what = "seed " + std::to_string(seed) + " query " + std::to_string(query);
      const rt::Status result = builder.build(grid, polyline_W_m, corridor);
      if (!result) {
        // Allowed only where the sampled polyline itself touches a blocked cell (the search checks its own
        // chords, which the curve follows within 1 mm, not these).
        EXPECT_FALSE(pathFree(grid, polyline_W_m)) << what << ": " << result.error().message;
        continue;
      }
      ++built;
      boxes += static_cast<int>(corridor.boxes.size());
      expectValidCorridor(grid, polyline_W_m, corridor, builder.params(), what);
    }
  }
  EXPECT_GE(searched, 80);
  EXPECT_GE(built, searched * 95 / 100) << "of " << searched << " search paths";
  std::printf("[ corridor ] %d of %d search paths, %.1f boxes on average\n", built, searched,
              static_cast<double>(boxes) / std::max(1, built));
}

// Single occupied voxels (the smallest blocked blobs: one inflation ball each) at random, for inflation radii
// whose balls allow the sparse check (0.25, 0.27, 0.35 m: every 3rd row) and radii that do not (0, 0.15, 0.2,
// 0.3 m: every row), and random straight paths between free points: every box is dense-checked.
TEST(Corridor, GivenScatteredSingleVoxelsAndSeveralInflationRadiiThenNoBoxHoldsABlockedCell) {
  CorridorBuilder builder = makeBuilder();
  Corridor corridor;
  for (const double radius_m : {0.25, 0.27, 0.35, 0.0, 0.15, 0.2, 0.3}) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(radius_m * 1000.0) + 7);
    std::uniform_real_distribution<double> xy(-3.8, 3.8);
    std::uniform_real_distribution<double> z(0.1, 2.9);
    std::vector<OccupiedBox> voxels;
    for (int i = 0; i < 100; ++i) {
      const Eigen::Vector3d c =
          ((Eigen::Vector3d{xy(rng), xy(rng), z(rng)} / kResolutionM).array().floor() + 0.5) * kResolutionM;
      voxels.push_back({c, c});
    }
    const mapping::LocalGrid grid =
        makeBoxGrid(Eigen::Vector3d(8.0, 8.0, 3.0), Eigen::Vector3d(0.0, 0.0, 1.5), voxels, radius_m);
    int built = 0;
    for (int query = 0; query < 40; ++query) {
      const Eigen::Vector3d a{xy(rng), xy(rng), z(rng)};
      const Eigen::Vector3d b{xy(rng), xy(rng), z(rng)};
      const std::vector<Eigen::Vector3d> path = polyline({a, b});
      if (!pathFree(grid, path)) continue;
      ++built;
      ASSERT_TRUE(builder.build(grid, path, corridor).has_value());
      expectValidCorridor(grid, path, corridor, builder.params(),
                          "radius " + std::to_string(radius_m) + " query " + std::to_string(query));
    }
    EXPECT_GE(built, 3) << "radius " << radius_m;
  }
}

// unknown_is_occupied: a known-free region with unknown pockets (each unknown cell blocks on its own, so
// every row is checked) and a wall.
TEST(Corridor, GivenUnknownCellsThatBlockThenBoxesStayInKnownFreeSpace) {
  mapping::LocalGridParams params;
  params.resolution_m = kResolutionM;
  params.size_m = Eigen::Vector3d(6.0, 6.0, 2.0);
  params.inflation_radius_m = 0.25;
  params.unknown_is_occupied = true;
  params.recenter_distance_m = 0.0;
  octomap::OcTree tree = mapping::test::makeTree(kResolutionM);
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> pocket(-25, 24);
  std::vector<mapping::CellIndex> pockets;
  pockets.reserve(40);
  for (int i = 0; i < 40; ++i) {
    const int x = pocket(rng);
    const int y = pocket(rng);
    pockets.emplace_back(x, y, pocket(rng) / 3 + 10);
  }
  for (int z = 0; z < 20; ++z) {
    for (int y = -28; y < 28; ++y) {
      for (int x = -28; x < 28; ++x) {
        const mapping::CellIndex cell(x, y, z);
        if (std::find(pockets.begin(), pockets.end(), cell) != pockets.end()) continue;
        mapping::test::setCell(tree, cell, x >= 5 && x < 8 && y < 10);  // a wall at x in [0.5, 0.8) m
      }
    }
  }
  mapping::LocalGrid grid = mapping::test::makeGrid(params);
  ASSERT_TRUE(grid.recenter(Eigen::Vector3d(0.0, 0.0, 1.0), tree).has_value());
  ASSERT_TRUE(grid.rebuild(tree).has_value());
  CorridorBuilder builder = makeBuilder();
  Corridor corridor;
  int built = 0;
  std::uniform_real_distribution<double> xy(-2.4, 2.4);
  std::uniform_real_distribution<double> z(0.4, 1.6);
  for (int query = 0; query < 30; ++query) {
    const std::vector<Eigen::Vector3d> path =
        polyline({{xy(rng), xy(rng), z(rng)}, {-0.5, 1.6, z(rng)}, {xy(rng), xy(rng), z(rng)}});
    if (!pathFree(grid, path)) continue;
    ++built;
    ASSERT_TRUE(builder.build(grid, path, corridor).has_value());
    expectValidCorridor(grid, path, corridor, builder.params(), "unknown blocks, query " + std::to_string(query));
  }
  EXPECT_GE(built, 5);
}

TEST(Corridor, GivenAChordThroughTheCornerOfABlockedCellThenTheWalkGoesRoundThroughTheFreeNeighbour) {
  // No inflation, one occupied voxel: cell (5, 4, 15). The chord from (0.45, 0.45) to (0.55, 0.55) passes
  // through the corner (0.5, 0.5), touching that cell only there (a point also on the free cells' faces).
  const Eigen::Vector3d voxel_W_m(0.55, 0.45, 1.55);
  const mapping::LocalGrid grid =
      makeBoxGrid(Eigen::Vector3d(4.0, 4.0, 3.0), Eigen::Vector3d(0.0, 0.0, 1.5), {{voxel_W_m, voxel_W_m}}, 0.0);
  ASSERT_TRUE(grid.isOccupied(voxel_W_m));
  const std::vector<Eigen::Vector3d> path{{0.45, 0.45, 1.55}, {0.55, 0.55, 1.55}};
  CorridorBuilder builder = makeBuilder();
  Corridor corridor;
  const rt::Status status = builder.build(grid, path, corridor);
  ASSERT_TRUE(status.has_value()) << status.error().message;
  expectValidCorridor(grid, path, corridor, builder.params(), "corner");
}

TEST(Corridor, GivenAChordCuttingABlockedCornerByAMillimetreThenTheToleranceDecides) {
  // As above, but the chord crosses x = 0.5 at y = 0.499: it runs 1 mm deep into the blocked cell (5, 4).
  const Eigen::Vector3d voxel_W_m(0.55, 0.45, 1.55);
  const mapping::LocalGrid grid =
      makeBoxGrid(Eigen::Vector3d(4.0, 4.0, 3.0), Eigen::Vector3d(0.0, 0.0, 1.5), {{voxel_W_m, voxel_W_m}}, 0.0);
  const std::vector<Eigen::Vector3d> path{{0.451, 0.45, 1.55}, {0.551, 0.55, 1.55}};
  ASSERT_FALSE(grid.segmentFree(path[0], path[1]));
  CorridorBuilder tolerant = makeBuilder();  // 2 mm
  Corridor corridor;
  const rt::Status status = tolerant.build(grid, path, corridor);
  ASSERT_TRUE(status.has_value()) << status.error().message;
  expectValidCorridor(grid, path, corridor, tolerant.params(), "1 mm corner");

  CorridorParams strict_params;
  strict_params.corner_tolerance_m = 0.0;
  CorridorBuilder strict = makeBuilder(strict_params);
  const rt::Status strict_status = strict.build(grid, path, corridor);
  ASSERT_FALSE(strict_status.has_value());
  EXPECT_NE(strict_status.error().message.find("crosses the blocked cell at (0.55, 0.45, 1.55)"), std::string::npos)
      << strict_status.error().message;
  strict_params.corner_tolerance_m = 0.0009;
  CorridorBuilder almost = makeBuilder(strict_params);
  EXPECT_FALSE(almost.build(grid, path, corridor).has_value());
}

TEST(Corridor, GivenACapOfTenCellsThenNoEdgeIsLonger) {
  const mapping::LocalGrid grid = makeBoxGrid(Eigen::Vector3d(8.0, 8.0, 3.0), Eigen::Vector3d(0.0, 0.0, 1.5), {});
  CorridorParams params;
  params.max_box_size_m = Eigen::Vector3d(1.0, 1.05, 0.2);  // 10, 10 and 2 cells
  CorridorBuilder builder = makeBuilder(params);
  const std::vector<Eigen::Vector3d> path = polyline({{-2.0, -1.0, 1.5}, {2.0, 1.0, 1.5}});
  Corridor corridor;
  ASSERT_TRUE(builder.build(grid, path, corridor).has_value());
  expectValidCorridor(grid, path, corridor, params, "capped");
  for (const CorridorBox& box : corridor.boxes) {
    EXPECT_LE((box.cells.hi - box.cells.lo).maxCoeff(), 10);
    EXPECT_EQ(box.cells.hi.z() - box.cells.lo.z(), 2);
  }
}

TEST(Corridor, GivenBadPathsThenBuildFailsWithAClearMessageAndAnEmptyCorridor) {
  const mapping::LocalGrid grid = makeBoxGrid(Eigen::Vector3d(8.0, 8.0, 3.0), Eigen::Vector3d(0.0, 0.0, 1.5),
                                              {{Eigen::Vector3d(1.0, -1.0, -1.0), Eigen::Vector3d(1.4, 1.0, 4.0)}});
  CorridorBuilder builder = makeBuilder();
  Corridor corridor;
  const auto fails = [&](const std::vector<Eigen::Vector3d>& path, const std::string& expected) {
    ASSERT_TRUE(builder.build(grid, Path{{0.0, 0.0, 1.5}, {0.3, 0.0, 1.5}}, corridor).has_value());
    ASSERT_FALSE(corridor.boxes.empty());
    const rt::Status status = builder.build(grid, path, corridor);
    ASSERT_FALSE(status.has_value()) << expected;
    EXPECT_NE(status.error().message.find(expected), std::string::npos) << status.error().message;
    EXPECT_EQ(status.error().message.find('\n'), std::string::npos);
    EXPECT_TRUE(corridor.boxes.empty());
    EXPECT_TRUE(corridor.waypoints_W_m.empty());
    EXPECT_TRUE(corridor.waypoint_path_index.empty());
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  fails({}, "empty path");
  fails({{0.0, 0.0, 1.5}, {0.5, nan, 1.5}}, "path point 1 is not finite");
  fails({{1.2, 0.0, 1.5}, {0.0, 0.0, 1.5}}, "path start (1.20, 0.00, 1.50) is in a blocked cell");
  fails({{0.9, 0.0, 1.5}}, "blocked cell");  // inflated: 0.1 m from the block
  fails({{9.0, 0.0, 1.5}, {0.0, 0.0, 1.5}}, "path start (9.00, 0.00, 1.50) is outside the grid window");
  fails({{0.0, 0.0, 1.5}, {0.0, 5.0, 1.5}}, "path point 1 (0.00, 5.00, 1.50) is outside the grid window");
  fails({{0.0, 0.0, 1.5}, {2.0, 0.0, 1.5}}, "the path between points 0 and 1 crosses the blocked cell");

  CorridorParams few;
  few.max_boxes = 2;
  CorridorBuilder limited = makeBuilder(few);
  const std::vector<Eigen::Vector3d> long_path = polyline({{-2.0, -3.5, 1.5}, {-2.0, 3.5, 1.5}});
  const rt::Status too_many = limited.build(grid, long_path, corridor);
  ASSERT_FALSE(too_many.has_value());
  EXPECT_NE(too_many.error().message.find("more than 2 boxes (max_boxes)"), std::string::npos)
      << too_many.error().message;

  CorridorParams short_walk;
  short_walk.max_path_cells = 10;
  CorridorBuilder walk_limited = makeBuilder(short_walk);
  const rt::Status too_long = walk_limited.build(grid, Path{{0.0, -3.0, 1.5}, {0.0, 3.0, 1.5}}, corridor);
  ASSERT_FALSE(too_long.has_value());
  EXPECT_NE(too_long.error().message.find("more than 10 grid cells (max_path_cells)"), std::string::npos);

  CorridorParams tiny;
  tiny.max_box_size_m = Eigen::Vector3d(3.0, 0.15, 2.0);  // one cell in y
  CorridorBuilder tiny_builder = makeBuilder(tiny);
  const rt::Status too_small = tiny_builder.build(grid, Path{{0.0, 0.0, 1.5}}, corridor);
  ASSERT_FALSE(too_small.has_value());
  EXPECT_NE(too_small.error().message.find("at least two grid cells"), std::string::npos);
}

TEST(Corridor, GivenBadParamsThenValidateAndCreateFail) {
  EXPECT_TRUE(validate(CorridorParams{}).has_value());
  CorridorParams params;
  params.max_box_size_m.y() = 0.0;
  EXPECT_FALSE(validate(params).has_value());
  EXPECT_FALSE(CorridorBuilder::create(params).has_value());
  params = CorridorParams{};
  params.max_box_size_m.z() = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(CorridorBuilder::create(params).has_value());
  params = CorridorParams{};
  params.max_boxes = 0;
  EXPECT_FALSE(CorridorBuilder::create(params).has_value());
  params = CorridorParams{};
  params.corner_tolerance_m = -0.001;
  EXPECT_FALSE(CorridorBuilder::create(params).has_value());
  params.corner_tolerance_m = 0.1;
  EXPECT_FALSE(CorridorBuilder::create(params).has_value());
  params = CorridorParams{};
  params.max_path_cells = 0;
  const auto created = CorridorBuilder::create(params);
  ASSERT_FALSE(created.has_value());
  EXPECT_NE(created.error().message.find("max_path_cells"), std::string::npos);
}

TEST(CorridorParams, GivenAConfigSectionThenEveryKeyIsReadStrictly) {
  const std::string text =
      "corridor:\n  max_box_size_m: [2.0, 2.5, 1.5]\n  max_boxes: 12\n  max_path_cells: 2000\n"
      "  corner_tolerance_m: 0.001\n";
  auto root = rt::ConfigNode::fromString(text, "corridor.yaml");
  ASSERT_TRUE(root.has_value());
  const CorridorParams params = parseCorridorParams(root->child("corridor"));
  EXPECT_EQ(params.max_box_size_m, Eigen::Vector3d(2.0, 2.5, 1.5));
  EXPECT_EQ(params.max_boxes, 12);
  EXPECT_EQ(params.max_path_cells, 2000);
  EXPECT_EQ(params.corner_tolerance_m, 0.001);

  auto unknown = rt::ConfigNode::fromString(text + "  max_box_count: 3\n", "corridor.yaml");
  ASSERT_TRUE(unknown.has_value());
  EXPECT_THROW(parseCorridorParams(unknown->child("corridor")), rt::ConfigError);
  auto missing = rt::ConfigNode::fromString(
      "corridor:\n  max_boxes: 12\n  max_path_cells: 2000\n  corner_tolerance_m: 0.0\n", "c.yaml");
  ASSERT_TRUE(missing.has_value());
  EXPECT_THROW(parseCorridorParams(missing->child("corridor")), rt::ConfigError);
  auto negative = rt::ConfigNode::fromString(
      "corridor:\n  max_box_size_m: [2.0, -1.0, 1.5]\n  max_boxes: 12\n  max_path_cells: 2000\n"
      "  corner_tolerance_m: 0.0\n",
      "c.yaml");
  ASSERT_TRUE(negative.has_value());
  EXPECT_THROW(parseCorridorParams(negative->child("corridor")), rt::ConfigError);
}

TEST(CorridorAllocation, GivenACreatedBuilderAndAWarmCorridorThenBuildNeverAllocates) {
  if (!aerotrack::test::kMallocCounted) GTEST_SKIP() << "malloc belongs to the sanitizer";
  std::vector<OccupiedBox> pillars;
  for (int k = 1; k <= 6; ++k) {
    const Eigen::Vector3d c(k, (k % 2 == 0 ? 0.5 : -0.5), 0.0);
    pillars.push_back({c + Eigen::Vector3d(-0.15, -0.15, -1.0), c + Eigen::Vector3d(0.15, 0.15, 4.0)});
  }
  const mapping::LocalGrid grid = makeBoxGrid(Eigen::Vector3d(10.0, 6.0, 3.0), Eigen::Vector3d(3.5, 0.0, 1.5), pillars);
  std::vector<Eigen::Vector3d> slalom;
  for (double x = 0.0; x <= 7.0 + 1e-9; x += 0.04) slalom.emplace_back(x, -0.5 * std::cos(M_PI * x), 1.5);
  const std::vector<Eigen::Vector3d> straight = polyline({{0.0, -2.0, 1.0}, {6.0, -2.0, 2.0}});
  CorridorBuilder builder = makeBuilder();
  EXPECT_GE(aerotrack::test::mallocsOfAHeapBuffer(), 1);  // the interposition works
  Corridor corridor;
  ASSERT_TRUE(builder.build(grid, straight, corridor).has_value());  // warms the corridor's vectors
  std::size_t boxes = 0;
  bool ok = true;
  aerotrack::test::g_mallocs = 0;
  aerotrack::test::g_counting_mallocs = true;
  ok = ok && builder.build(grid, slalom, corridor).has_value();  // more boxes than the warm-up
  boxes += corridor.boxes.size();
  ok = ok && builder.build(grid, straight, corridor).has_value();
  boxes += corridor.boxes.size();
  ok = ok && builder.build(grid, slalom, corridor).has_value();
  boxes += corridor.boxes.size();
  aerotrack::test::g_counting_mallocs = false;
  EXPECT_TRUE(ok);
  EXPECT_GE(boxes, 13u);
  EXPECT_EQ(aerotrack::test::g_mallocs.load(), 0);
}

}  // namespace
}  // namespace aerotrack::planning
