// Concurrency test of ObstacleWorld (hal/sim/world): its const queries are thread-safe (no
// mutable state). Several threads query one world at once and must get exactly the results of a
// single-threaded pass; run under TSan (label concurrency) to catch data races.
#include <functional>
#include <random>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "aerotrack/hal/sim/obstacle_world.hpp"

namespace aerotrack::hal::sim {
namespace {

TEST(ObstacleWorldConcurrency, GivenFourThreadsQueryingOneWorldThenSameResultsAsOneThread) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> xy(-20.0, 20.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Cylinder> trees;
  for (int i = 0; i < 150; ++i) trees.push_back(Cylinder{Eigen::Vector2d(xy(rng), xy(rng)), 0.3, 0.0, 5.0});
  std::vector<Box> walls{Box{Eigen::Vector3d(-5, -5, 0), Eigen::Vector3d(5, -4.8, 3)}};
  auto created = ObstacleWorld::create(std::move(walls), std::move(trees));
  ASSERT_TRUE(created.has_value());
  const ObstacleWorld& world = created.value();

  constexpr int kQueries = 20000;
  std::vector<Eigen::Vector3d> origins;
  std::vector<Eigen::Vector3d> dirs;
  for (int i = 0; i < kQueries; ++i) {
    origins.emplace_back(xy(rng), xy(rng), 3.0 * unit(rng));
    dirs.push_back(Eigen::Vector3d(unit(rng) - 0.5, unit(rng) - 0.5, 0.2 * (unit(rng) - 0.5)).normalized());
  }
  const auto run = [&](std::vector<double>& out) {
    out.resize(3 * kQueries);
    for (int i = 0; i < kQueries; ++i) {
      const auto hit = world.raycast(origins[i], dirs[i], 15.0, true);
      out[3 * i] = hit.value_or(-1.0);
      out[3 * i + 1] = world.distance(origins[i]);
      out[3 * i + 2] = world.segmentClear(origins[i], origins[i] + 8.0 * dirs[i]) ? 1.0 : 0.0;
    }
  };
  std::vector<double> expected;
  run(expected);
  std::vector<std::vector<double>> results(4);
  std::vector<std::thread> threads;
  for (auto& result : results) threads.emplace_back(run, std::ref(result));
  for (auto& thread : threads) thread.join();
  for (const auto& result : results) EXPECT_EQ(result, expected);
}

}  // namespace
}  // namespace aerotrack::hal::sim
