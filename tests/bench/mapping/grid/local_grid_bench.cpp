// Benchmarks of LocalGrid (Google Benchmark) on the default 20 x 20 x 5 m, 0.1 m grid in a cluttered
// synthetic world (ground, random pillars and boxes, known free space up to 2.5 m): point queries,
// 10,000 line-of-sight casts of 5 m, applyChanges for a frame's changed keys, recentre by 2 m, copyFrom
// (a snapshot for readers) and a full rebuild for comparison. Targets: isOccupied <= 20 ns, 10,000
// casts <= 5 ms.
#include <benchmark/benchmark.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "aerotrack/mapping/local_grid.hpp"

namespace aerotrack::mapping {
namespace {

constexpr int kKeyOffset = 32768;

octomap::OcTreeKey keyOf(int x, int y, int z) {
  return octomap::OcTreeKey(static_cast<octomap::key_type>(x + kKeyOffset),
                            static_cast<octomap::key_type>(y + kKeyOffset),
                            static_cast<octomap::key_type>(z + kKeyOffset));
}

// The world, built once: a 44 x 44 m area (cells -220..219), ground at z cell -1, free space in z cells
// 0..24, 300 random pillars (0.2-1 m square, 1-3 m tall) and 3,000 random single voxels.
struct World {
  octomap::OcTree tree{0.1};
  World() {
    std::mt19937 rng(1);
    for (int y = -220; y < 220; ++y) {
      for (int x = -220; x < 220; ++x) {
        tree.setNodeValue(keyOf(x, y, -1), 2.0f, true);
        for (int z = 0; z < 25; ++z) tree.setNodeValue(keyOf(x, y, z), -2.0f, true);
      }
    }
    std::uniform_int_distribution<int> xy(-220, 219);
    std::uniform_int_distribution<int> width(2, 10);
    std::uniform_int_distribution<int> height(10, 30);
    for (int i = 0; i < 300; ++i) {
      const int x0 = xy(rng);
      const int y0 = xy(rng);
      const int w = width(rng);
      const int h = height(rng);
      for (int z = 0; z < h; ++z) {
        for (int y = y0; y < y0 + w; ++y) {
          for (int x = x0; x < x0 + w; ++x) tree.setNodeValue(keyOf(x, y, z), 2.0f, true);
        }
      }
    }
    std::uniform_int_distribution<int> zc(0, 24);
    for (int i = 0; i < 3000; ++i) tree.setNodeValue(keyOf(xy(rng), xy(rng), zc(rng)), 2.0f, true);
    tree.updateInnerOccupancy();
    tree.prune();
  }
};

World& world() {
  static World instance;  // benchmark-only: built on first use, shared by all benchmarks
  return instance;
}

LocalGrid makeGrid(const LocalGridParams& params = {}) {
  auto grid = LocalGrid::create(params);
  if (!grid) std::abort();
  return std::move(grid).value();
}

LocalGrid syncedGrid(const LocalGridParams& params = {}) {
  LocalGrid grid = makeGrid(params);
  if (!grid.rebuild(world().tree)) std::abort();
  return grid;
}

std::vector<Eigen::Vector3d> randomPoints(int n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> xy(-9.99, 9.99);
  std::uniform_real_distribution<double> z(-0.2, 2.4);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < n; ++i) points.emplace_back(xy(rng), xy(rng), z(rng));
  return points;
}

void BM_IsOccupied(benchmark::State& state) {
  const LocalGrid grid = syncedGrid();
  const std::vector<Eigen::Vector3d> points = randomPoints(4096, 2);
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(grid.isOccupied(points[i]));
    i = (i + 1) & 4095;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_IsOccupied);

// 10,000 casts of 5 m from random points in random directions (some leave the window). Sight stops at the
// first raw-occupied cell; the counter says what fraction was blocked.
void castBench(benchmark::State& state, bool clutter) {
  const LocalGrid grid = clutter ? syncedGrid() : makeGrid();
  std::mt19937 rng(3);
  std::normal_distribution<double> dir(0.0, 1.0);
  const std::vector<Eigen::Vector3d> starts = randomPoints(10000, 4);
  std::vector<Eigen::Vector3d> ends;
  for (const Eigen::Vector3d& a : starts) {
    ends.push_back(a + 5.0 * Eigen::Vector3d(dir(rng), dir(rng), 0.3 * dir(rng)).normalized());
  }
  int visible = 0;
  for (auto _ : state) {
    visible = 0;
    for (std::size_t i = 0; i < starts.size(); ++i) visible += grid.lineOfSight(starts[i], ends[i]) ? 1 : 0;
    benchmark::DoNotOptimize(visible);
  }
  state.counters["blocked_fraction"] = 1.0 - visible / 10000.0;
  state.SetItemsProcessed(state.iterations() * 10000);
}
void BM_LineOfSight10k(benchmark::State& state) {
  castBench(state, true);
}
void BM_LineOfSight10kEmpty(benchmark::State& state) {
  castBench(state, false);
}  // no early exit
BENCHMARK(BM_LineOfSight10k)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LineOfSight10kEmpty)->Unit(benchmark::kMillisecond);

