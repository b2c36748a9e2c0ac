// Benchmark of one target prediction (issue 7, item 1): the Bezier fit of degree 5 over a full
// 1.5 s window of estimates at 30 Hz (46) plus the two QPs (x, y), on a turning walk whose bounds
// are active (predictBoundsActive) and on a straight walk where they are not (predictStraight).
// Target: <= 0.2 ms per prediction.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "aerotrack/prediction/target_predictor.hpp"

namespace aerotrack::prediction {
namespace {

constexpr double kRateHz = 30.0;

void runPredictions(benchmark::State& state, double max_speed_mps, double turn_rate_rps) {
  TargetPredictorParams params;
  params.max_speed_mps = max_speed_mps;
  auto predictor = TargetPredictor::create(params);
  if (!predictor) {
    state.SkipWithError(predictor.error().message.c_str());
    return;
  }
  std::mt19937_64 rng(1);
  std::normal_distribution<double> noise(0.0, 0.05);
  int k = 0;
  const auto addNext = [&] {
    const double t_s = k / kRateHz;
    const double angle = turn_rate_rps * t_s;
    const Eigen::Vector3d p = turn_rate_rps > 0.0 ? Eigen::Vector3d(1.5 / turn_rate_rps * std::sin(angle),
                                                                    1.5 / turn_rate_rps * (1.0 - std::cos(angle)), 0.9)
                                                  : Eigen::Vector3d(1.5 * t_s, 0.0, 0.9);
    predictor->add(rt::secondsToNs(t_s), p + Eigen::Vector3d(noise(rng), noise(rng), 0.0));
    ++k;
  };
  for (int i = 0; i < 60; ++i) addNext();
  int iterations = 0;
  for (auto _ : state) {
    addNext();  // a new estimate per prediction, as in the loop (cheap next to the fit)
    auto prediction = predictor->predict(rt::secondsToNs((k - 1) / kRateHz));
    benchmark::DoNotOptimize(prediction);
    if (prediction) iterations += prediction->qp_iterations;
  }
  state.counters["qp_iterations"] = benchmark::Counter(iterations, benchmark::Counter::kAvgIterations);
}

void predictStraight(benchmark::State& state) {
  runPredictions(state, 3.0, 0.0);
}
BENCHMARK(predictStraight)->Unit(benchmark::kMicrosecond);

void predictBoundsActive(benchmark::State& state) {
  runPredictions(state, 1.0, 0.375);
}
BENCHMARK(predictBoundsActive)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace aerotrack::prediction
