// A square banded linear system solved by LU factorisation without pivoting, in O(N (p + q)^2) time
// for N unknowns, lower bandwidth p and upper bandwidth q. It carries the minimum-jerk coefficient map
// (min_jerk_spline.hpp; Wang et al., "Geometrically constrained trajectory optimization for
// multicopters", T-RO 2022, Sect. IV: the matrix of the optimality conditions is banded, so the map
// from waypoints and durations to coefficients, and its adjoint for gradients, cost O(M)).
// No pivoting is safe for that matrix: every diagonal entry is a nonzero constant or T^5 of a
// positive duration, and the tests compare the solutions with a dense, pivoted reference.
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace aerotrack::planning {

/// N x 3 right-hand sides and solutions (x, y, z columns), rows contiguous.
using RowMatrixX3d = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

class BandedSystem {
 public:
  /// Sizes the system (N >= 1, bandwidths >= 0) and zeroes it. Allocates only when the band grows.
  void resize(int n, int lower, int upper);
  /// Zeroes every entry, keeping the size.
  void setZero();

  int size() const { return n_; }
  /// Entry (i, j); |i - j| within the bandwidths (not checked in release builds).
  double& operator()(std::ptrdiff_t i, std::ptrdiff_t j) { return band_[index(i, j)]; }
  double operator()(std::ptrdiff_t i, std::ptrdiff_t j) const { return band_[index(i, j)]; }

  /// Replaces the matrix by its LU factors (unit lower L below the diagonal, U on and above it).
  /// False if a pivot is zero or not finite (the solves are then meaningless).
  bool factorize();
  /// Solves A X = B in place (B: N rows of 3, row-major so each row is contiguous), after factorize().
  void solve(RowMatrixX3d& b) const;
  /// Solves A^T X = B in place, after factorize() (the adjoint, for gradients).
  void solveAdjoint(RowMatrixX3d& b) const;

 private:
  std::size_t index(std::ptrdiff_t i, std::ptrdiff_t j) const {
    return static_cast<std::size_t>(i * width_ + (j - i + lower_));
  }

  int n_ = 0;
  int lower_ = 0;
  int upper_ = 0;
  int width_ = 1;
  std::vector<double> band_;  // row-major band: row i holds columns i - lower .. i + upper
};

}  // namespace aerotrack::planning
