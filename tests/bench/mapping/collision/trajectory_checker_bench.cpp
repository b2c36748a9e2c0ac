// Benchmarks for TrajectoryChecker (issue 4, item 4; target <= 1 ms per check): a 3 s trajectory
// weaving at 2.75-3.0 m/s (about 9 m, ~180 samples at 5 cm) through a forest-like OctoMap at
// 0.1 m resolution: a ground layer and ~60 trees as occupied vertical columns (radius 0.1-0.3 m,
// 5 m tall) over 20 x 20 m. Cases: collision free (the worst case: every sample is checked) and a
// tree in the way half-way along. The argument is broad_phase_group (1 = one FCL query per sample).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include <octomap/OcTree.h>

#include "aerotrack/mapping/trajectory_checker.hpp"

namespace aerotrack::mapping {
namespace {

constexpr double kResolutionM = 0.1;
constexpr double kForestSizeM = 20.0;
constexpr double kTreeHeightM = 5.0;
constexpr double kDroneRadiusM = 0.25;
constexpr int kWeaves = 8;

/// x = x0 + 2.75 t, y = y0 + 0.8 sin(1.5 t), z = 1.5 on [0, 3] s: speed in [2.75, 3.0] m/s.
class Weave final : public trajectory_server::Trajectory {
 public:
  Weave(double x0_m, double y0_m) : x0_m_(x0_m), y0_m_(y0_m) {}
  double durationS() const override { return 3.0; }
  trajectory_server::TrajectorySample sample(double t_s) const override {
    const double t = std::clamp(t_s, 0.0, 3.0);
    trajectory_server::TrajectorySample s;
    s.p_W_m = {x0_m_ + 2.75 * t, y0_m_ + 0.8 * std::sin(1.5 * t), 1.5};
    s.v_W_mps = {2.75, 1.2 * std::cos(1.5 * t), 0.0};
    s.a_W_mps2 = {0.0, -1.8 * std::sin(1.5 * t), 0.0};
    return s;
  }

 private:
  double x0_m_;
  double y0_m_;
};

void addTree(octomap::OcTree& tree, double x_m, double y_m, double radius_m) {
  for (double x = std::floor((x_m - radius_m) / kResolutionM) * kResolutionM; x <= x_m + radius_m; x += kResolutionM) {
    for (double y = std::floor((y_m - radius_m) / kResolutionM) * kResolutionM; y <= y_m + radius_m;
         y += kResolutionM) {
      const double cx = x + kResolutionM / 2;
      const double cy = y + kResolutionM / 2;
      if (std::hypot(cx - x_m, cy - y_m) > radius_m) continue;
      for (double z = kResolutionM / 2; z < kTreeHeightM; z += kResolutionM) {
        tree.updateNode(octomap::point3d(static_cast<float>(cx), static_cast<float>(cy), static_cast<float>(z)), true);
      }
    }
  }
}

struct Scene {
  std::vector<Weave> weaves;
  std::shared_ptr<octomap::OcTree> forest;   // every weave is collision free
  std::shared_ptr<octomap::OcTree> blocked;  // the same plus a tree on every weave at t = 1.5 s
};

Scene makeScene() {
  Scene scene;
  for (int k = 0; k < kWeaves; ++k) scene.weaves.emplace_back(5.0, 1.8 + 2.3 * k);
  scene.forest = std::make_shared<octomap::OcTree>(kResolutionM);
  for (double x = kResolutionM / 2; x < kForestSizeM; x += kResolutionM) {
    for (double y = kResolutionM / 2; y < kForestSizeM; y += kResolutionM) {
      scene.forest->updateNode(octomap::point3d(static_cast<float>(x), static_cast<float>(y), -0.05f), true);
    }
  }
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coord(0.0, kForestSizeM);
  std::uniform_real_distribution<double> radius(0.1, 0.3);
  int trees = 0;
  while (trees < 60) {
    const double x = coord(rng), y = coord(rng), r = radius(rng);
    // Keep 0.1 m between the drone's sphere and a voxel's corner (voxels stick out up to
    // 0.05 sqrt(2) m beyond the trunk radius).
    bool in_the_way = false;
    for (const Weave& weave : scene.weaves) {
      for (double t = 0.0; t <= 3.0 && !in_the_way; t += 0.005) {
        const Eigen::Vector3d p = weave.sample(t).p_W_m;
        in_the_way = std::hypot(p.x() - x, p.y() - y) < r + 0.0708 + kDroneRadiusM + 0.1;
      }
    }
    if (in_the_way) continue;
    addTree(*scene.forest, x, y, r);
    ++trees;
  }
  scene.blocked = std::make_shared<octomap::OcTree>(*scene.forest);
  for (const Weave& weave : scene.weaves) {
    const Eigen::Vector3d p = weave.sample(1.5).p_W_m;
    addTree(*scene.blocked, p.x(), p.y(), 0.2);
  }
  return scene;
}

const Scene& scene() {
  static const Scene kScene = makeScene();  // built once, outside the timed loops
  return kScene;
}

void runCheck(benchmark::State& state, const std::shared_ptr<octomap::OcTree>& tree, bool expect_free) {
  TrajectoryCheckerParams params;
  params.broad_phase_group = static_cast<int>(state.range(0));
  const TrajectoryChecker checker = TrajectoryChecker::create(params).value();
  const std::shared_ptr<const octomap::OcTree> snapshot = tree;
  for (const Weave& weave : scene().weaves) {
    auto report = checker.check(weave, 0.0, weave.durationS(), snapshot);
    if (!report || report->collision_free != expect_free) {
      state.SkipWithError("scene does not give the expected verdict");
      return;
    }
  }
  size_t i = 0;
  double samples = 0;
  for (auto _ : state) {
    const Weave& weave = scene().weaves[i++ % scene().weaves.size()];
    auto report = checker.check(weave, 0.0, weave.durationS(), snapshot);
    benchmark::DoNotOptimize(report);
    samples += report->samples_checked;
  }
  state.counters["samples"] = benchmark::Counter(samples / static_cast<double>(state.iterations()));
  state.counters["leaves"] = static_cast<double>(tree->getNumLeafNodes());
}

void BM_CheckCollisionFree(benchmark::State& state) {
  runCheck(state, scene().forest, true);
}
BENCHMARK(BM_CheckCollisionFree)->Arg(1)->Arg(4)->Arg(8)->Arg(16)->Arg(32)->Arg(64)->Unit(benchmark::kMicrosecond);

void BM_CheckTreeHalfWay(benchmark::State& state) {
  runCheck(state, scene().blocked, false);
}
BENCHMARK(BM_CheckTreeHalfWay)->Arg(1)->Arg(8)->Arg(16)->Unit(benchmark::kMicrosecond);

/// The sampler alone (trajectory evaluation and step control), for scale.
void BM_SampleOnly(benchmark::State& state) {
  std::vector<CheckSample> samples;
  samples.reserve(1024);
  const Weave& weave = scene().weaves[0];
  for (auto _ : state) {
    samples.clear();
    benchmark::DoNotOptimize(sampleTrajectory(weave, 0.0, weave.durationS(), 0.05, samples));
  }
  state.counters["samples"] = static_cast<double>(samples.size());
}
BENCHMARK(BM_SampleOnly)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace aerotrack::mapping