void BM_SegmentFree10k(benchmark::State& state) {
  const LocalGrid grid = syncedGrid();
  const std::vector<Eigen::Vector3d> starts = randomPoints(10000, 5);
  const std::vector<Eigen::Vector3d> ends = randomPoints(10000, 6);
  for (auto _ : state) {
    int free = 0;
    for (std::size_t i = 0; i < starts.size(); ++i) {
      const Eigen::Vector3d b = starts[i] + 0.5 * (ends[i] - starts[i]).normalized();  // 0.5 m path segments
      free += grid.segmentFree(starts[i], b) ? 1 : 0;
    }
    benchmark::DoNotOptimize(free);
  }
  state.SetItemsProcessed(state.iterations() * 10000);
}
BENCHMARK(BM_SegmentFree10k)->Unit(benchmark::kMillisecond);

// applyChanges for N changed keys in the window, every one flipping free <-> occupied (the worst case:
// each flip touches the 81-cell stencil twice per round trip). The tree edits are not timed.
void BM_ApplyChangesFlips(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  octomap::OcTree tree(0.1);
  tree.enableChangeDetection(true);
  LocalGrid grid = makeGrid();
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> xy(-100, 99);
  std::uniform_int_distribution<int> z(-25, 24);
  std::vector<octomap::OcTreeKey> keys;
  for (int i = 0; i < n; ++i) keys.push_back(keyOf(xy(rng), xy(rng), z(rng)));
  bool occupied = true;
  for (auto _ : state) {
    state.PauseTiming();
    tree.resetChangeDetection();
    for (const auto& key : keys) tree.setNodeValue(key, occupied ? 2.0f : -2.0f);
    occupied = !occupied;
    state.ResumeTiming();
    if (!grid.applyChanges(tree)) state.SkipWithError("applyChanges failed");
  }
  state.counters["changed_keys"] = static_cast<double>(tree.numChangesDetected());
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_ApplyChangesFlips)->Arg(2000)->Arg(20000)->Unit(benchmark::kMicrosecond);

// applyChanges after one depth frame (rays from the drone: mostly newly free keys, occupied ends).
void BM_ApplyChangesDepthFrame(benchmark::State& state) {
  const int rays = static_cast<int>(state.range(0));
  std::mt19937 rng(8);
  std::normal_distribution<double> dir(0.0, 1.0);
  std::uniform_real_distribution<double> dist(1.0, 6.0);
  double changed = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    octomap::OcTree tree(0.1);
    tree.enableChangeDetection(true);
    LocalGrid grid = makeGrid();
    octomap::Pointcloud cloud;
    for (int i = 0; i < rays; ++i) {
      const Eigen::Vector3d p = dist(rng) * Eigen::Vector3d(dir(rng), dir(rng), 0.3 * dir(rng)).normalized();
      cloud.push_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    }
    tree.insertPointCloud(cloud, octomap::point3d(0.0f, 0.0f, 0.0f));
    changed = static_cast<double>(tree.numChangesDetected());
    state.ResumeTiming();
    if (!grid.applyChanges(tree)) state.SkipWithError("applyChanges failed");
  }
  state.counters["changed_keys"] = changed;
}
BENCHMARK(BM_ApplyChangesDepthFrame)->Arg(500)->Arg(2000)->Unit(benchmark::kMicrosecond);

// Recentre by 2 m in x, back and forth (every iteration moves the window by 2 m).
void BM_Recenter2m(benchmark::State& state) {
  LocalGridParams params;
  params.recenter_distance_m = 1.0;
  LocalGrid grid = syncedGrid(params);
  bool forward = true;
  for (auto _ : state) {
    auto moved = grid.recenter(Eigen::Vector3d(forward ? 2.0 : 0.0, 0.0, 0.0), world().tree);
    if (!moved || !*moved) state.SkipWithError("recenter did not move");
    forward = !forward;
  }
}
BENCHMARK(BM_Recenter2m)->Unit(benchmark::kMillisecond);

void BM_CopyFrom(benchmark::State& state) {
  const LocalGrid grid = syncedGrid();
  LocalGrid snapshot = makeGrid();
  for (auto _ : state) {
    snapshot.copyFrom(grid);
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(grid.storageBytes()));
}
BENCHMARK(BM_CopyFrom)->Unit(benchmark::kMicrosecond);

void BM_Rebuild(benchmark::State& state) {
  LocalGrid grid = makeGrid();
  for (auto _ : state) {
    if (!grid.rebuild(world().tree)) state.SkipWithError("rebuild failed");
  }
}
BENCHMARK(BM_Rebuild)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace aerotrack::mapping
