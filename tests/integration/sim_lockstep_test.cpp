// The whole foundation pipeline in lockstep: config -> devices -> tasks -> executor. The same
// inputs give the same trace and the same final state, bit for bit; the vehicle flies the tour.
#include <gtest/gtest.h>

#include <cstring>

#include "aerotrack/rt/lockstep_executor.hpp"
#include "aerotrack/trajectory_server/min_jerk_tour.hpp"
#include "app_config.hpp"
#include "scenario.hpp"
#include "system.hpp"

namespace aerotrack::app {
namespace {

struct RunResult {
  std::uint64_t trace_hash = 0;
  hal::sim::PointMassTruth truth;
  double mean_error_m = 0;
};

RunResult flyOpenScenario() {
  auto config = loadAppConfig(AEROTRACK_SOURCE_DIR "/config/sim.yaml");
  auto scenario = loadScenario(AEROTRACK_SOURCE_DIR "/config/scenarios/open.yaml");
  EXPECT_TRUE(config && scenario);
  config->sim.start_p_W_m = scenario->drone_start_m;
  auto system = System::build(*config, 0);
  EXPECT_TRUE(system);
  std::vector<Eigen::Vector3d> waypoints{scenario->drone_start_m};
  waypoints.insert(waypoints.end(), scenario->tour_waypoints_m.begin(), scenario->tour_waypoints_m.end());
  auto tour = trajectory_server::MinJerkTour::create(waypoints, 2.0, 2.0);
  EXPECT_TRUE(tour);
  (*system)->channels().trajectories.write(
      std::make_shared<const trajectory_server::TimedTrajectory>(trajectory_server::TimedTrajectory{
          std::make_shared<const trajectory_server::MinJerkTour>(tour.value()), rt::secondsToNs(1.0)}));
  rt::ManualClock clock(0);
  rt::MonotonicClock wall;
  rt::LockstepExecutor executor(clock, wall);
  for (const auto& b : (*system)->bindings()) EXPECT_TRUE(executor.add(b));
  EXPECT_TRUE(executor.runUntil(rt::secondsToNs(scenario->duration_s)));
  return {executor.traceHash(), (*system)->devices().world->truth(),
          (*system)->devices().world->trackingStats().meanErrorM()};
}

TEST(SimLockstep, GivenSameInputsWhenRunTwiceThenBitIdentical) {
  const RunResult a = flyOpenScenario();
  const RunResult b = flyOpenScenario();
  EXPECT_EQ(a.trace_hash, b.trace_hash);
  EXPECT_EQ(std::memcmp(a.truth.p_W_m.data(), b.truth.p_W_m.data(), sizeof(double) * 3), 0);
  EXPECT_EQ(std::memcmp(a.truth.v_W_mps.data(), b.truth.v_W_mps.data(), sizeof(double) * 3), 0);
  EXPECT_EQ(a.mean_error_m, b.mean_error_m);
}

TEST(SimLockstep, GivenTourThenVehicleTracksItAndEndsAtTheLastWaypoint) {
  const RunResult r = flyOpenScenario();
  EXPECT_LT((r.truth.p_W_m - Eigen::Vector3d(0, 0, 1.5)).norm(), 0.01);
  EXPECT_LT(r.mean_error_m, 0.05);  // feed-forward + PD at 100 Hz setpoints follows closely
}

}  // namespace
}  // namespace aerotrack::app
