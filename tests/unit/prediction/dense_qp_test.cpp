// Tests of DenseQpSolver (issue 7, item 1) against a slow but obvious reference: for small
// problems, every subset of the inequalities is tried as the active set, the KKT system solved,
// and the point that is feasible with non-negative multipliers is the optimum (for a strictly
// convex QP it is unique, and some linearly independent active set reaches it). Random problems,
// infeasible ones (a row contradicting a combination of two others, inconsistent equalities),
// degenerate ones (duplicate rows, an inequality on an equality's row, redundant equalities), warm
// start (same answer, fewer iterations), the failure values and allocation-free solving.
#include <algorithm>
#include <cstdio>
#include <limits>
#include <optional>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "aerotrack/prediction/dense_qp.hpp"
#include "support/require.hpp"

namespace aerotrack::prediction {
namespace {

struct Problem {
  Eigen::MatrixXd h;
  Eigen::VectorXd g;
  Eigen::MatrixXd a_eq;
  Eigen::VectorXd b_eq;
  Eigen::MatrixXd a_in;
  Eigen::VectorXd b_in;
  QpProblem view() const { return {h, g, a_eq, b_eq, a_in, b_in}; }
};

struct Reference {
  Eigen::VectorXd x;
  double objective = 0.0;
};

double objectiveOf(const Problem& p, const Eigen::VectorXd& x) {
  return 0.5 * x.dot(p.h * x) + p.g.dot(x);
}

/// The oracle: enumerate active sets, solve [H -N'; N 0] [x; u] = [-g; b], keep the KKT point.
std::optional<Reference> referenceSolve(const Problem& p) {
  const auto n = p.h.rows();
  const auto m_eq = p.a_eq.rows();
  const auto m_in = p.a_in.rows();
  std::optional<Reference> best;
  for (unsigned mask = 0; mask < (1u << m_in); ++mask) {
    std::vector<int> rows;
    for (int i = 0; i < m_in; ++i) {
      if ((mask >> i) & 1u) rows.push_back(i);
    }
    const auto q = m_eq + static_cast<Eigen::Index>(rows.size());
    if (q > n) continue;
    Eigen::MatrixXd n_mat(q, n);
    Eigen::VectorXd b(q);
    n_mat.topRows(m_eq) = p.a_eq;
    b.head(m_eq) = p.b_eq;
    for (std::size_t k = 0; k < rows.size(); ++k) {
      n_mat.row(m_eq + static_cast<Eigen::Index>(k)) = p.a_in.row(rows[k]);
      b(m_eq + static_cast<Eigen::Index>(k)) = p.b_in(rows[k]);
    }
    Eigen::MatrixXd kkt = Eigen::MatrixXd::Zero(n + q, n + q);
    kkt.topLeftCorner(n, n) = p.h;
    kkt.topRightCorner(n, q) = -n_mat.transpose();
    kkt.bottomLeftCorner(q, n) = n_mat;
    Eigen::VectorXd rhs(n + q);
    rhs << -p.g, b;
    const Eigen::FullPivLU<Eigen::MatrixXd> lu(kkt);
    if (!lu.isInvertible()) continue;
    const Eigen::VectorXd sol = lu.solve(rhs);
    const Eigen::VectorXd x = sol.head(n);
    const Eigen::VectorXd u = sol.tail(q);
    if (u.tail(q - m_eq).size() > 0 && u.tail(q - m_eq).minCoeff() < -1e-9) continue;
    if (m_in > 0 && (p.a_in * x - p.b_in).minCoeff() < -1e-9) continue;
    const double f = objectiveOf(p, x);
    if (!best || f < best->objective) best = Reference{x, f};
  }
  return best;
}

Problem randomProblem(std::mt19937_64& rng, int n, int m_eq, int m_in) {
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const auto random = [&](int rows, int cols) {
    Eigen::MatrixXd m(rows, cols);
    for (int i = 0; i < m.size(); ++i) m.data()[i] = normal(rng);
    return m;
  };
  Problem p;
  const Eigen::MatrixXd m = random(n, n);
  p.h = m * m.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
  p.g = 3.0 * random(n, 1);
  const Eigen::VectorXd x0 = random(n, 1);  // feasible by construction
  p.a_eq = random(m_eq, n);
  p.b_eq = p.a_eq * x0;
  p.a_in = random(m_in, n);
  p.b_in = p.a_in * x0;
  for (int i = 0; i < m_in; ++i) p.b_in(i) -= uniform(rng);
  return p;
}

DenseQpSolver makeSolver(int max_iterations = 200) {
  DenseQpSolverParams params;
  params.max_variables = 8;
  params.max_equalities = 4;
  params.max_inequalities = 16;
  params.max_iterations = max_iterations;
  return aerotrack::test::require(DenseQpSolver::create(params), "DenseQpSolver::create");
}

TEST(DenseQpSolver, GivenRandomFeasibleProblemsThenMatchesTheEnumeratingReference) {
  std::mt19937_64 rng(7);
  DenseQpSolver solver = makeSolver();
  double worst_x = 0.0;
  double worst_f = 0.0;
  int with_active = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int n = 2 + trial % 5;
    const int m_eq = std::min(trial % 3, n - 1);
    const int m_in = 1 + trial % 9;
    const Problem p = randomProblem(rng, n, m_eq, m_in);
    const auto reference = referenceSolve(p);
    ASSERT_TRUE(reference) << "trial " << trial;
    const QpResult result = solver.solve(p.view());
    ASSERT_EQ(result.status, QpStatus::kOptimal) << "trial " << trial;
    const double scale = 1.0 + reference->x.lpNorm<Eigen::Infinity>();
    worst_x = std::max(worst_x, (solver.solution() - reference->x).lpNorm<Eigen::Infinity>() / scale);
    worst_f =
        std::max(worst_f, std::abs(result.objective - reference->objective) / (1.0 + std::abs(reference->objective)));
    if (!solver.activeInequalities().empty()) ++with_active;
    for (const double u : solver.inequalityMultipliers()) EXPECT_GE(u, 0.0);
  }
  std::printf(
      "qp vs reference over 400 problems: max |dx| %.2e (relative), max |df| %.2e (relative), %d with active "
      "inequalities\n",
      worst_x, worst_f, with_active);
  EXPECT_LT(worst_x, 1e-6);
  EXPECT_LT(worst_f, 1e-6);
  EXPECT_GT(with_active, 200);  // the problems do exercise the active set
}

TEST(DenseQpSolver, GivenContradictoryInequalitiesThenInfeasible) {
  std::mt19937_64 rng(11);
  DenseQpSolver solver = makeSolver();
  for (int trial = 0; trial < 100; ++trial) {
    const int n = 2 + trial % 4;
    Problem p = randomProblem(rng, n, trial % 2, 2 + trial % 5);
    // a_0 x >= b_0 and a_1 x >= b_1 imply (a_0 + a_1) x >= b_0 + b_1; ask for <= b_0 + b_1 - 0.5.
    const auto m = p.a_in.rows();
    p.a_in.conservativeResize(m + 1, Eigen::NoChange);
    p.b_in.conservativeResize(m + 1);
    p.a_in.row(m) = -(p.a_in.row(0) + p.a_in.row(1));
    p.b_in(m) = -(p.b_in(0) + p.b_in(1)) + 0.5;
    EXPECT_FALSE(referenceSolve(p)) << "trial " << trial;
    EXPECT_EQ(solver.solve(p.view()).status, QpStatus::kInfeasible) << "trial " << trial;
  }
}

TEST(DenseQpSolver, GivenInconsistentEqualitiesThenInfeasible) {
  Problem p;
  p.h = Eigen::MatrixXd::Identity(3, 3);
  p.g = Eigen::VectorXd::Zero(3);
  p.a_eq = Eigen::MatrixXd(2, 3);
  p.a_eq << 1, 1, 0, 2, 2, 0;
  p.b_eq = Eigen::Vector2d(1.0, 3.0);
  p.a_in = Eigen::MatrixXd(0, 3);
  p.b_in = Eigen::VectorXd(0);
  DenseQpSolver solver = makeSolver();
  EXPECT_EQ(solver.solve(p.view()).status, QpStatus::kInfeasible);
  p.b_eq(1) = 2.0;  // now redundant, not inconsistent
  ASSERT_EQ(solver.solve(p.view()).status, QpStatus::kOptimal);
  EXPECT_NEAR(solver.solution()(0), 0.5, 1e-12);
  EXPECT_NEAR(solver.solution()(1), 0.5, 1e-12);
}

TEST(DenseQpSolver, GivenDuplicateAndEqualityShadowingRowsThenSolvesLikeTheCleanProblem) {
  std::mt19937_64 rng(13);
  DenseQpSolver solver = makeSolver();
  double worst = 0.0;
  for (int trial = 0; trial < 100; ++trial) {
    const int n = 3 + trial % 3;
    const Problem clean = randomProblem(rng, n, 1, 3 + trial % 4);
    const auto clean_reference = referenceSolve(clean);
    ASSERT_TRUE(clean_reference);
    Problem degenerate = clean;
    const auto m = clean.a_in.rows();
    degenerate.a_in.conservativeResize(m + 4, Eigen::NoChange);
    degenerate.b_in.conservativeResize(m + 4);
    degenerate.a_in.row(m) = clean.a_in.row(0);  // exact duplicate
    degenerate.b_in(m) = clean.b_in(0);
    degenerate.a_in.row(m + 1) = 3.0 * clean.a_in.row(1);  // scaled duplicate
    degenerate.b_in(m + 1) = 3.0 * clean.b_in(1);
    degenerate.a_in.row(m + 2) = clean.a_eq.row(0);  // inequality on the equality's row, both ways
    degenerate.b_in(m + 2) = clean.b_eq(0);
    degenerate.a_in.row(m + 3) = -clean.a_eq.row(0);
    degenerate.b_in(m + 3) = -clean.b_eq(0);
    degenerate.a_eq.conservativeResize(2, Eigen::NoChange);  // a redundant equality
    degenerate.b_eq.conservativeResize(2);
    degenerate.a_eq.row(1) = -2.0 * clean.a_eq.row(0);
    degenerate.b_eq(1) = -2.0 * clean.b_eq(0);
    const QpResult result = solver.solve(degenerate.view());
    ASSERT_EQ(result.status, QpStatus::kOptimal) << "trial " << trial;
    worst = std::max(worst, (solver.solution() - clean_reference->x).lpNorm<Eigen::Infinity>());
  }
  EXPECT_LT(worst, 1e-6);
}

TEST(DenseQpSolver, GivenTheLastActiveSetThenWarmStartGivesTheSameAnswerInFewerIterations) {
  std::mt19937_64 rng(17);
  std::normal_distribution<double> normal(0.0, 1.0);
  DenseQpSolver solver = makeSolver();
  int cold_total = 0;
  int warm_total = 0;
  double worst = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    Problem p = randomProblem(rng, 3 + trial % 4, trial % 2, 4 + trial % 8);
    ASSERT_EQ(solver.solve(p.view()).status, QpStatus::kOptimal);
    const auto active = solver.activeInequalities();
    const std::vector<int> guess(active.begin(), active.end());
    // The next problem of a sequence: slightly different gradient (as the next prediction).
    for (int i = 0; i < p.g.size(); ++i) p.g(i) += 0.01 * normal(rng);
    const QpResult cold = solver.solve(p.view());
    ASSERT_EQ(cold.status, QpStatus::kOptimal);
    const Eigen::VectorXd x_cold = solver.solution();
    const QpResult warm = solver.solve(p.view(), guess);
    ASSERT_EQ(warm.status, QpStatus::kOptimal);
    worst = std::max(worst, (solver.solution() - x_cold).lpNorm<Eigen::Infinity>());
    EXPECT_NEAR(warm.objective, cold.objective, 1e-9 * (1.0 + std::abs(cold.objective)));
    cold_total += cold.iterations;
    warm_total += warm.iterations;
  }
  std::printf("warm start: %d iterations over 200 problems, cold: %d\n", warm_total, cold_total);
  EXPECT_LT(worst, 1e-8);
  EXPECT_LT(warm_total, cold_total);
}

