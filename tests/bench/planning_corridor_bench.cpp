// Speed of the flight corridor (modules/planning/corridor, issue 8 item 1: well under 0.5 ms per build, as
// it runs inside a 3 ms planning cycle at 20 Hz) in the LocalGrids of the `forest` and `sharp_turn`
// scenarios with the search benchmark's 256 seeded queries (scenario_grid.hpp). Each query is searched
// once during set-up (occlusion-aware, default parameters) and its path sampled every 20 ms into a
// polyline; each iteration then builds the corridor of one polyline, and only the build is timed. The
// counters give the median, 99th percentile and maximum (p50_us, p99_us, max_us, of thread CPU time) over
// all iterations, the boxes per corridor (mean and max), the path length and the fraction of builds that
// failed.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "aerotrack/planning/corridor.hpp"
#include "aerotrack/planning/kinodynamic_search.hpp"
#include "scenario_grid.hpp"

namespace {

using aerotrack::bench::makeWorld;
using aerotrack::bench::Query;
using aerotrack::bench::threadCpuMs;
using aerotrack::bench::World;
using aerotrack::planning::Corridor;
using aerotrack::planning::CorridorBuilder;
using aerotrack::planning::CorridorParams;
using aerotrack::planning::KinodynamicSearch;
using aerotrack::planning::KinodynamicSearchParams;
using aerotrack::planning::SearchPath;
using aerotrack::planning::SearchStatus;

constexpr double kSampleS = 0.02;  // the search path is sampled every 20 ms into the polyline

void runCorridor(benchmark::State& state, const std::string& scenario, const Eigen::Vector3d& center_W_m) {
  const World world = makeWorld(scenario, center_W_m);
  auto search = KinodynamicSearch::create(KinodynamicSearchParams{});
  if (!search) throw std::runtime_error(search.error().message);
  std::vector<std::vector<Eigen::Vector3d>> polylines;
  double length_m = 0.0;
  SearchPath path;
  for (const Query& q : world.queries) {
    const aerotrack::planning::PersonPositionFn person = [&q](double /*t_s*/) { return q.person_W_m; };
    const SearchStatus status = search->search(world.grid, q.start, q.goal, 0.0, person, path);
    if (status != SearchStatus::kReachedGoal && status != SearchStatus::kPartial) continue;
    std::vector<Eigen::Vector3d>& polyline = polylines.emplace_back();
    const int n = std::max(1, static_cast<int>(std::ceil(path.duration_s / kSampleS)));
    for (int i = 0; i <= n; ++i) polyline.push_back(path.stateAt(path.duration_s * i / n).p_W_m);
    for (std::size_t k = 1; k < polyline.size(); ++k) length_m += (polyline[k] - polyline[k - 1]).norm();
  }
  if (polylines.empty()) throw std::runtime_error("no search path");

  auto builder = CorridorBuilder::create(CorridorParams{});
  if (!builder) throw std::runtime_error(builder.error().message);
  Corridor corridor;
  std::vector<double> times_us;
  times_us.reserve(static_cast<std::size_t>(state.max_iterations));
  std::size_t next = 0;
  long boxes = 0;
  std::size_t max_boxes = 0;
  int failed = 0;
  for (auto _ : state) {
    const std::vector<Eigen::Vector3d>& polyline = polylines[next++ % polylines.size()];
    const double t0_ms = threadCpuMs();
    const bool ok = builder->build(world.grid, polyline, corridor).has_value();
    const double t1_ms = threadCpuMs();
    benchmark::DoNotOptimize(corridor.boxes.data());
    times_us.push_back((t1_ms - t0_ms) * 1e3);
    failed += ok ? 0 : 1;
    boxes += static_cast<long>(corridor.boxes.size());
    max_boxes = std::max(max_boxes, corridor.boxes.size());
  }
  std::sort(times_us.begin(), times_us.end());
  const auto quantile = [&](double p) {
    return times_us[std::min(times_us.size() - 1, static_cast<std::size_t>(p * static_cast<double>(times_us.size())))];
  };
  const double n = static_cast<double>(times_us.size());
  state.counters["p50_us"] = quantile(0.5);
  state.counters["p99_us"] = quantile(0.99);
  state.counters["max_us"] = times_us.back();
  state.counters["boxes"] = static_cast<double>(boxes) / std::max(1.0, n - failed);
  state.counters["max_boxes"] = static_cast<double>(max_boxes);
  state.counters["path_m"] = length_m / static_cast<double>(polylines.size());
  state.counters["failed"] = failed / n;
}

void corridorForest(benchmark::State& state) {
  runCorridor(state, "forest", Eigen::Vector3d(0.0, 0.0, 2.5));
}
void corridorSharpTurn(benchmark::State& state) {
  runCorridor(state, "sharp_turn", Eigen::Vector3d(14.0, 2.0, 2.5));
}

}  // namespace

BENCHMARK(corridorForest)->Unit(benchmark::kMicrosecond)->Iterations(2048);
BENCHMARK(corridorSharpTurn)->Unit(benchmark::kMicrosecond)->Iterations(2048);
