// Checks the allocation claims of the prediction (issue 7, item 1): after create(), DenseQpSolver::
// solve() and a successful TargetPredictor::add() / predict() never allocate. malloc is interposed
// in this test binary (Eigen allocates through malloc, not operator new) and counts calls while a
// flag is set. Under AddressSanitizer or ThreadSanitizer (which own malloc) the tests are skipped.
#include <atomic>
#include <cmath>
#include <cstddef>
#include <random>

#include <gtest/gtest.h>

#include "aerotrack/prediction/dense_qp.hpp"
#include "aerotrack/prediction/target_predictor.hpp"

#include "../malloc_counter.hpp"

namespace aerotrack::prediction {
namespace {

using CountMallocs = aerotrack::test::MallocCount;

TEST(PredictionAllocation, GivenTheInterposedMallocThenItCounts) {
  if (!aerotrack::test::kMallocCounted) GTEST_SKIP() << "malloc belongs to the sanitizer";
  long counted = 0;
  {
    const CountMallocs counter;
    const Eigen::VectorXd v = Eigen::VectorXd::Ones(100);
    EXPECT_EQ(v.sum(), 100.0);
    counted = counter.count();
  }
  EXPECT_GE(counted, 1);
}

TEST(PredictionAllocation, GivenACreatedPredictorThenAddAndPredictNeverAllocate) {
  if (!aerotrack::test::kMallocCounted) GTEST_SKIP() << "malloc belongs to the sanitizer";
  TargetPredictorParams params;
  params.max_speed_mps = 1.0;  // active bounds: the QP's add/drop paths run too
  params.fit_z = true;
  auto predictor = TargetPredictor::create(params);
  ASSERT_TRUE(predictor);
  std::mt19937_64 rng(4);
  std::normal_distribution<double> noise(0.0, 0.05);
  int predictions = 0;
  int qp_iterations = 0;
  long mallocs = 0;
  {
    const CountMallocs counter;
    for (int k = 0; k < 300; ++k) {
      const double t_s = k / 30.0;
      const Eigen::Vector3d p(4.0 * std::sin(0.375 * t_s), 4.0 * (1.0 - std::cos(0.375 * t_s)), 0.9);
      predictor->add(rt::secondsToNs(t_s), p + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
      if (k < 10) continue;
      const auto prediction = predictor->predict(rt::secondsToNs(t_s));
      if (prediction) {
        ++predictions;
        qp_iterations += prediction->qp_iterations;
      }
    }
    mallocs = counter.count();
  }
  EXPECT_EQ(predictions, 290);
  EXPECT_GT(qp_iterations, 0);
  EXPECT_EQ(mallocs, 0);
}

}  // namespace
}  // namespace aerotrack::prediction
