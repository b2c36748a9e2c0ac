// The simulator's own speed (issue 3: at least 50x real time on one core in lockstep, keypoint
// mode, depth at 15 Hz, planner and detector excluded): a Simulation stepped at 200 Hz through
// a whole scenario with the baseline follower supplying setpoints, nothing else. The counter
// realtime_factor is simulated seconds per wall second.
#include <benchmark/benchmark.h>

#include <chrono>

#include "aerotrack/hal/sim/baseline_follower.hpp"
#include "aerotrack/hal/sim/simulation.hpp"

namespace {

using namespace aerotrack;

void BM_SimulationRealtimeFactor(benchmark::State& state, const std::string& scenario, bool depth) {
  auto spec = hal::sim::loadScenarioSpec(AEROTRACK_SOURCE_DIR "/config/scenarios/" + scenario + ".yaml");
  if (!spec) {
    state.SkipWithError(spec.error().message.c_str());
    return;
  }
  double simulated_s = 0.0, wall_s = 0.0;
  std::uint64_t seed = 1;
  for (auto _ : state) {
    auto trial = hal::sim::instantiate(*spec, seed++);
    hal::sim::SimulationOptions options;
    options.render_depth = depth;
    auto sim = hal::sim::Simulation::create(*trial, options, 0);
    hal::sim::BaselineFollower follower({}, trial->spec.drone.start_m, trial->spec.drone.start_yaw_rad);
    const rt::TimeNs end_ns = rt::secondsToNs(trial->duration_s);
    const auto begin = std::chrono::steady_clock::now();
    for (rt::TimeNs t = 0; t <= end_ns; t += 5'000'000) {  // 200 Hz
      (*sim)->step(t);
      const auto command = follower.update(*(*sim)->truthOut().read(), t);
      (*sim)->setpointInbox().write(command.setpoint);
      (*sim)->gimbalInbox().write(command.gimbal);
      while ((*sim)->detectionsOut().try_pop()) {
      }
    }
    wall_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
    simulated_s += trial->duration_s;
  }
  state.counters["realtime_factor"] = simulated_s / wall_s;
}

BENCHMARK_CAPTURE(BM_SimulationRealtimeFactor, forest_depth15hz, "forest", true)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);
BENCHMARK_CAPTURE(BM_SimulationRealtimeFactor, sharp_turn_depth15hz, "sharp_turn", true)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);
BENCHMARK_CAPTURE(BM_SimulationRealtimeFactor, corridor_depth15hz, "corridor", true)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);
BENCHMARK_CAPTURE(BM_SimulationRealtimeFactor, forest_no_depth, "forest", false)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);
// Bystanders (issue 20): crowd has 13 (a milling group of 5, 6 random walkers, a crosser, a
// look-alike), crossing 6; each is observed, occludes and is rendered into the depth frames.
BENCHMARK_CAPTURE(BM_SimulationRealtimeFactor, crowd_depth15hz, "crowd", true)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);
BENCHMARK_CAPTURE(BM_SimulationRealtimeFactor, crossing_depth15hz, "crossing", true)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);

}  // namespace
