// DenseQpSolver: a compact dense quadratic-programming solver for the small problems of the target
// prediction (issue 7, item 1; the paper's Sect. V-A fits the predicted trajectory "as a QP"). It
// minimises 1/2 x'Hx + g'x subject to A_eq x = b_eq and A_in x >= b_in, with H symmetric positive
// definite, by the dual active-set method of Goldfarb and Idnani ("A numerically stable dual method
// for solving strictly convex quadratic programs", Math. Programming 27, 1983):
//  - it starts at the unconstrained minimum -H^-1 g, adds the equalities, then repeatedly adds a
//    violated inequality, dropping active ones whose multiplier would turn negative, so every
//    iterate is the optimum of a subproblem and the objective only grows;
//  - numerically, it never forms H^-1: with H = L L' it keeps J = L^-T Q and the upper-triangular R
//    of the QR factorisation of J' N (N: the active normals), updated by Givens rotations when a
//    constraint is added or dropped (the paper's Sect. 4, as in quadprog and eiquadprog);
//  - infeasibility is detected as dual unboundedness (a violated constraint that neither a primal
//    nor a dual step can satisfy), and dependent constraints (duplicates, an inequality on an
//    equality's row) are never added;
//  - warm start: the active set of a previous solution is re-imposed first as equalities; those
//    whose multiplier comes out negative are released and the rest re-imposed, until the start is
//    dual feasible; then the ordinary iterations finish the job (few or none when the guess is right).
// Allocation: only in create(), for the maximum problem size; solve() never allocates.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::prediction {

struct DenseQpSolverParams {
  int max_variables = 16;               ///< Largest n the solver accepts; >= 1.
  int max_equalities = 8;               ///< Largest number of rows of A_eq; >= 0.
  int max_inequalities = 64;            ///< Largest number of rows of A_in; >= 0.
  int max_iterations = 200;             ///< Cap on constraint additions plus removals; >= 1.
  double feasibility_tolerance = 1e-9;  ///< A row violated by more than this times its norm is violated; > 0.
};

enum class QpStatus : std::uint8_t {
  kOptimal,              ///< solution() is the minimiser; activeInequalities() its active set.
  kInfeasible,           ///< The constraints have no common point (or the equalities are inconsistent).
  kMaxIterations,        ///< The iteration cap was reached; solution() is the last iterate (not feasible).
  kNotPositiveDefinite,  ///< The Cholesky factorisation of H failed.
  kInvalidProblem,       ///< Sizes inconsistent or above the maxima, or a non-finite entry.
};
const char* toString(QpStatus status);

/// One problem; the matrices are read, not copied. Rows of A_eq / A_in are constraints.
struct QpProblem {
  Eigen::Ref<const Eigen::MatrixXd> hessian;   ///< H, n x n, symmetric positive definite (lower half is read).
  Eigen::Ref<const Eigen::VectorXd> gradient;  ///< g, n.
  Eigen::Ref<const Eigen::MatrixXd> a_eq;      ///< m_eq x n (may have 0 rows).
  Eigen::Ref<const Eigen::VectorXd> b_eq;      ///< m_eq.
  Eigen::Ref<const Eigen::MatrixXd> a_in;      ///< m_in x n (may have 0 rows).
  Eigen::Ref<const Eigen::VectorXd> b_in;      ///< m_in.
};

struct QpResult {
  QpStatus status = QpStatus::kInvalidProblem;
  double objective = 0.0;  ///< 1/2 x'Hx + g'x at solution() (for kOptimal).
  int iterations = 0;      ///< Constraint additions plus removals (equalities and warm start included).
};

/// Thread safety: none (one owner). Allocation: create() only.
class DenseQpSolver {
 public:
  static rt::Expected<DenseQpSolver> create(const DenseQpSolverParams& params);

  /// Solves `problem`. warm_start_active: indices of rows of A_in believed active at the solution
  /// (e.g. activeInequalities() of the last solve of a similar problem); out-of-range or repeated
  /// indices are ignored. Never allocates.
  QpResult solve(const QpProblem& problem, std::span<const int> warm_start_active = {});

  /// The last solve's x (n entries).
  Eigen::VectorBlock<const Eigen::VectorXd> solution() const { return x_.head(n_); }
  /// Rows of A_in active at the last solution (meaningful for kOptimal), in the order added.
  std::span<const int> activeInequalities() const;
  /// Lagrange multipliers (>= 0) of activeInequalities(), same order.
  std::span<const double> inequalityMultipliers() const;
  const DenseQpSolverParams& params() const { return params_; }

 private:
  explicit DenseQpSolver(const DenseQpSolverParams& params);

  bool factorise(const Eigen::Ref<const Eigen::MatrixXd>& hessian);
  /// Row `row` of the equalities (row < m_eq) or of the inequalities (row - m_eq), as a normal.
  void loadNormal(const QpProblem& problem, int constraint);
  /// d = J' n, z = J2 d2 (primal direction), r = R^-1 d1 (dual direction); returns |d2|^2 <= tiny |d|^2.
  bool computeDirections();
  void addConstraint(int constraint, double multiplier);
  void dropConstraint(int position);
  double slack(const QpProblem& problem, int constraint) const;
  void resetToUnconstrained(const QpProblem& problem);
  /// Adds the equalities as active constraints; false if they are inconsistent.
  bool addEqualities(const QpProblem& problem, int& iterations);
  /// Full step onto `constraint` as if it were an equality and adds it; false (nothing done) if it
  /// depends on the active ones.
  bool stepOntoAsEquality(const QpProblem& problem, int constraint);
  double violationTolerance(int inequality) const;

  DenseQpSolverParams params_;
  int n_ = 0;
  int m_eq_ = 0;
  int m_in_ = 0;
  int q_ = 0;          ///< Active constraints (equalities first).
  Eigen::MatrixXd l_;  ///< Cholesky factor of H (lower).
  Eigen::MatrixXd j_;  ///< L^-T Q.
  Eigen::MatrixXd r_;  ///< Upper triangular, q x q.
  Eigen::VectorXd x_;
  Eigen::VectorXd normal_;  ///< The constraint being added.
  Eigen::VectorXd d_, z_, r_dir_;
  Eigen::VectorXd u_;            ///< Multipliers of the active constraints.
  Eigen::VectorXd row_norm_in_;  ///< |row| of each inequality (for the tolerance).
  Eigen::VectorXd slack_in_;
  std::vector<int> active_;         ///< Constraint ids: i < m_eq an equality, else inequality i - m_eq.
  std::vector<int> active_in_out_;  ///< activeInequalities() storage.
  std::vector<double> u_in_out_;
  std::vector<int> warm_;           ///< Scratch for the warm-start set.
  std::vector<char> in_warm_;       ///< Per inequality: in warm_.
  std::vector<char> is_active_in_;  ///< Per inequality: in the active set.
  int active_in_count_ = 0;
};

}  // namespace aerotrack::prediction
