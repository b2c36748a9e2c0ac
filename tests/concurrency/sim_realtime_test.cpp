// The simulator on threads: the whole sim configuration on the real-time executor, one thread per
// task, for a second and a half of wall time; and in lockstep, where the mapping task's work runs on
// the executor's worker thread (its latency_ms) while the other tasks go on. Run under
// ThreadSanitizer by scripts/check.sh, they check that the sim devices' channels are the only state
// shared between threads.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include <chrono>
#include <thread>

#include "aerotrack/rt/lockstep_executor.hpp"
#include "aerotrack/rt/realtime_executor.hpp"
#include "app_config.hpp"
#include "sim_report.hpp"
#include "support/require.hpp"
#include "support/sanitizers.hpp"
#include "system.hpp"

namespace aerotrack::app {
namespace {

TEST(SimRealtime, GivenSimConfigOnThreadsThenEveryTaskRunsAndTheDroneTakesOff) {
  auto config = loadAppConfig(AEROTRACK_SOURCE_DIR "/config/sim.yaml");
  ASSERT_TRUE(config);
  config->realtime.use_realtime_priority = false;
  config->realtime.lock_memory = false;
#if defined(AEROTRACK_TEST_ASAN) || defined(AEROTRACK_TEST_TSAN)
  // Sanitizers slow every thread 5-15x on threads that run in real time: the odometry then arrives
  // later than the supervisor's 0.2 s failsafe allows and the drone is (rightly) held on the ground.
  // This test is about the threads, not the failsafes (tested in lockstep), so give them room.
  if (config->supervisor) {
    config->supervisor->odometry_timeout_s *= 10.0;
    config->supervisor->depth_timeout_s *= 10.0;
    config->supervisor->camera_timeout_s *= 10.0;
    config->supervisor->gimbal_timeout_s *= 10.0;
    config->supervisor->startup_grace_s *= 10.0;
  }
#endif
  auto trial = loadTrial(AEROTRACK_SOURCE_DIR "/tests/data/short.yaml", 1, std::nullopt);
  ASSERT_TRUE(trial) << trial.error().message;
  const rt::MonotonicClock clock;
  auto system = System::build(*config, &trial.value(), clock.now());
  ASSERT_TRUE(system) << system.error().message;
  rt::RealtimeExecutor executor(clock, config->realtime);
  for (const auto& b : (*system)->bindings()) ASSERT_TRUE(executor.add(b));
  ASSERT_TRUE(executor.start());
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  executor.requestStop();
  executor.join();
  for (const auto& s : executor.stats()) EXPECT_GT(s.stats->snapshot().runs, 5U) << s.name;
  const hal::sim::Simulation& sim = *(*system)->devices().simulation;
  EXPECT_GT(sim.truth().drone.p_W_m.z(), 0.3);  // climbing towards 1.5 m
  EXPECT_EQ(sim.metrics().collisions(), 0);
  EXPECT_GT((*system)->channels().odometry.version(), 50U);
  EXPECT_GT((*system)->channels().depth.version(), 5U);
  // The control tasks keep their budgets: overruns (runs longer than budget_ms) within 5 % of their
  // runs. Not under sanitizers, whose instrumentation multiplies execution times.
#if !defined(AEROTRACK_TEST_ASAN) && !defined(AEROTRACK_TEST_TSAN)
  for (const auto& s : executor.stats()) {
    const std::string name = s.name;
    if (name != "gimbal_control" && name != "trajectory_server" && name != "supervisor" && name != "gimbal" &&
        name != "odometry")
      continue;
    const rt::TimingSnapshot t = s.stats->snapshot();
    std::printf("%-18s runs %llu overruns %llu\n", name.c_str(), static_cast<unsigned long long>(t.runs),
                static_cast<unsigned long long>(t.overruns));
    EXPECT_LE(static_cast<double>(t.overruns), 0.05 * static_cast<double>(t.runs)) << name;
  }
#endif
}

/// Lockstep run of the short trial with the sim configuration: the trace hash and the drone's height.
/// Fails the calling test (test::require) if the trial, the system or its simulation is missing.
std::pair<std::uint64_t, double> runLockstep(const AppConfig& config) {
  const hal::sim::ScenarioInstance trial = aerotrack::test::require(
      loadTrial(AEROTRACK_SOURCE_DIR "/tests/data/short.yaml", 1, std::nullopt), "tests/data/short.yaml");
  rt::ManualClock clock(0);
  const rt::MonotonicClock wall;
  const std::unique_ptr<System> system =
      aerotrack::test::require(System::build(config, &trial, clock.now()), "the system");
  rt::LockstepExecutor executor(clock, wall);
  for (const auto& b : system->bindings()) EXPECT_TRUE(executor.add(b));
  EXPECT_TRUE(executor.runUntil(3 * rt::kNsPerSecond));
  const hal::sim::Simulation& sim = aerotrack::test::require(system->devices().simulation.get(), "the simulation");
  return {executor.traceHash(), sim.truth().drone.p_W_m.z()};
}

TEST(SimLockstep, GivenMappingOverlappedOnTheWorkerThreadThenTwoRunsAreIdentical) {
  auto config = loadAppConfig(AEROTRACK_SOURCE_DIR "/config/sim.yaml");
  ASSERT_TRUE(config);
  bool overlapped = false;
  for (const rt::TaskSpec& t : config->tasks) overlapped |= t.name == "mapping" && t.latency_ms > 0.0;
  ASSERT_TRUE(overlapped) << "config/sim.yaml no longer overlaps the mapping task";
  const auto a = runLockstep(*config);
  const auto b = runLockstep(*config);
  EXPECT_EQ(a.first, b.first);
  EXPECT_EQ(a.second, b.second);
  EXPECT_GT(a.second, 0.3);  // climbing towards 1.5 m
}

}  // namespace
}  // namespace aerotrack::app
