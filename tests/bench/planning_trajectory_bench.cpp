// Speed of the trajectory optimiser (modules/planning/trajectory, issue 8): one evaluation of the cost
// and its gradient for 10 pieces (target <= 10 us), and whole optimisations of random corridors of
// 10, 100 and 1000 pieces (target: time(1000) / time(100) <= 12, linear in the pieces). Corridors:
// tests/unit/planning/random_corridor.hpp (steps of 1-3 m, boxes 0.25-0.6 m around each step, initial
// speed 2.5 m/s). The optimisation benchmarks report iterations and evaluations per run, so a ratio can be
// read per evaluation too.
#include <benchmark/benchmark.h>

#include <random>

#include "../unit/planning/random_corridor.hpp"
#include "aerotrack/planning/trajectory_optimizer.hpp"

namespace {

using aerotrack::planning::PolynomialTrajectory;
using aerotrack::planning::TrajectoryOptimizer;
using aerotrack::planning::TrajectoryOptimizerParams;

void BM_CostAndGradient(benchmark::State& state) {
  std::mt19937 rng(42);
  const auto corridor = aerotrack::planning::test::randomCorridor(static_cast<int>(state.range(0)), rng, 2.5);
  TrajectoryOptimizerParams params;
  params.max_pieces = static_cast<int>(state.range(0));
  auto opt = TrajectoryOptimizer::create(params);
  if (!opt || !opt->setProblem(corridor.problem())) {
    state.SkipWithError("setup failed");
    return;
  }
  const Eigen::VectorXd x = opt->initialVariables();
  Eigen::VectorXd grad(x.size());
  for (auto _ : state) benchmark::DoNotOptimize(opt->evaluate(x, grad));
}
BENCHMARK(BM_CostAndGradient)->Arg(10)->Arg(100)->Unit(benchmark::kMicrosecond);

// The same at the optimum (what most evaluations of a warm optimisation see: few penalties active).
void BM_CostAndGradientAtOptimum(benchmark::State& state) {
  std::mt19937 rng(42);
  const int pieces = static_cast<int>(state.range(0));
  const auto corridor = aerotrack::planning::test::randomCorridor(pieces, rng, 2.5);
  TrajectoryOptimizerParams params;
  params.max_pieces = pieces;
  auto opt = TrajectoryOptimizer::create(params);
  PolynomialTrajectory out(pieces);
  if (!opt || !opt->optimize(corridor.problem(), out) || !opt->setProblem(corridor.problem())) {
    state.SkipWithError("setup failed");
    return;
  }
  // The optimum's variables: the waypoints and durations of the optimised spline.
  Eigen::VectorXd x = opt->initialVariables();
  for (int i = 0; i + 1 < pieces; ++i)
    x.segment<3>(3 * i) = out.sample([&] {
                               double t = 0.0;
                               for (int k = 0; k <= i; ++k) t += out.pieceDurationS(k);
                               return t;
                             }())
                              .p_W_m;
  for (int i = 0; i < pieces; ++i)
    x(3 * (pieces - 1) + i) = TrajectoryOptimizer::tauFromDuration(out.pieceDurationS(i));
  Eigen::VectorXd grad(x.size());
  for (auto _ : state) benchmark::DoNotOptimize(opt->evaluate(x, grad));
}
BENCHMARK(BM_CostAndGradientAtOptimum)->Arg(10)->Unit(benchmark::kMicrosecond);

void BM_Optimize(benchmark::State& state) {
  const int pieces = static_cast<int>(state.range(0));
  std::mt19937 rng(7);
  const auto corridor = aerotrack::planning::test::randomCorridor(pieces, rng, 2.5);
  TrajectoryOptimizerParams params;
  params.max_pieces = pieces;
  auto opt = TrajectoryOptimizer::create(params);
  PolynomialTrajectory out(pieces);
  if (!opt) {
    state.SkipWithError("setup failed");
    return;
  }
  double iterations = 0.0;
  double evaluations = 0.0;
  for (auto _ : state) {
    const auto result = opt->optimize(corridor.problem(), out);
    if (!result) {
      state.SkipWithError(result.error().message.c_str());
      return;
    }
    iterations += result->iterations;
    evaluations += result->evaluations;
  }
  state.counters["iterations"] = benchmark::Counter(iterations, benchmark::Counter::kAvgIterations);
  state.counters["evaluations"] = benchmark::Counter(evaluations, benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_Optimize)->Arg(10)->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond);

}  // namespace
