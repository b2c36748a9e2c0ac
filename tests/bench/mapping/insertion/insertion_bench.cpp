// Benchmarks of depth-frame insertion into the OctoMap (issue 4, item 6). The depth images are
// rendered analytically here (no simulator library): a camera 1.5 m above the ground, pitched
// 10 deg down, flies along +x through a procedural forest (vertical cylinders of radius 0.10 to
// 0.25 m on a jittered 2.5 m grid, a 2 m corridor kept clear) beside a 3 m high wall at y = 5 m;
// ground z = 0. D435-like depth camera (87 x 58 deg), depths beyond 10 m read 0 (no data), as
// in the simulator. Only the pixels that depthToPoints reads at the benchmark's decimation are
// rendered (the others are 0), so a 640 x 480 frame costs no more to prepare than 160 x 120.
//
// Run: bench_mapping_insertion --benchmark_repetitions=10 --benchmark_report_aggregates_only=true
// and read the *_median rows. Targets (one core): 160 x 120 / 4 <= 3 ms, 640 x 480 / 16 <= 5 ms.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include <benchmark/benchmark.h>

#include "aerotrack/mapping/depth_points.hpp"
#include "aerotrack/mapping/frame_inserter.hpp"
#include "aerotrack/mapping/octomap_map.hpp"
#include "aerotrack/mapping/pose_history.hpp"