TEST(DenseQpSolver, GivenAWrongWarmStartGuessThenStillOptimal) {
  std::mt19937_64 rng(19);
  DenseQpSolver solver = makeSolver();
  for (int trial = 0; trial < 100; ++trial) {
    const Problem p = randomProblem(rng, 3 + trial % 4, trial % 2, 6);
    const auto reference = referenceSolve(p);
    ASSERT_TRUE(reference);
    const std::vector<int> guess{0, 2, 4, 4, 99, -1};  // arbitrary, repeated and out-of-range rows
    ASSERT_EQ(solver.solve(p.view(), guess).status, QpStatus::kOptimal);
    EXPECT_LT((solver.solution() - reference->x).lpNorm<Eigen::Infinity>(), 1e-6);
  }
}

TEST(DenseQpSolver, GivenBadInputsThenTheFailureIsNamed) {
  DenseQpSolver solver = makeSolver(1);
  Problem p;
  p.h = Eigen::Matrix2d(Eigen::Vector2d(1.0, -1.0).asDiagonal());
  p.g = Eigen::Vector2d(1.0, 1.0);
  p.a_eq = Eigen::MatrixXd(0, 2);
  p.b_eq = Eigen::VectorXd(0);
  p.a_in = Eigen::MatrixXd::Identity(2, 2);
  p.b_in = Eigen::Vector2d(1.0, 1.0);
  EXPECT_EQ(solver.solve(p.view()).status, QpStatus::kNotPositiveDefinite);
  p.h = Eigen::MatrixXd::Identity(2, 2);
  const QpResult capped = solver.solve(p.view());  // needs two additions, the cap is one
  EXPECT_EQ(capped.status, QpStatus::kMaxIterations);
  EXPECT_EQ(capped.iterations, 2);
  p.g(0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(solver.solve(p.view()).status, QpStatus::kInvalidProblem);
  p.g = Eigen::VectorXd::Zero(3);
  EXPECT_EQ(solver.solve(p.view()).status, QpStatus::kInvalidProblem);
  EXPECT_STREQ(toString(QpStatus::kInfeasible), "infeasible");
  DenseQpSolverParams bad;
  bad.max_iterations = 0;
  EXPECT_FALSE(DenseQpSolver::create(bad));
}

TEST(DenseQpSolver, GivenAnUnconstrainedProblemThenTheNewtonPoint) {
  DenseQpSolver solver = makeSolver();
  Problem p;
  p.h = Eigen::Matrix2d{{4.0, 1.0}, {1.0, 3.0}};
  p.g = Eigen::Vector2d(1.0, 2.0);
  p.a_eq = Eigen::MatrixXd(0, 2);
  p.b_eq = Eigen::VectorXd(0);
  p.a_in = Eigen::MatrixXd(0, 2);
  p.b_in = Eigen::VectorXd(0);
  const QpResult result = solver.solve(p.view());
  ASSERT_EQ(result.status, QpStatus::kOptimal);
  const Eigen::Vector2d expected = -p.h.llt().solve(p.g);
  EXPECT_LT((solver.solution() - expected).norm(), 1e-12);
  EXPECT_EQ(result.iterations, 0);
}

}  // namespace
}  // namespace aerotrack::prediction
