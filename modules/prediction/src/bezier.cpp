// Bernstein basis, binomials and the closed-form acceleration energy (see bezier.hpp).
#include "aerotrack/prediction/bezier.hpp"

#include <array>

namespace aerotrack::prediction {
namespace {

constexpr int kMaxN = 2 * kMaxBezierDegree;

constexpr std::array<std::array<double, kMaxN + 1>, kMaxN + 1> makeBinomials() {
  std::array<std::array<double, kMaxN + 1>, kMaxN + 1> c{};
  for (int n = 0; n <= kMaxN; ++n) {
    c[static_cast<std::size_t>(n)][0] = 1.0;
    for (int k = 1; k <= n; ++k) {
      c[static_cast<std::size_t>(n)][static_cast<std::size_t>(k)] =
          c[static_cast<std::size_t>(n) - 1][static_cast<std::size_t>(k) - 1] +
          (k < n ? c[static_cast<std::size_t>(n) - 1][static_cast<std::size_t>(k)] : 0.0);
    }
  }
  return c;
}

constexpr auto kBinomials = makeBinomials();

}  // namespace

double binomial(int n, int k) {
  return kBinomials[static_cast<std::size_t>(n)][static_cast<std::size_t>(k)];
}

void bernsteinBasis(int degree, double s, std::span<double> out) {
  // Powers of s and (1 - s), then the products; exact for the small degrees used.
  std::array<double, kMaxBezierDegree + 1> s_pow{};
  std::array<double, kMaxBezierDegree + 1> one_minus_pow{};
  s_pow[0] = 1.0;
  one_minus_pow[0] = 1.0;
  for (int i = 1; i <= degree; ++i) {
    s_pow[static_cast<std::size_t>(i)] = s_pow[static_cast<std::size_t>(i) - 1] * s;
    one_minus_pow[static_cast<std::size_t>(i)] = one_minus_pow[static_cast<std::size_t>(i) - 1] * (1.0 - s);
  }
  for (int i = 0; i <= degree; ++i) {
    out[static_cast<std::size_t>(i)] =
        binomial(degree, i) * s_pow[static_cast<std::size_t>(i)] * one_minus_pow[static_cast<std::size_t>(degree - i)];
  }
}

void accelerationEnergyMatrix(int degree, double duration_s, Eigen::Ref<Eigen::MatrixXd> out) {
  const int m = degree - 2;  // degree of the acceleration curve
  // Q = D2' M D2 / T^3 with (D2 c)_j = n(n-1) (c_j - 2 c_{j+1} + c_{j+2}), written out entrywise.
  const double scale = static_cast<double>(degree * (degree - 1));
  const std::array<double, 3> stencil{scale, -2.0 * scale, scale};
  out.setZero();
  for (int i = 0; i <= m; ++i) {
    for (int j = 0; j <= m; ++j) {
      const double gram = binomial(m, i) * binomial(m, j) / (static_cast<double>(2 * m + 1) * binomial(2 * m, i + j));
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
          out(i + a, j + b) += stencil[static_cast<std::size_t>(a)] * gram * stencil[static_cast<std::size_t>(b)];
        }
      }
    }
  }
  out /= duration_s * duration_s * duration_s;
}

}  // namespace aerotrack::prediction