namespace {

using aerotrack::hal::DepthFrame;
using namespace aerotrack::mapping;  // NOLINT(google-build-using-namespace)

constexpr double kPi = 3.14159265358979323846;
constexpr double kTreeSpacingM = 2.5;
constexpr double kWallYM = 5.0;
constexpr double kWallHeightM = 3.0;
constexpr double kCameraMaxRangeM = 10.0;
constexpr double kCameraHeightM = 1.5;
constexpr double kFlightStepM = 2.0 / 30.0;  // 2 m/s at 30 frames per second.

double hash01(std::int64_t i, std::int64_t j, std::uint64_t salt) {
  std::uint64_t h = static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ULL ^
                    static_cast<std::uint64_t>(j) * 0xC2B2AE3D27D4EB4FULL ^ salt * 0x165667B19E3779F9ULL;
  h ^= h >> 29U;
  h *= 0xBF58476D1CE4E5B9ULL;
  h ^= h >> 32U;
  return static_cast<double>(h >> 11U) * 0x1.0p-53;
}

struct Tree {
  double x_m, y_m, r_m;
};

/// Trees within radius_m of (x_m, y_m).
std::vector<Tree> treesNear(double x_m, double y_m, double radius_m) {
  std::vector<Tree> trees;
  const auto i0 = static_cast<std::int64_t>(std::floor((x_m - radius_m) / kTreeSpacingM));
  const auto i1 = static_cast<std::int64_t>(std::ceil((x_m + radius_m) / kTreeSpacingM));
  const auto j0 = static_cast<std::int64_t>(std::floor((y_m - radius_m) / kTreeSpacingM));
  const auto j1 = static_cast<std::int64_t>(std::ceil((y_m + radius_m) / kTreeSpacingM));
  for (std::int64_t i = i0; i <= i1; ++i) {
    for (std::int64_t j = j0; j <= j1; ++j) {
      const Tree t{(static_cast<double>(i) + 0.8 * hash01(i, j, 1)) * kTreeSpacingM,
                   (static_cast<double>(j) + 0.8 * hash01(i, j, 2)) * kTreeSpacingM, 0.10 + 0.15 * hash01(i, j, 3)};
      if (std::abs(t.y_m) < 1.0 + t.r_m || t.y_m > kWallYM - t.r_m) continue;
      if (std::hypot(t.x_m - x_m, t.y_m - y_m) <= radius_m) trees.push_back(t);
    }
  }
  return trees;
}

aerotrack::hal::CameraIntrinsics d435Intrinsics(int width_px, int height_px) {
  aerotrack::hal::CameraIntrinsics k;
  k.width_px = width_px;
  k.height_px = height_px;
  k.cx_px = 0.5 * width_px;
  k.cy_px = 0.5 * height_px;
  k.fx_px = k.cx_px / std::tan(0.5 * 87.0 * kPi / 180.0);
  k.fy_px = k.cy_px / std::tan(0.5 * 58.0 * kPi / 180.0);
  return k;
}

/// Camera (OpenCV axes) in body (FLU): z_C = x_B, x_C = -y_B, y_C = -z_B, pitched 10 deg down.
Eigen::Isometry3d cameraInBody() {
  Eigen::Matrix3d R_BC;
  R_BC << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  Eigen::Isometry3d T_BC = Eigen::Isometry3d::Identity();
  T_BC.linear() = Eigen::AngleAxisd(10.0 * kPi / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix() * R_BC;
  T_BC.translation() = Eigen::Vector3d(0.1, 0.0, 0.0);
  return T_BC;
}

Eigen::Isometry3d bodyAt(double x_m) {
  Eigen::Isometry3d T_WB = Eigen::Isometry3d::Identity();
  T_WB.translation() = Eigen::Vector3d(x_m, 0.0, kCameraHeightM);
  return T_WB;
}

/// Renders the pixels (u, v) with u % step == 0 and v % step == 0 into frame.depth_m (others 0).
void render(const Eigen::Isometry3d& T_WC, int step, DepthFrame& frame) {
  const aerotrack::hal::CameraIntrinsics& k = frame.intrinsics;
  frame.depth_m.create(k.height_px, k.width_px, CV_32FC1);
  frame.depth_m.setTo(0.0F);
  const Eigen::Vector3d o = T_WC.translation();
  const std::vector<Tree> trees = treesNear(o.x(), o.y(), kCameraMaxRangeM * 1.3);
  for (int v = 0; v < k.height_px; v += step) {
    for (int u = 0; u < k.width_px; u += step) {
      const Eigen::Vector3d ray_C((u + 0.5 - k.cx_px) / k.fx_px, (v + 0.5 - k.cy_px) / k.fy_px, 1.0);
      const Eigen::Vector3d d = T_WC.linear() * ray_C;  // t along d: camera z = t.
      double t_min = std::numeric_limits<double>::infinity();
      if (d.z() < 0.0) t_min = -o.z() / d.z();
      if (d.y() > 0.0) {
        const double t = (kWallYM - o.y()) / d.y();
        const double z = o.z() + t * d.z();
        if (z >= 0.0 && z <= kWallHeightM) t_min = std::min(t_min, t);
      }
      const double a = d.x() * d.x() + d.y() * d.y();
      for (const Tree& tree : trees) {
        const double ox = o.x() - tree.x_m;
        const double oy = o.y() - tree.y_m;
        const double b = ox * d.x() + oy * d.y();
        const double c = ox * ox + oy * oy - tree.r_m * tree.r_m;
        const double disc = b * b - a * c;
        if (disc < 0.0 || a <= 0.0) continue;
        const double t = (-b - std::sqrt(disc)) / a;
        if (t > 0.0) t_min = std::min(t_min, t);
      }
      frame.depth_m.at<float>(v, u) = t_min <= kCameraMaxRangeM ? static_cast<float>(t_min) : 0.0F;
    }
  }
}

struct Flight {
  Flight(int width_px, int height_px, int decimation) : step(decimation) {
    frame.intrinsics = d435Intrinsics(width_px, height_px);
    frame.T_BC = cameraInBody();
  }
  /// Renders the next frame along the path.
  const DepthFrame& next() {
    x_m += kFlightStepM;
    T_WC = bodyAt(x_m) * frame.T_BC;
    render(T_WC, step, frame);
    return frame;
  }
  int step;
  double x_m = 0.0;
  DepthFrame frame;
  Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();
};

DepthPointsParams depthParams(int decimation, double max_range_m) {
  DepthPointsParams params;
  params.decimation = decimation;
  params.max_range_m = max_range_m;
  return params;
}

/// Forward flight: conversion + insertion of a new frame each iteration into a map that already
/// holds 60 frames (4 m) of the flight. Args: width, height, decimation, max range (dm).
void BM_InsertFlight(benchmark::State& state) {
  const int decimation = static_cast<int>(state.range(2));
  const DepthPointsParams params = depthParams(decimation, static_cast<double>(state.range(3)) / 10.0);
  Flight flight(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)), decimation);
  OctomapMap map = OctomapMap::create().value();
  octomap::Pointcloud hits_W;
  octomap::Pointcloud misses_W;
  const auto insertOne = [&]() {
    const DepthPointsStats points = depthToPoints(flight.frame, flight.T_WC, params, hits_W, misses_W).value();
    const InsertStats stats = map.insert(hits_W, misses_W, flight.T_WC.translation()).value();
    return std::make_pair(points, stats);
  };
  for (int i = 0; i < 60; ++i) {
    flight.next();
    (void)insertOne();
  }
  std::size_t voxels = 0;
  std::size_t saturated = 0;
  std::size_t hits = 0;
  for (auto _ : state) {
    state.PauseTiming();
    flight.next();
    state.ResumeTiming();
    const auto [points, stats] = insertOne();
    voxels += stats.updatedVoxels();
    saturated += stats.saturated_voxels;
    hits += points.hits;
  }
  const auto n = static_cast<double>(state.iterations());
  state.counters["hits"] = static_cast<double>(hits) / n;
  state.counters["voxels"] = static_cast<double>(voxels) / n;
  state.counters["saturated"] = static_cast<double>(saturated) / n;
}
BENCHMARK(BM_InsertFlight)
    ->ArgNames({"w", "h", "dec", "max_dm"})
    ->Args({160, 120, 4, 60})
    ->Args({640, 480, 16, 60})
    ->Args({160, 120, 4, 40})
    ->Args({160, 120, 4, 80})
    ->Args({160, 120, 2, 60})
    ->Args({160, 120, 8, 60})
    ->Unit(benchmark::kMillisecond);

