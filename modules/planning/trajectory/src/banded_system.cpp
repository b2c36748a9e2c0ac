// Banded LU without pivoting: see banded_system.hpp.
#include "aerotrack/planning/banded_system.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace aerotrack::planning {

void BandedSystem::resize(int n, int lower, int upper) {
  n_ = n;
  lower_ = lower;
  upper_ = upper;
  width_ = lower + upper + 1;
  band_.assign(static_cast<std::size_t>(n) * static_cast<std::size_t>(width_), 0.0);
}

void BandedSystem::setZero() {
  std::fill(band_.begin(), band_.end(), 0.0);
}

bool BandedSystem::factorize() {
  // Raw row pointers: the inner loop is a contiguous axpy within the band (the hot path of every
  // cost evaluation).
  for (int k = 0; k < n_; ++k) {
    const double pivot = (*this)(k, k);
    if (pivot == 0.0 || !std::isfinite(pivot)) return false;
    const int last_row = std::min(k + lower_, n_ - 1);
    const int count = std::min(k + upper_, n_ - 1) - k;  // columns k+1 .. k+count
    const double* row_k = &(*this)(k, k) + 1;
    for (int i = k + 1; i <= last_row; ++i) {
      double& l_ik = (*this)(i, k);
      if (l_ik == 0.0) continue;
      l_ik /= pivot;
      const double l = l_ik;
      double* row_i = &l_ik + 1;
      for (int c = 0; c < count; ++c) row_i[c] -= l * row_k[c];
    }
  }
  return true;
}

namespace {

// row_i -= l * row_k for rows of 3.
inline void subtractRow(double* row_i, const double* row_k, double l) {
  row_i[0] -= l * row_k[0];
  row_i[1] -= l * row_k[1];
  row_i[2] -= l * row_k[2];
}

}  // namespace

void BandedSystem::solve(RowMatrixX3d& b) const {
  double* x = b.data();
  const std::ptrdiff_t n = n_;
  // L y = b (unit diagonal), then U x = y.
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    for (std::ptrdiff_t k = std::max<std::ptrdiff_t>(0, i - lower_); k < i; ++k)
      subtractRow(x + 3 * i, x + 3 * k, (*this)(i, k));
  }
  for (std::ptrdiff_t i = n - 1; i >= 0; --i) {
    for (std::ptrdiff_t k = i + 1; k <= std::min<std::ptrdiff_t>(i + upper_, n - 1); ++k)
      subtractRow(x + 3 * i, x + 3 * k, (*this)(i, k));
    const double inv = 1.0 / (*this)(i, i);
    x[3 * i] *= inv;
    x[3 * i + 1] *= inv;
    x[3 * i + 2] *= inv;
  }
}

void BandedSystem::solveAdjoint(RowMatrixX3d& b) const {
  double* x = b.data();
  const std::ptrdiff_t n = n_;
  // A^T = U^T L^T: U^T z = b (forward), then L^T x = z (backward, unit diagonal).
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    for (std::ptrdiff_t k = std::max<std::ptrdiff_t>(0, i - upper_); k < i; ++k)
      subtractRow(x + 3 * i, x + 3 * k, (*this)(k, i));
    const double inv = 1.0 / (*this)(i, i);
    x[3 * i] *= inv;
    x[3 * i + 1] *= inv;
    x[3 * i + 2] *= inv;
  }
  for (std::ptrdiff_t i = n - 1; i >= 0; --i) {
    for (std::ptrdiff_t k = i + 1; k <= std::min<std::ptrdiff_t>(i + lower_, n - 1); ++k)
      subtractRow(x + 3 * i, x + 3 * k, (*this)(k, i));
  }
}

}  // namespace aerotrack::planning
