// Minimum-jerk piecewise polynomials from waypoints and durations (paper Sect. V-C, after Wang et
// al., "Generating large-scale trajectories efficiently using double descriptions of polynomials",
// ICRA 2021, and "Geometrically constrained trajectory optimization for multicopters", T-RO 2022).
//
// M pieces, piece i a quintic p_i(t) = sum_k c_{i,k} t^k on [0, T_i] (W frame, metres). Given the
// start and end position, velocity and acceleration, the M - 1 intermediate waypoints q_i = p_i(T_i)
// and the durations T_i, the jerk-energy minimiser is the spline with position, velocity,
// acceleration, jerk and snap continuous at every junction (the optimality conditions for s = 3).
// Those 6M conditions are linear in the 6M x 3 coefficients, A(T) c = b(q), with A banded (lower and
// upper bandwidth 6), so c follows in O(M). Gradients of any cost J(c, T) with respect to q and T follow
// from the adjoint: G = A^-T dJ/dc gives dJ/dq_i = G row of q_i's equation and
// dJ/dT_i = dJ/dT_i (explicit) - G^T (dA/dT_i) c.
//
// Row layout of A (piece i's coefficients are columns 6i..6i+5; beta_d(t) the d-th derivative of
// [1 t t^2 t^3 t^4 t^5]):
//   rows 0..2        beta_d(0) c_0 = start derivative d (d = 0, 1, 2)
//   per junction i:  6i+3: beta_3(T_i) c_i - beta_3(0) c_{i+1} = 0   (jerk continuity)
//                    6i+4: beta_4(T_i) c_i - beta_4(0) c_{i+1} = 0   (snap continuity)
//                    6i+5: beta_0(T_i) c_i = q_i                      (the waypoint)
//                    6i+6..6i+8: beta_d(T_i) c_i - beta_d(0) c_{i+1} = 0, d = 0, 1, 2
//   rows 6M-3..6M-1  beta_d(T_{M-1}) c_{M-1} = end derivative d
// This order puts a nonzero constant or T^5 on every diagonal entry, so LU needs no pivoting.
#pragma once

#include <Eigen/Core>

#include "aerotrack/planning/banded_system.hpp"

namespace aerotrack::planning {

/// Position, velocity and acceleration (columns) of a boundary state, W frame.
using StatePva = Eigen::Matrix3d;

class MinJerkSpline {
 public:
  /// Sets the boundary states (columns p, v, a) and the number of pieces M >= 1; sizes all scratch
  /// memory (allocates only when M grows beyond what it held before).
  void reset(const StatePva& start, const StatePva& end, int pieces);

  /// Computes the coefficients for waypoints q (3 x (M-1), column i = q_i) and durations T (M, all
  /// > 0). False if the system is singular (a duration not positive or not finite).
  bool generate(const Eigen::Ref<const Eigen::Matrix3Xd>& waypoints_m,
                const Eigen::Ref<const Eigen::VectorXd>& durations_s);

  int pieces() const { return pieces_; }
  const Eigen::VectorXd& durations() const { return durations_s_; }
  /// Coefficients, 6M x 3: rows 6i..6i+5 are piece i's c_{i,0..5}, columns x, y, z.
  const RowMatrixX3d& coefficients() const { return coeffs_; }

  /// Jerk energy sum_i int_0^T_i |p_i'''|^2 dt of the current spline.
  double jerkEnergy() const;
  /// Adds the partial derivatives of jerkEnergy() with respect to the coefficients and (explicitly) the
  /// durations to grad_c (6M x 3) and grad_T (M).
  void addJerkEnergyGradient(RowMatrixX3d& grad_c, Eigen::VectorXd& grad_T) const;

  /// Chain rule through the coefficient map. In: dJ/dc (6M x 3, consumed as scratch) and the explicit
  /// dJ/dT (M). Out: dJ/dq (3 x (M-1)) and the total dJ/dT (M, updated in place).
  void propagateGradient(RowMatrixX3d& grad_c, Eigen::VectorXd& grad_T, Eigen::Matrix3Xd& grad_q) const;

 private:
  int pieces_ = 0;
  StatePva start_ = StatePva::Zero();
  StatePva end_ = StatePva::Zero();
  BandedSystem system_;
  RowMatrixX3d coeffs_;
  Eigen::VectorXd durations_s_;
};

/// beta_d(t): the d-th time derivative (d = 0..5) of the monomial basis [1 t t^2 t^3 t^4 t^5].
Eigen::Matrix<double, 6, 1> monomialBasis(int derivative, double t_s);

}  // namespace aerotrack::planning
