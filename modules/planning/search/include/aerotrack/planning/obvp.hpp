// The optimal boundary value problem (OBVP) of the double integrator, the heuristic D(x_c, x_g)
// of the kinodynamic search (paper Sect. V-B; Zhou et al., "Robust and efficient quadrotor trajectory
// generation for fast autonomous flight", RA-L 2019, Sect. III-B). Between (p0, v0) and (p1, v1), with
// the input u = p'' (acceleration) and a free duration T, minimise J = integral_0^T |u|^2 dt + rho T.
// For a fixed T the optimum is a cubic per axis with cost, with d = p1 - p0,
//   J(T) = 12 |d|^2 / T^3 - 12 d.(v0 + v1) / T^2 + 4 (|v0|^2 + v0.v1 + |v1|^2) / T + rho T,
// and the best T is a positive root of dJ/dT * T^4 = rho T^4 - c T^2 - 2 b T - 3 a (a, b, c the three
// numerators above). That quartic has at most three positive roots (Descartes); they are bracketed on a
// geometric grid between root bounds and polished by safeguarded Newton, and the smallest J among them is taken.
// All functions are pure, allocation-free and thread-safe.
#pragma once

#include <Eigen/Core>

namespace aerotrack::planning {

/// Optimal duration and cost of the OBVP.
struct ObvpSolution {
  double cost = 0.0;        ///< integral |u|^2 dt + rho T at the optimum (m^2/s^3 + rho s).
  double duration_s = 0.0;  ///< The optimal T (0 when the two states coincide).
};

/// The cost J(T) for a fixed duration T > 0 (see the file comment). Positions in m, velocities in m/s.
double obvpCostForDuration(const Eigen::Vector3d& p0_m, const Eigen::Vector3d& v0_mps, const Eigen::Vector3d& p1_m,
                           const Eigen::Vector3d& v1_mps, double rho, double duration_s);

/// min over T > 0 of J(T), rho > 0. Identical states give {0, 0}. Relative error of the cost below 1e-9
/// against a dense 1D search (tested), except in near-tangent cases where two stationary points lie
/// within one bracketing step (32 geometric steps between the root bounds), where the result can be a
/// local minimum slightly above the global one.
ObvpSolution solveObvp(const Eigen::Vector3d& p0_m, const Eigen::Vector3d& v0_mps, const Eigen::Vector3d& p1_m,
                       const Eigen::Vector3d& v1_mps, double rho);

/// The optimal cubic of a fixed duration T > 0, as p(t) = p0 + v0 t + a0 t^2 / 2 + jerk t^3 / 6.
struct ObvpCubic {
  Eigen::Vector3d a0_mps2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d jerk_mps3 = Eigen::Vector3d::Zero();
};
ObvpCubic obvpCubic(const Eigen::Vector3d& p0_m, const Eigen::Vector3d& v0_mps, const Eigen::Vector3d& p1_m,
                    const Eigen::Vector3d& v1_mps, double duration_s);

}  // namespace aerotrack::planning
