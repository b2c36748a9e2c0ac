// The target pipeline in the closed loop (issue 6): the simulator's keypoint camera (MoveNet-like
// noise, misses, 40 ms latency), the localization regression shipped in config/localization.yaml,
// camera to world at each capture time, and the Kalman filter; its estimate is compared with the
// person's true position and velocity while they walk (the target_check task). The issue's
// targets: mean position error <= 0.10 m, velocity error <= 0.3 m/s, walking at 1.5 m/s. The depth camera sees
// the person (issue 22): it ranges most of their frames, and the map holds no trace of them.
#include <gtest/gtest.h>

#include <octomap/OcTree.h>

#include "aerotrack/hal/sim/bystanders.hpp"
#include "aerotrack/rt/lockstep_executor.hpp"
#include "app_config.hpp"
#include "device_tasks.hpp"
#include "sim_report.hpp"
#include "support/require.hpp"
#include "system.hpp"

namespace aerotrack::app {
namespace {

struct TrackedRun {
  nlohmann::json estimation;
  double visible_ratio = 0.0;  ///< The share of the time the person could be seen (the simulator's truth).
  /// Occupied voxels, at body height, within the person's body radius of where they walked.
  std::size_t voxels_on_the_persons_path = 0;
};

/// The occupied leaves of the map between 0.3 and 1.6 m high whose centres lie within `radius_m` (horizontally)
/// of the person's true position at some tenth of a second of the run.
std::size_t occupiedOnPath(const octomap::OcTree& tree, const hal::sim::Simulation& sim, rt::TimeNs end_ns,
                           double radius_m) {
  std::vector<Eigen::Vector2d> path;
  for (rt::TimeNs t = sim.startNs(); t <= end_ns; t += rt::secondsToNs(0.1))
    path.push_back(sim.personAt(t).p_W_m.head<2>());
  std::size_t count = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (!tree.isNodeOccupied(*it) || it.getZ() < 0.3 || it.getZ() > 1.6) continue;
    const Eigen::Vector2d c(it.getX(), it.getY());
    for (const Eigen::Vector2d& p : path) {
      if ((c - p).norm() < radius_m) {
        ++count;
        break;
      }
    }
  }
  return count;
}

/// Fails the calling test (test::require) if the config, the trial, the system, its target task or
/// its simulation is missing.
TrackedRun estimationOf(const std::string& scenario, std::uint64_t seed, double speed_mps) {
  const AppConfig config =
      aerotrack::test::require(loadAppConfig(AEROTRACK_SOURCE_DIR "/config/sim.yaml"), "config/sim.yaml");
  const hal::sim::ScenarioInstance trial = aerotrack::test::require(
      loadTrial(AEROTRACK_SOURCE_DIR "/config/scenarios/" + scenario + ".yaml", seed, speed_mps), scenario);
  const std::unique_ptr<System> system = aerotrack::test::require(System::build(config, &trial, 0), "the system");
  rt::ManualClock clock(0);
  rt::MonotonicClock wall;
  rt::LockstepExecutor executor(clock, wall);
  for (const auto& b : system->bindings()) EXPECT_TRUE(executor.add(b));
  EXPECT_TRUE(executor.runUntil(rt::secondsToNs(trial.duration_s)));
  const estimation::TargetTask& target = aerotrack::test::require(system->targetTask(), "the target task");
  const hal::sim::Simulation& sim = aerotrack::test::require(system->devices().simulation.get(), "the simulation");
  const mapping::MappingTask& mapping = aerotrack::test::require(system->mappingTask(), "the mapping task");
  return {estimationSummary(&target, system->targetCheckTask()), sim.metrics().visibleRatio(),
          occupiedOnPath(mapping.mapper().octomap().tree(), sim, clock.now(), hal::sim::kPersonBodyRadiusM)};
}

class TargetEstimation : public ::testing::TestWithParam<std::uint64_t> {};

TEST_P(TargetEstimation, GivenSharpTurnAt1p5MpsWhenTrackedThenTheEstimateMeetsTheAccuracyTargets) {
  const TrackedRun run = estimationOf("sharp_turn", GetParam(), 1.5);
  const nlohmann::json& e = run.estimation;
  std::printf("seed %llu: visible %.4f, %s\n", static_cast<unsigned long long>(GetParam()), run.visible_ratio,
              e.dump().c_str());
  ASSERT_FALSE(e.is_null());
  EXPECT_GT(e["accepted"].get<int>(), 500);
  // Live whenever the person can be seen: the corner of the building hides them for a second or two at
  // the turn (the path keeps 0.9 m from the wall), and a loss is declared lost_after_s after the last
  // detection, so the live share may trail the visible share by a little.
  EXPECT_GT(e["live_ratio"].get<double>(), run.visible_ratio - 0.03);
  EXPECT_LE(e["position_error_mean_m"].get<double>(), 0.10);
  EXPECT_LE(e["velocity_error_mean_mps"].get<double>(), 0.30);
  // The depth camera faces where the drone flies, after the person: most of their frames are ranged by it.
  EXPECT_GT(e["depth_ranged"].get<double>(), 0.5 * e["detections"].get<double>());
  // Their body is in the depth images but never in the map (mapping.exclude_target).
  std::printf("occupied voxels on the person's path: %zu\n", run.voxels_on_the_persons_path);
  EXPECT_EQ(run.voxels_on_the_persons_path, 0U);
}

INSTANTIATE_TEST_SUITE_P(Seeds, TargetEstimation, ::testing::Values(1, 2, 3));

}  // namespace
}  // namespace aerotrack::app
