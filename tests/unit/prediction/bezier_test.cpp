// Tests of the Bezier helpers (issue 7, item 1): the Bernstein basis is a partition of unity, and
// the closed-form acceleration energy c' Q c matches a numerical integral of |p''(t)|^2 (Simpson
// on the explicit second derivative) and its gradient 2 Q c matches finite differences.
#include <array>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "aerotrack/prediction/bezier.hpp"

namespace aerotrack::prediction {
namespace {

/// p''(t) of one axis by the explicit formula n(n-1)/T^2 sum (c_{i+2} - 2c_{i+1} + c_i) b_i^{n-2}.
double secondDerivative(const Eigen::VectorXd& c, double duration_s, double t_s) {
  const int n = static_cast<int>(c.size()) - 1;
  std::array<double, kMaxBezierDegree + 1> b{};
  bernsteinBasis(n - 2, t_s / duration_s, b);
  double v = 0.0;
  for (int i = 0; i + 2 <= n; ++i) v += (c(i + 2) - 2.0 * c(i + 1) + c(i)) * b[static_cast<std::size_t>(i)];
  return static_cast<double>(n * (n - 1)) / (duration_s * duration_s) * v;
}

double simpsonEnergy(const Eigen::VectorXd& c, double duration_s) {
  constexpr int kIntervals = 2000;
  const double h = duration_s / kIntervals;
  double sum = 0.0;
  for (int k = 0; k <= kIntervals; ++k) {
    const double a = secondDerivative(c, duration_s, k * h);
    const double w = (k == 0 || k == kIntervals) ? 1.0 : (k % 2 == 1 ? 4.0 : 2.0);
    sum += w * a * a;
  }
  return sum * h / 3.0;
}

TEST(Bezier, GivenAnySThenTheBernsteinBasisSumsToOne) {
  for (int degree = 0; degree <= kMaxBezierDegree; ++degree) {
    for (const double s : {0.0, 0.3, 1.0, 1.7}) {
      std::array<double, kMaxBezierDegree + 1> b{};
      bernsteinBasis(degree, s, b);
      double sum = 0.0;
      for (int i = 0; i <= degree; ++i) sum += b[static_cast<std::size_t>(i)];
      EXPECT_NEAR(sum, 1.0, 1e-12) << "degree " << degree << " s " << s;
    }
  }
  EXPECT_EQ(binomial(10, 5), 252.0);
}

TEST(Bezier, GivenRandomControlPointsThenTheEnergyMatrixMatchesNumericalIntegration) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int degree = 2; degree <= kMaxBezierDegree; ++degree) {
    for (const double duration_s : {0.5, 3.0}) {
      Eigen::VectorXd c(degree + 1);
      for (int i = 0; i <= degree; ++i) c(i) = normal(rng);
      Eigen::MatrixXd q(degree + 1, degree + 1);
      accelerationEnergyMatrix(degree, duration_s, q);
      const double closed_form = c.dot(q * c);
      EXPECT_NEAR(closed_form, simpsonEnergy(c, duration_s), 1e-8 * (1.0 + closed_form)) << "degree " << degree;
      EXPECT_LT((q - q.transpose()).norm(), 1e-12);
      // Gradient 2 Q c against central differences of the integral.
      constexpr double kStep = 1e-4;
      for (int i = 0; i <= degree; ++i) {
        Eigen::VectorXd plus = c, minus = c;
        plus(i) += kStep;
        minus(i) -= kStep;
        const double numeric = (simpsonEnergy(plus, duration_s) - simpsonEnergy(minus, duration_s)) / (2.0 * kStep);
        EXPECT_NEAR(2.0 * (q * c)(i), numeric, 1e-6 * (1.0 + std::abs(numeric))) << "degree " << degree << " i " << i;
      }
    }
  }
}

TEST(Bezier, GivenAStraightLineThenNoAccelerationEnergy) {
  Eigen::VectorXd c(6);
  c << 0.0, 0.2, 0.4, 0.6, 0.8, 1.0;  // evenly spaced: p(t) linear
  Eigen::MatrixXd q(6, 6);
  accelerationEnergyMatrix(5, 2.0, q);
  EXPECT_NEAR(c.dot(q * c), 0.0, 1e-12);
  EXPECT_NEAR((q * Eigen::VectorXd::Ones(6)).norm(), 0.0, 1e-12);
}

}  // namespace
}  // namespace aerotrack::prediction
