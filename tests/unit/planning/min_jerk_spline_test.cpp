// MinJerkSpline: the banded coefficient map against a dense reference (the jerk-energy QP solved by
// its KKT system with only C^2 continuity imposed: the optimality of C^4 continuity is then checked,
// not assumed), continuity at every junction, and the adjoint gradients against central differences.
#include "aerotrack/planning/min_jerk_spline.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

namespace aerotrack::planning {
namespace {

struct Problem {
  StatePva start;
  StatePva end;
  Eigen::Matrix3Xd q;
  Eigen::VectorXd t;
};

Problem randomProblem(int m, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> dur(0.3, 1.5);
  Problem p;
  p.start = StatePva::NullaryExpr([&] { return u(rng); });
  p.end = StatePva::NullaryExpr([&] { return u(rng); });
  p.end.col(0) += Eigen::Vector3d(3.0 * m, 0.0, 0.0);
  p.q.resize(3, m - 1);
  for (int i = 0; i + 1 < m; ++i) p.q.col(i) = Eigen::Vector3d(3.0 * (i + 1), 0.0, 0.0) + Eigen::Vector3d::Random();
  p.t.resize(m);
  for (int i = 0; i < m; ++i) p.t(i) = dur(rng);
  return p;
}

// The reference: per axis, minimise sum_i int |p_i'''|^2 subject to the boundary states, the waypoints
// and C^2 continuity, by a dense KKT solve.
RowMatrixX3d denseReference(const Problem& p) {
  const int m = static_cast<int>(p.t.size());
  const int n = 6 * m;
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < m; ++i) {
    // int beta_3(t) beta_3(t)^T dt over [0, T], by 8-point Gauss-Legendre (exact for degree 4).
    const double gx[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
    const double gw[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
    for (int k = 0; k < 4; ++k) {
      for (const double sign : {-1.0, 1.0}) {
        const double t = 0.5 * p.t(i) * (1.0 + sign * gx[k]);
        const Eigen::Matrix<double, 6, 1> b = monomialBasis(3, t);
        h.block<6, 6>(6 * i, 6 * i) += 0.5 * p.t(i) * gw[k] * b * b.transpose();
      }
    }
  }
  const int constraints = 6 + 4 * (m - 1);
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(constraints, n);
  RowMatrixX3d rhs = RowMatrixX3d::Zero(constraints, 3);
  int row = 0;
  for (int d = 0; d < 3; ++d, ++row) {
    a.block<1, 6>(row, 0) = monomialBasis(d, 0.0).transpose();
    rhs.row(row) = p.start.col(d).transpose();
  }
  for (int i = 0; i + 1 < m; ++i) {
    a.block<1, 6>(row, 6 * i) = monomialBasis(0, p.t(i)).transpose();
    rhs.row(row++) = p.q.col(i).transpose();
    a.block<1, 6>(row, 6 * (i + 1)) = monomialBasis(0, 0.0).transpose();
    rhs.row(row++) = p.q.col(i).transpose();
    for (int d = 1; d <= 2; ++d, ++row) {
      a.block<1, 6>(row, 6 * i) = monomialBasis(d, p.t(i)).transpose();
      a.block<1, 6>(row, 6 * (i + 1)) = -monomialBasis(d, 0.0).transpose();
    }
  }
  for (int d = 0; d < 3; ++d, ++row) {
    a.block<1, 6>(row, 6 * (m - 1)) = monomialBasis(d, p.t(m - 1)).transpose();
    rhs.row(row) = p.end.col(d).transpose();
  }
  Eigen::MatrixXd kkt = Eigen::MatrixXd::Zero(n + constraints, n + constraints);
  kkt.topLeftCorner(n, n) = 2.0 * h;
  kkt.topRightCorner(n, constraints) = a.transpose();
  kkt.bottomLeftCorner(constraints, n) = a;
  RowMatrixX3d b = RowMatrixX3d::Zero(n + constraints, 3);
  b.bottomRows(constraints) = rhs;
  const RowMatrixX3d solution = kkt.fullPivLu().solve(b);
  return solution.topRows(n);
}

TEST(MinJerkSpline, CoefficientsMatchDenseQp) {
  std::mt19937 rng(3);
  for (const int m : {1, 2, 5, 12}) {
    const Problem p = randomProblem(m, rng);
    MinJerkSpline spline;
    spline.reset(p.start, p.end, m);
    ASSERT_TRUE(spline.generate(p.q, p.t));
    const RowMatrixX3d reference = denseReference(p);
    const double scale = std::max(1.0, reference.cwiseAbs().maxCoeff());
    EXPECT_LT((spline.coefficients() - reference).cwiseAbs().maxCoeff() / scale, 1e-8) << "M=" << m;
  }
}

TEST(MinJerkSpline, ContinuousAtEveryJunctionAndMeetsBoundaries) {
  std::mt19937 rng(5);
  const int m = 9;
  const Problem p = randomProblem(m, rng);
  MinJerkSpline spline;
  spline.reset(p.start, p.end, m);
  ASSERT_TRUE(spline.generate(p.q, p.t));
  const RowMatrixX3d& c = spline.coefficients();
  for (int d = 0; d < 3; ++d) {
    EXPECT_LT((c.middleRows<6>(0).transpose() * monomialBasis(d, 0.0) - p.start.col(d)).norm(), 1e-9);
    EXPECT_LT((c.middleRows<6>(6 * (m - 1)).transpose() * monomialBasis(d, p.t(m - 1)) - p.end.col(d)).norm(), 1e-9);
  }
  for (int i = 0; i + 1 < m; ++i) {
    EXPECT_LT((c.middleRows<6>(6 * i).transpose() * monomialBasis(0, p.t(i)) - p.q.col(i)).norm(), 1e-9);
    for (int d = 0; d <= 4; ++d) {
      const Eigen::Vector3d left = c.middleRows<6>(6 * i).transpose() * monomialBasis(d, p.t(i));
      const Eigen::Vector3d right = c.middleRows<6>(6 * (i + 1)).transpose() * monomialBasis(d, 0.0);
      EXPECT_LT((left - right).norm(), 1e-8 * std::max(1.0, left.norm())) << "junction " << i << " d=" << d;
    }
  }
}

TEST(MinJerkSpline, JerkEnergyMatchesQuadrature) {
  std::mt19937 rng(11);
  const Problem p = randomProblem(4, rng);
  MinJerkSpline spline;
  spline.reset(p.start, p.end, 4);
  ASSERT_TRUE(spline.generate(p.q, p.t));
  double reference = 0.0;
  const int steps = 20000;
  for (int i = 0; i < 4; ++i) {
    const double h = p.t(i) / steps;
    for (int k = 0; k < steps; ++k) {  // midpoint rule
      const Eigen::Vector3d j =
          spline.coefficients().middleRows<6>(6 * i).transpose() * monomialBasis(3, (k + 0.5) * h);
      reference += j.squaredNorm() * h;
    }
  }
  EXPECT_NEAR(spline.jerkEnergy(), reference, 1e-6 * reference);
}

// The adjoint gradient of the jerk energy (a function of q and T through the map) against central
// differences of the whole map.
TEST(MinJerkSpline, EnergyGradientMatchesFiniteDifferences) {
  std::mt19937 rng(13);
  const int m = 6;
  Problem p = randomProblem(m, rng);
  MinJerkSpline spline;
  spline.reset(p.start, p.end, m);
  auto energy = [&](const Eigen::Matrix3Xd& q, const Eigen::VectorXd& t) {
    EXPECT_TRUE(spline.generate(q, t));
    return spline.jerkEnergy();
  };
  ASSERT_TRUE(spline.generate(p.q, p.t));
  RowMatrixX3d grad_c = RowMatrixX3d::Zero(6 * m, 3);
  Eigen::VectorXd grad_t = Eigen::VectorXd::Zero(m);
  Eigen::Matrix3Xd grad_q;
  spline.addJerkEnergyGradient(grad_c, grad_t);
  spline.propagateGradient(grad_c, grad_t, grad_q);
  const double h = 1e-6;
  for (int i = 0; i + 1 < m; ++i) {
    for (int axis = 0; axis < 3; ++axis) {
      Eigen::Matrix3Xd plus = p.q;
      Eigen::Matrix3Xd minus = p.q;
      plus(axis, i) += h;
      minus(axis, i) -= h;
      const double fd = (energy(plus, p.t) - energy(minus, p.t)) / (2.0 * h);
      EXPECT_NEAR(grad_q(axis, i), fd, 1e-6 * std::max(1.0, std::abs(fd))) << "q " << i << "," << axis;
    }
  }
  for (int i = 0; i < m; ++i) {
    Eigen::VectorXd plus = p.t;
    Eigen::VectorXd minus = p.t;
    plus(i) += h;
    minus(i) -= h;
    const double fd = (energy(p.q, plus) - energy(p.q, minus)) / (2.0 * h);
    EXPECT_NEAR(grad_t(i), fd, 1e-6 * std::max(1.0, std::abs(fd))) << "T " << i;
  }
}

TEST(MinJerkSpline, NonPositiveDurationIsRejected) {
  MinJerkSpline spline;
  spline.reset(StatePva::Zero(), StatePva::Identity(), 2);
  Eigen::Matrix3Xd q = Eigen::Matrix3Xd::Ones(3, 1);
  Eigen::VectorXd t(2);
  t << 1.0, 0.0;
  EXPECT_FALSE(spline.generate(q, t));
}

}  // namespace
}  // namespace aerotrack::planning
