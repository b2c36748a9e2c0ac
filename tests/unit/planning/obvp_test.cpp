// Tests of the OBVP heuristic (obvp.hpp): the closed-form J(T) against a numerical integral of the cubic's
// squared acceleration, the cubic's boundary states, and the minimisation over T against a dense 1D search.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "aerotrack/planning/obvp.hpp"

namespace aerotrack::planning {
namespace {

Eigen::Vector3d randomVector(std::mt19937_64& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return {u(rng), u(rng), u(rng)};
}

// Slow, obvious reference: J(T) on a dense geometric grid of T, refined around the best sample.
double denseMinimum(const Eigen::Vector3d& p0, const Eigen::Vector3d& v0, const Eigen::Vector3d& p1,
                    const Eigen::Vector3d& v1, double rho) {
  double best = std::numeric_limits<double>::infinity();
  double best_t = 0.0;
  for (double t = 1e-3; t < 1e3; t *= 1.001) {
    const double j = obvpCostForDuration(p0, v0, p1, v1, rho, t);
    if (j < best) {
      best = j;
      best_t = t;
    }
  }
  for (double t = best_t / 1.001; t < best_t * 1.001; t += best_t * 1e-7) {
    best = std::min(best, obvpCostForDuration(p0, v0, p1, v1, rho, t));
  }
  return best;
}

TEST(Obvp, GivenADurationWhenTheCubicIsIntegratedThenItMeetsBothStatesAndCostsJOfT) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Vector3d p0 = randomVector(rng, 5.0);
    const Eigen::Vector3d v0 = randomVector(rng, 3.0);
    const Eigen::Vector3d p1 = randomVector(rng, 5.0);
    const Eigen::Vector3d v1 = randomVector(rng, 3.0);
    const double rho = 10.0;
    const double t_end = 0.5 + 0.1 * trial;
    const ObvpCubic cubic = obvpCubic(p0, v0, p1, v1, t_end);
    const Eigen::Vector3d p_end =
        p0 + v0 * t_end + cubic.a0_mps2 * t_end * t_end / 2.0 + cubic.jerk_mps3 * t_end * t_end * t_end / 6.0;
    const Eigen::Vector3d v_end = v0 + cubic.a0_mps2 * t_end + cubic.jerk_mps3 * t_end * t_end / 2.0;
    EXPECT_LT((p_end - p1).norm(), 1e-9);
    EXPECT_LT((v_end - v1).norm(), 1e-9);
    // Simpson's rule is exact for the quadratic |a(t)|^2.
    const auto a_sq = [&](double t) { return (cubic.a0_mps2 + t * cubic.jerk_mps3).squaredNorm(); };
    const double integral = t_end / 6.0 * (a_sq(0.0) + 4.0 * a_sq(t_end / 2.0) + a_sq(t_end));
    EXPECT_NEAR(integral + rho * t_end, obvpCostForDuration(p0, v0, p1, v1, rho, t_end), 1e-9 * (1.0 + integral));
  }
}

TEST(Obvp, GivenRandomStatePairsWhenSolvedThenTheCostIsTheDenseMinimumOverT) {
  std::mt19937_64 rng(11);
  double worst_relative = 0.0;
  for (int trial = 0; trial < 300; ++trial) {
    const Eigen::Vector3d p0 = randomVector(rng, 6.0);
    const Eigen::Vector3d v0 = randomVector(rng, 3.0);
    const Eigen::Vector3d p1 = randomVector(rng, 6.0);
    const Eigen::Vector3d v1 = randomVector(rng, 3.0);
    const double rho = trial % 3 == 0 ? 1.0 : (trial % 3 == 1 ? 10.0 : 100.0);
    const ObvpSolution solution = solveObvp(p0, v0, p1, v1, rho);
    const double reference = denseMinimum(p0, v0, p1, v1, rho);
    EXPECT_NEAR(solution.cost, obvpCostForDuration(p0, v0, p1, v1, rho, solution.duration_s), 1e-9 * reference);
    // Never above the reference (beyond rounding), and not below it either: it is a value of J.
    worst_relative = std::max(worst_relative, (solution.cost - reference) / reference);
    EXPECT_LE(solution.cost, reference * (1.0 + 1e-9)) << "trial " << trial;
  }
  RecordProperty("worst_relative_excess", std::to_string(worst_relative));
  std::printf("OBVP vs dense search over T: worst relative excess %.3g over 300 pairs\n", worst_relative);
}

TEST(Obvp, GivenIdenticalStatesThenTheCostIsZero) {
  const Eigen::Vector3d p(1.0, 2.0, 3.0);
  const ObvpSolution solution = solveObvp(p, Eigen::Vector3d::Zero(), p, Eigen::Vector3d::Zero(), 10.0);
  EXPECT_EQ(solution.cost, 0.0);
  EXPECT_EQ(solution.duration_s, 0.0);
}

TEST(Obvp, GivenOnlyAVelocityChangeThenTheCostIsTwoRootOfCRho) {
  // d = 0, v0 = -v1: J = 4 |v|^2 / T + rho T (the other terms vanish), minimum 2 sqrt(4 |v|^2 rho).
  const Eigen::Vector3d v(1.0, 0.0, 0.0);
  const ObvpSolution solution = solveObvp(Eigen::Vector3d::Zero(), v, Eigen::Vector3d::Zero(), -v, 10.0);
  EXPECT_NEAR(solution.cost, 2.0 * std::sqrt(4.0 * 10.0), 1e-9);
  EXPECT_NEAR(solution.duration_s, std::sqrt(4.0 / 10.0), 1e-9);
}

}  // namespace
}  // namespace aerotrack::planning
