// Bezier-curve building blocks of the target prediction (the paper's Sect. V-A, eq. for P_t(t)):
// the Bernstein basis b_i^n(s) = C(n,i) s^i (1-s)^(n-i) on normalised time s in [0, 1], the
// hodograph (derivative) control points, and the closed-form acceleration energy. With a curve of
// duration T, p(t) = sum_i c_i b_i^n(s), s = t / T, so
//   p'(t)  = n/T       sum_{i<n}   (c_{i+1} - c_i)             b_i^{n-1}(s)
//   p''(t) = n(n-1)/T^2 sum_{i<n-1} (c_{i+2} - 2 c_{i+1} + c_i) b_i^{n-2}(s)
// and, by the convex hull property, a bound on the hodograph's control points bounds the velocity
// (acceleration) on the whole curve. The energy int_0^T |p''(t)|^2 dt = c' Q c with
// Q = D2' M D2 / T^3, D2 the second-difference matrix scaled by n(n-1) and M the Gram matrix of the
// Bernstein basis of degree n-2: M_ij = C(m,i) C(m,j) / ((2m+1) C(2m,i+j)).
// All functions are pure, thread-safe and allocation-free.
#pragma once

#include <span>

#include <Eigen/Core>

namespace aerotrack::prediction {

inline constexpr int kMaxBezierDegree = 9;

/// Binomial coefficient C(n, k) for 0 <= k <= n <= 2 * kMaxBezierDegree.
double binomial(int n, int k);

/// out[i] = b_i^degree(s), i = 0..degree (out.size() >= degree + 1). Any s evaluates the polynomial;
/// the convex hull property holds for s in [0, 1].
void bernsteinBasis(int degree, double s, std::span<double> out);

/// Q with int_0^T |p''(t)|^2 dt = c' Q c for one axis of a degree-`degree` curve of duration
/// `duration_s` (degree >= 2, duration_s > 0). out: (degree+1) x (degree+1). Units: 1/s^3.
void accelerationEnergyMatrix(int degree, double duration_s, Eigen::Ref<Eigen::MatrixXd> out);

}  // namespace aerotrack::prediction
