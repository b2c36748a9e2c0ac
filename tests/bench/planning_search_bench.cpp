// Speed of the occlusion-aware kinodynamic search (modules/planning/search, issue 7: <= 2 ms median and
// <= 8 ms at the 99th percentile on one core) in LocalGrids built from the obstacles of the `forest` and
// `sharp_turn` scenarios (scenario_grid.hpp: every 0.1 m cell whose centre lies in a box or cylinder is
// occupied; inflation 0.25 m, the drone's radius; no ground). Queries (scenario_grid.hpp): 256 seeded
// start/goal pairs 3-8 m apart at 1-2 m altitude, free in the inflated grid, random horizontal velocities
// up to 1.5 m/s, the person 2.5 m beyond the goal. Each iteration runs one query; the counters give the
// median and 99th percentile (p50_ms, p99_ms, of thread CPU time) over all iterations, and how the searches
// ended.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <string>
#include <vector>

#include "aerotrack/planning/kinodynamic_search.hpp"
#include "scenario_grid.hpp"

namespace {

using aerotrack::bench::makeWorld;
using aerotrack::bench::Query;
using aerotrack::bench::threadCpuMs;
using aerotrack::bench::World;
using aerotrack::planning::KinodynamicSearch;
using aerotrack::planning::KinodynamicSearchParams;
using aerotrack::planning::SearchPath;
using aerotrack::planning::SearchStatus;

void runSearch(benchmark::State& state, const std::string& scenario, const Eigen::Vector3d& center_W_m,
               bool occlusion_aware) {
  const World world = makeWorld(scenario, center_W_m);
  KinodynamicSearchParams params;
  params.occlusion_aware = occlusion_aware;
  auto search = KinodynamicSearch::create(params);
  if (!search) throw std::runtime_error(search.error().message);
  SearchPath path;
  std::vector<double> times_ms;
  std::size_t next = 0;
  int reached = 0;
  int partial = 0;
  long expansions = 0;
  for (auto _ : state) {
    const Query& q = world.queries[next++ % world.queries.size()];
    const aerotrack::planning::PersonPositionFn person = [&q](double /*t_s*/) { return q.person_W_m; };
    const double t0_ms = threadCpuMs();
    const SearchStatus status = search->search(world.grid, q.start, q.goal, 0.0, person, path);
    const double t1_ms = threadCpuMs();
    benchmark::DoNotOptimize(path.cost);
    times_ms.push_back(t1_ms - t0_ms);
    reached += status == SearchStatus::kReachedGoal ? 1 : 0;
    partial += status == SearchStatus::kPartial ? 1 : 0;
    expansions += path.expansions;
  }
  std::sort(times_ms.begin(), times_ms.end());
  const auto quantile = [&](double p) {
    return times_ms[std::min(times_ms.size() - 1, static_cast<std::size_t>(p * static_cast<double>(times_ms.size())))];
  };
  const double n = static_cast<double>(times_ms.size());
  state.counters["p50_ms"] = quantile(0.5);
  state.counters["p99_ms"] = quantile(0.99);
  state.counters["max_ms"] = times_ms.back();
  state.counters["reached"] = reached / n;
  state.counters["partial"] = partial / n;
  state.counters["expansions"] = static_cast<double>(expansions) / n;
}

void searchForest(benchmark::State& state) {
  runSearch(state, "forest", Eigen::Vector3d(0.0, 0.0, 2.5), true);
}
void searchForestBaseline(benchmark::State& state) {
  runSearch(state, "forest", Eigen::Vector3d(0.0, 0.0, 2.5), false);
}
void searchSharpTurn(benchmark::State& state) {
  runSearch(state, "sharp_turn", Eigen::Vector3d(14.0, 2.0, 2.5), true);
}
void searchSharpTurnBaseline(benchmark::State& state) {
  runSearch(state, "sharp_turn", Eigen::Vector3d(14.0, 2.0, 2.5), false);
}

}  // namespace

BENCHMARK(searchForest)->Unit(benchmark::kMillisecond)->Iterations(1024);
BENCHMARK(searchForestBaseline)->Unit(benchmark::kMillisecond)->Iterations(1024);
BENCHMARK(searchSharpTurn)->Unit(benchmark::kMillisecond)->Iterations(1024);
BENCHMARK(searchSharpTurnBaseline)->Unit(benchmark::kMillisecond)->Iterations(1024);
