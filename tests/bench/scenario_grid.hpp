// Shared by the planning benchmarks (planning_search_bench.cpp, planning_corridor_bench.cpp): a LocalGrid
// built from the obstacles of a scenario (every 0.1 m cell whose centre lies in a box or cylinder is
// occupied; inflation 0.25 m, the drone's radius; no ground; a 20 x 20 x 5 m window) and 256 seeded
// queries in it: start/goal pairs 3-8 m apart at 1-2 m altitude, free in the inflated grid, random
// horizontal velocities up to 1.5 m/s, the person 2.5 m beyond the goal. Also the thread's CPU clock (the
// machines are shared: wall time includes other processes' slices). Benchmarks only: throws on failure.
#pragma once

#include <octomap/OcTree.h>

#include <cmath>
#include <ctime>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "aerotrack/hal/sim/scenario.hpp"
#include "aerotrack/mapping/local_grid.hpp"
#include "aerotrack/planning/kinodynamic_search.hpp"

namespace aerotrack::bench {

/// CPU time of this thread, milliseconds.
inline double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

struct Query {
  planning::KinematicState start;
  planning::KinematicState goal;
  Eigen::Vector3d person_W_m;
};

struct World {
  mapping::LocalGrid grid;
  std::vector<Query> queries;
};

/// The grid of config/scenarios/<scenario>.yaml (seed 1) with its window centred on center_W_m, and the
/// queries (seed 42) in it.
inline World makeWorld(const std::string& scenario, const Eigen::Vector3d& center_W_m) {
  auto spec = hal::sim::loadScenarioSpec(AEROTRACK_SOURCE_DIR "/config/scenarios/" + scenario + ".yaml");
  if (!spec) throw std::runtime_error(spec.error().message);
  auto instance = hal::sim::instantiate(*spec, 1);
  if (!instance) throw std::runtime_error(instance.error().message);
  mapping::LocalGridParams params;
  params.resolution_m = 0.1;
  params.size_m = Eigen::Vector3d(20.0, 20.0, 5.0);
  params.inflation_radius_m = 0.25;
  params.recenter_distance_m = 0.0;
  octomap::OcTree tree(params.resolution_m);
  const double r = params.resolution_m;
  const auto mark = [&](const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const auto& inside) {
    const Eigen::Vector3d window_lo = center_W_m - 0.5 * params.size_m - Eigen::Vector3d::Constant(1.0);
    const Eigen::Vector3d window_hi = center_W_m + 0.5 * params.size_m + Eigen::Vector3d::Constant(1.0);
    const Eigen::Vector3i a = (lo.cwiseMax(window_lo) / r).array().floor().cast<int>();
    const Eigen::Vector3i b = (hi.cwiseMin(window_hi) / r).array().ceil().cast<int>();
    for (int z = a.z(); z < b.z(); ++z) {
      for (int y = a.y(); y < b.y(); ++y) {
        for (int x = a.x(); x < b.x(); ++x) {
          const Eigen::Vector3d c = (Eigen::Vector3d(x, y, z).array() + 0.5) * r;
          if (inside(c)) tree.setNodeValue(octomap::point3d(float(c.x()), float(c.y()), float(c.z())), 2.0f);
        }
      }
    }
  };
  for (const auto& box : instance->spec.boxes) {
    mark(box.min_W_m, box.max_W_m, [&](const Eigen::Vector3d& c) {
      return (c.array() >= box.min_W_m.array()).all() && (c.array() <= box.max_W_m.array()).all();
    });
  }
  for (const auto& cyl : instance->spec.cylinders) {
    const Eigen::Vector3d lo(cyl.center_W_m.x() - cyl.radius_m, cyl.center_W_m.y() - cyl.radius_m, cyl.z_min_m);
    const Eigen::Vector3d hi(cyl.center_W_m.x() + cyl.radius_m, cyl.center_W_m.y() + cyl.radius_m, cyl.z_max_m);
    mark(lo, hi, [&](const Eigen::Vector3d& c) {
      return (c.head<2>() - cyl.center_W_m).norm() <= cyl.radius_m && c.z() >= cyl.z_min_m && c.z() <= cyl.z_max_m;
    });
  }
  auto grid = mapping::LocalGrid::create(params);
  if (!grid) throw std::runtime_error(grid.error().message);
  if (!grid->recenter(center_W_m, tree) || !grid->rebuild(tree)) throw std::runtime_error("grid build failed");
  World world{std::move(grid).value(), {}};

  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> x(center_W_m.x() - 8.0, center_W_m.x() + 8.0);
  std::uniform_real_distribution<double> y(center_W_m.y() - 8.0, center_W_m.y() + 8.0);
  std::uniform_real_distribution<double> z(1.0, 2.0);
  std::uniform_real_distribution<double> distance(3.0, 8.0);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  std::uniform_real_distribution<double> speed(-1.5, 1.5);
  const auto usable = [&](const Eigen::Vector3d& p) {
    return (p.head<2>() - center_W_m.head<2>()).cwiseAbs().maxCoeff() < 9.0 && !world.grid.isOccupied(p);
  };
  while (world.queries.size() < 256) {
    Query q;
    q.start.p_W_m = Eigen::Vector3d(x(rng), y(rng), z(rng));
    const double heading = angle(rng);
    const Eigen::Vector3d direction(std::cos(heading), std::sin(heading), 0.0);
    q.goal.p_W_m = q.start.p_W_m + distance(rng) * direction;
    q.goal.p_W_m.z() = z(rng);
    if (!usable(q.start.p_W_m) || !usable(q.goal.p_W_m)) continue;
    q.start.v_W_mps = Eigen::Vector3d(speed(rng), speed(rng), 0.0);
    q.goal.v_W_mps = Eigen::Vector3d(speed(rng), speed(rng), 0.0);
    q.person_W_m = q.goal.p_W_m + 2.5 * direction;
    world.queries.push_back(q);
  }
  return world;
}

}  // namespace aerotrack::bench