/// Hover: the same frame again and again (most voxels already clamped): the lower bound.
void BM_InsertHover(benchmark::State& state) {
  const DepthPointsParams params = depthParams(4, 6.0);
  Flight flight(160, 120, 4);
  flight.next();
  OctomapMap map = OctomapMap::create().value();
  octomap::Pointcloud hits_W;
  octomap::Pointcloud misses_W;
  for (auto _ : state) {
    (void)depthToPoints(flight.frame, flight.T_WC, params, hits_W, misses_W).value();
    (void)map.insert(hits_W, misses_W, flight.T_WC.translation()).value();
  }
}
BENCHMARK(BM_InsertHover)->Unit(benchmark::kMillisecond);

/// The parts: depthToPoints alone (160 x 120 / 4).
void BM_DepthToPoints(benchmark::State& state) {
  const DepthPointsParams params = depthParams(4, 6.0);
  Flight flight(160, 120, 4);
  flight.next();
  octomap::Pointcloud hits_W;
  octomap::Pointcloud misses_W;
  for (auto _ : state) {
    benchmark::DoNotOptimize(depthToPoints(flight.frame, flight.T_WC, params, hits_W, misses_W).value());
  }
}
BENCHMARK(BM_DepthToPoints)->Unit(benchmark::kMicrosecond);

/// Reference: OctoMap's own OcTree::insertPointCloud (std::unordered_set batching, no early
/// skip) on the same flight, hits with maxrange clipping done by OctoMap (misses as far points).
void BM_OctomapInsertPointCloudReference(benchmark::State& state) {
  const DepthPointsParams params = depthParams(4, 6.0);
  Flight flight(160, 120, 4);
  octomap::OcTree tree(0.1);
  tree.enableChangeDetection(true);
  octomap::Pointcloud hits_W;
  octomap::Pointcloud misses_W;
  const auto insertOne = [&]() {
    (void)depthToPoints(flight.frame, flight.T_WC, params, hits_W, misses_W).value();
    const Eigen::Vector3d o = flight.T_WC.translation();
    const octomap::point3d origin(static_cast<float>(o.x()), static_cast<float>(o.y()), static_cast<float>(o.z()));
    // Misses pushed slightly past max range so that octomap treats them as maxrange rays.
    for (const octomap::point3d& p : misses_W) hits_W.push_back(origin + (p - origin) * 1.01F);
    tree.insertPointCloud(hits_W, origin, 6.0);
    tree.resetChangeDetection();
  };
  for (int i = 0; i < 60; ++i) {
    flight.next();
    insertOne();
  }
  for (auto _ : state) {
    state.PauseTiming();
    flight.next();
    state.ResumeTiming();
    insertOne();
  }
}
BENCHMARK(BM_OctomapInsertPointCloudReference)->Unit(benchmark::kMillisecond);

/// snapshot() of the map after a flight of range(0) frames (x 6.7 cm): its cost grows with the map.
void BM_Snapshot(benchmark::State& state) {
  const DepthPointsParams params = depthParams(4, 6.0);
  Flight flight(160, 120, 4);
  OctomapMap map = OctomapMap::create().value();
  octomap::Pointcloud hits_W;
  octomap::Pointcloud misses_W;
  for (std::int64_t i = 0; i < state.range(0); ++i) {
    flight.next();
    (void)depthToPoints(flight.frame, flight.T_WC, params, hits_W, misses_W).value();
    (void)map.insert(hits_W, misses_W, flight.T_WC.translation()).value();
  }
  for (auto _ : state) benchmark::DoNotOptimize(map.snapshot());
  state.counters["nodes"] = static_cast<double>(map.tree().size());
  state.counters["MB"] = static_cast<double>(map.tree().memoryUsage()) / 1e6;
}
BENCHMARK(BM_Snapshot)->Arg(150)->Arg(1500)->Unit(benchmark::kMillisecond);

}  // namespace
