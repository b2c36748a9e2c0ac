#include "aerotrack/estimation/look_spread.hpp"

#include <algorithm>
#include <cmath>

namespace aerotrack::estimation {

namespace {

/// The median of values[0, n) (the mean of the two middle ones for even n); reorders them. n > 0.
double medianOf(std::array<double, LookSpread::kWindow>& values, std::size_t n) {
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(n / 2);
  std::nth_element(values.begin(), mid, values.begin() + static_cast<std::ptrdiff_t>(n));
  if (n % 2 == 1) return *mid;
  const double upper = *mid;
  const double lower = *std::max_element(values.begin(), mid);
  return 0.5 * (lower + upper);
}

}  // namespace

void LookSpread::push(double distance) {
  if (!std::isfinite(distance)) return;
  window_[next_] = distance;
  next_ = (next_ + 1) % kWindow;
  count_ = std::min(count_ + 1, kWindow);
  // At most 64 values and one push per detection: a copy and two selections beat an order-statistics tree.
  std::array<double, kWindow> scratch = window_;
  median_ = medianOf(scratch, count_);
  for (std::size_t i = 0; i < count_; ++i) scratch[i] = std::abs(window_[i] - median_);
  mad_ = medianOf(scratch, count_);
}

}  // namespace aerotrack::estimation
