// The whole pipeline on the sim HAL in lockstep: config -> devices -> tasks -> executor. The same
// seed gives the same run bit for bit; every built-in scenario runs; the baseline follower keeps
// a walking person in an open field in sight without collision.
#include <gtest/gtest.h>

#include "aerotrack/rt/lockstep_executor.hpp"
#include "app_config.hpp"
#include "sim_report.hpp"
#include "support/require.hpp"
#include "system.hpp"

namespace aerotrack::app {
namespace {

struct Outcome {
  std::uint64_t trace_hash = 0;
  nlohmann::json summary;
  Eigen::Vector3d drone_m = Eigen::Vector3d::Zero();
};

/// Fails the calling test (test::require) if the config, the trial or the system cannot be made.
Outcome fly(const std::string& scenario, std::uint64_t seed, double max_sim_s) {
  const AppConfig config =
      aerotrack::test::require(loadAppConfig(AEROTRACK_SOURCE_DIR "/config/sim.yaml"), "config/sim.yaml");
  const hal::sim::ScenarioInstance trial = aerotrack::test::require(
      loadTrial(AEROTRACK_SOURCE_DIR "/config/scenarios/" + scenario + ".yaml", seed, std::nullopt), scenario);
  const std::unique_ptr<System> system = aerotrack::test::require(System::build(config, &trial, 0), "the system");
  rt::ManualClock clock(0);
  rt::MonotonicClock wall;
  rt::LockstepExecutor executor(clock, wall);
  for (const auto& b : system->bindings()) EXPECT_TRUE(executor.add(b));
  EXPECT_TRUE(executor.runUntil(rt::secondsToNs(std::min(max_sim_s, trial.duration_s))));
  const hal::sim::Simulation& sim = aerotrack::test::require(system->devices().simulation.get(), "the simulation");
  RunInfo info;  // no timings: they are wall-clock measurements and differ between runs
  info.sim_time_s = rt::nsToSeconds(clock.now());
  info.latency = latencySummary(system->trajectoryServerTask());  // simulated time: deterministic
  return {executor.traceHash(), simSummary(sim, info), sim.truth().drone.p_W_m};
}

TEST(SimLockstep, GivenSameSeedWhenRunTwiceThenSummariesAreIdentical) {
  const Outcome a = fly("sharp_turn", 3, 20.0);
  const Outcome b = fly("sharp_turn", 3, 20.0);
  EXPECT_EQ(a.trace_hash, b.trace_hash);
  EXPECT_EQ(a.summary.dump(), b.summary.dump());
  EXPECT_EQ(a.drone_m, b.drone_m);  // bit for bit
  const Outcome c = fly("sharp_turn", 4, 20.0);
  EXPECT_NE(a.summary.dump(), c.summary.dump());
}

// Issue 21 item 4: image capture to the first setpoint from the plan that used it, in simulated time
// (deterministic, so a fixed bound is safe here; the real-time executor's number is measured, not
// tested: docs/benchmarks.md). The camera's 40 ms delivery, the detection at once to the target task,
// the new estimate at once to the planner, an 8 ms hand-over: the paper's 60 ms median.
TEST(SimLockstep, GivenTheShippedConfigThenCaptureToFirstSetpointMedianIsWithinThePapers60Ms) {
  const Outcome o = fly("sharp_turn", 1, 20.0);
  const nlohmann::json& latency = o.summary["latency"];
  ASSERT_GT(latency["samples"].get<int>(), 300);  // ~30 plans a second from 1 s on
  EXPECT_LE(latency["capture_to_setpoint_ms_p50"].get<double>(), 60.0);
  EXPECT_GE(latency["capture_to_setpoint_ms_p50"].get<double>(), 48.0);  // no faster than delivery + hand-over
  EXPECT_LE(latency["capture_to_setpoint_ms_p99"].get<double>(), 130.0);
}

class EveryScenario : public ::testing::TestWithParam<std::string> {};

TEST_P(EveryScenario, RunsForSecondsWithTheDroneAirborneAndUnharmed) {
  const Outcome o = fly(GetParam(), 1, 8.0);
  EXPECT_EQ(o.summary["collisions"], 0);
  EXPECT_GT(o.drone_m.z(), 1.0);  // took off towards 1.5 m
}

INSTANTIATE_TEST_SUITE_P(Scenarios, EveryScenario,
                         ::testing::Values("sharp_turn", "forest", "corridor", "open", "runner", "drift", "windy"));

TEST(SimLockstep, GivenOpenFieldThenBaselineFollowerTracksThePersonToTheEnd) {
  const Outcome o = fly("open", 2, 1000.0);
  EXPECT_TRUE(o.summary["success"].get<bool>()) << o.summary.dump(2);
  EXPECT_GT(o.summary["visible_ratio"].get<double>(), 0.9);
  EXPECT_LT(o.summary["distance_mean_m"].get<double>(), 3.5);
}

}  // namespace
}  // namespace aerotrack::app
