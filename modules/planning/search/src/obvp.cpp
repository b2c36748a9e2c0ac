// OBVP of the double integrator (see obvp.hpp).
#include "aerotrack/planning/obvp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace aerotrack::planning {
namespace {

struct Coefficients {
  double a;  // 12 |d|^2
  double b;  // -12 d.(v0 + v1)
  double c;  // 4 (|v0|^2 + v0.v1 + |v1|^2)
};

Coefficients coefficients(const Eigen::Vector3d& p0, const Eigen::Vector3d& v0, const Eigen::Vector3d& p1,
                          const Eigen::Vector3d& v1) {
  const Eigen::Vector3d d = p1 - p0;
  return {12.0 * d.squaredNorm(), -12.0 * d.dot(v0 + v1), 4.0 * (v0.squaredNorm() + v0.dot(v1) + v1.squaredNorm())};
}

double costAt(const Coefficients& k, double rho, double t) {
  const double inv = 1.0 / t;
  return ((k.a * inv + k.b) * inv + k.c) * inv + rho * t;
}

// dJ/dT * T^4.
double stationarity(const Coefficients& k, double rho, double t) {
  const double t2 = t * t;
  return rho * t2 * t2 - k.c * t2 - 2.0 * k.b * t - 3.0 * k.a;
}

}  // namespace

double obvpCostForDuration(const Eigen::Vector3d& p0_m, const Eigen::Vector3d& v0_mps, const Eigen::Vector3d& p1_m,
                           const Eigen::Vector3d& v1_mps, double rho, double duration_s) {
  return costAt(coefficients(p0_m, v0_mps, p1_m, v1_mps), rho, duration_s);
}

ObvpSolution solveObvp(const Eigen::Vector3d& p0_m, const Eigen::Vector3d& v0_mps, const Eigen::Vector3d& p1_m,
                       const Eigen::Vector3d& v1_mps, double rho) {
  const Coefficients k = coefficients(p0_m, v0_mps, p1_m, v1_mps);
  const double scale = k.a + std::abs(k.b) + k.c;
  if (scale <= 1e-18) return {};
  // Positive roots of rho T^4 - c T^2 - 2 b T - 3 a lie in [lo, hi] (Fujiwara's bound on the polynomial
  // and on its reverse; a = 0 leaves T = 0 as a root of the reverse, so a small floor is used then).
  const double hi = 2.0 * std::max({std::sqrt(k.c / rho), std::cbrt(2.0 * std::abs(k.b) / rho),
                                    std::sqrt(std::sqrt(3.0 * k.a / rho))}) +
                    1e-9;
  double lo = 1e-6 * hi;
  if (k.a > 0.0) {
    const double reverse = 2.0 * std::max({2.0 * std::abs(k.b) / (3.0 * k.a), std::sqrt(k.c / (3.0 * k.a)),
                                           std::sqrt(std::sqrt(rho / (3.0 * k.a)))});
    lo = std::max(lo, 1.0 / reverse);
  }
  lo = std::min(lo, 0.5 * hi);
  constexpr int kSamples = 32;
  const double ratio = std::pow(hi / lo, 1.0 / kSamples);
  ObvpSolution best{std::numeric_limits<double>::infinity(), 0.0};
  double t_prev = lo;
  double g_prev = stationarity(k, rho, t_prev);
  for (int i = 1; i <= kSamples; ++i) {
    const double t = (i == kSamples) ? hi : t_prev * ratio;
    const double g = stationarity(k, rho, t);
    if (g_prev < 0.0 && g >= 0.0) {  // a local minimum of J: safeguarded Newton on the bracket
      double a = t_prev;
      double b = t;
      double root = 0.5 * (a + b);
      for (int it = 0; it < 50 && b - a > 1e-12 * b; ++it) {
        const double value = stationarity(k, rho, root);
        if (value < 0.0) {
          a = root;
        } else {
          b = root;
        }
        const double slope = 4.0 * rho * root * root * root - 2.0 * k.c * root - 2.0 * k.b;
        const double newton = slope > 0.0 ? root - value / slope : 0.5 * (a + b);
        const double next = (newton > a && newton < b) ? newton : 0.5 * (a + b);
        if (std::abs(next - root) <= 1e-13 * root) break;
        root = next;
      }
      const double cost = costAt(k, rho, root);
      if (cost < best.cost) best = {cost, root};
    }
    t_prev = t;
    g_prev = g;
  }
  if (!std::isfinite(best.cost)) {  // numerically flat: fall back to the better bound
    const double c_lo = costAt(k, rho, lo);
    const double c_hi = costAt(k, rho, hi);
    best = c_lo < c_hi ? ObvpSolution{c_lo, lo} : ObvpSolution{c_hi, hi};
  }
  return best;
}

ObvpCubic obvpCubic(const Eigen::Vector3d& p0_m, const Eigen::Vector3d& v0_mps, const Eigen::Vector3d& p1_m,
                    const Eigen::Vector3d& v1_mps, double duration_s) {
  const double t = duration_s;
  const Eigen::Vector3d dp = p1_m - p0_m - v0_mps * t;
  const Eigen::Vector3d dv = v1_mps - v0_mps;
  ObvpCubic cubic;
  cubic.a0_mps2 = 6.0 * dp / (t * t) - 2.0 * dv / t;
  cubic.jerk_mps3 = -12.0 * dp / (t * t * t) + 6.0 * dv / (t * t);
  return cubic;
}

}  // namespace aerotrack::planning
