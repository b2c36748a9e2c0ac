// BandedSystem against a dense, pivoted reference solve (Eigen's PartialPivLU).
#include "aerotrack/planning/banded_system.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

namespace aerotrack::planning {
namespace {

struct Banded {
  BandedSystem system;
  Eigen::MatrixXd dense;
};

// A random banded matrix, made diagonally dominant so that LU without pivoting is stable.
Banded randomBanded(int n, int lower, int upper, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Banded b;
  b.system.resize(n, lower, upper);
  b.dense = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = std::max(0, i - lower); j <= std::min(n - 1, i + upper); ++j) {
      const double v = (i == j) ? 4.0 + u(rng) : u(rng);
      b.system(i, j) = v;
      b.dense(i, j) = v;
    }
  }
  return b;
}

TEST(BandedSystem, SolveMatchesDense) {
  std::mt19937 rng(7);
  for (const auto& [n, lower, upper] :
       {std::tuple{1, 0, 0}, std::tuple{12, 6, 6}, std::tuple{60, 6, 6}, std::tuple{25, 2, 5}, std::tuple{30, 5, 1}}) {
    Banded b = randomBanded(n, lower, upper, rng);
    const RowMatrixX3d rhs = RowMatrixX3d::Random(n, 3);
    const Eigen::MatrixXd expected = b.dense.partialPivLu().solve(rhs);
    const Eigen::MatrixXd expected_adjoint = b.dense.transpose().partialPivLu().solve(rhs);
    ASSERT_TRUE(b.system.factorize());
    RowMatrixX3d x = rhs;
    b.system.solve(x);
    RowMatrixX3d y = rhs;
    b.system.solveAdjoint(y);
    EXPECT_LT((x - expected).cwiseAbs().maxCoeff(), 1e-12) << "n=" << n;
    EXPECT_LT((y - expected_adjoint).cwiseAbs().maxCoeff(), 1e-12) << "n=" << n;
  }
}

TEST(BandedSystem, ZeroPivotIsReported) {
  BandedSystem s;
  s.resize(3, 1, 1);
  s(0, 0) = 1.0;
  s(1, 1) = 0.0;
  s(2, 2) = 1.0;
  EXPECT_FALSE(s.factorize());
}

}  // namespace
}  // namespace aerotrack::planning
