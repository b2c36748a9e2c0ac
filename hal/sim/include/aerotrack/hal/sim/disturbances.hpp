// Disturbances of the closed-loop simulator (issue 20): the drift and jumps of the drone's own
// pose estimate (visual-inertial odometry), and wind.
//
// Odometry drift. A real drone's pose comes from visual-inertial odometry (VIO), whose frame O
// wanders away from the world W: position and yaw are unobservable to VIO, so their errors grow as
// the drone flies (typically 0.5-2 % of the distance flown, plus a yaw error), and jump when the
// estimator relocalises (loop closure, reset). Here O is a rigid transform T_OW (a yaw about z and
// a translation): p_O = R_z(yaw) p_W + t. It is a random walk driven by the distance flown and by
// time: over an update in which the drone flies ds metres in dt seconds, the increments are
// independent zero-mean normals with
//   var(dx) = var(dy) = a_xy^2 ds + b^2 dt,  var(dz) = a_z^2 ds + b^2 dt,  var(dyaw) = c^2 ds + e^2 dt
// (a_xy = position_m_per_sqrt_m, a_z = z_m_per_sqrt_m, b = position_m_per_sqrt_s,
// c = yaw_rad_per_sqrt_m, e = yaw_rad_per_sqrt_s), so after a flight of length s and duration T
// the translation error has variance a^2 s + b^2 T per axis: a Wiener process in the distance flown
// (the relative pose error of VIO grows with the distance, not the time, when the drone moves).
// An increment and a jump (dp, dyaw) both act about the drone: its reported position steps by dp
// and the frame turns by dyaw about the drone's reported position, so a yaw error changes nothing
// where the drone is and grows the position error as it flies on (as a VIO heading error does).
// Jumps: at listed times, and at seeded Poisson times (a horizontal step of a given size in a
// random direction, and a yaw step of a given size and random sign).
//
// Calibration (the values are the scenario's, the defaults are 0: no drift). 0.5-2 % of the
// distance flown is the range usually quoted for the translation drift of the monocular VIO systems
// compared by Delmerico & Scaramuzza, "A Benchmark Comparison of Monocular Visual-Inertial Odometry
// Algorithms for Flying Robots", ICRA 2018 (EuRoC MAV sequences: OKVIS, ROVIO, VINS-Mono, SVO+MSF,
// MSCKF); OpenVINS (Geneva et al., ICRA 2020) and VINS-Mono (Qin et al., T-RO 2018) report errors of
// the same order on EuRoC. (The range is taken as quoted; the papers' tables were not re-read to
// write this, and the drift of a given drone depends on its camera, its scene and its speed.) A
// random walk gives an error std that grows as sqrt(s), not s; config/scenarios/drift.yaml sets a_xy
// so that the 1-sigma horizontal error reaches the pessimistic 2 % of the distance at s = 100 m:
//   sqrt(2 a^2 s) = 0.02 s  =>  a = 0.02 sqrt(s / 2) = 0.14 m/sqrt(m).
//
// Wind. The wind at the drone is a mean plus gusts, each world axis a first-order Gauss-Markov
// process g' = -g / tau + sigma sqrt(2 / tau) w (w white): stationary std sigma, autocorrelation
// exp(-|lag| / tau). This is the form of the Dryden model's longitudinal spectrum
// (MIL-F-8785C / MIL-HDBK-1797: Phi_u(Omega) = sigma_u^2 (2 L_u / pi) / (1 + (L_u Omega)^2)) with the
// turbulence frozen and carried past the drone at the mean wind speed U, tau = L / U; the Dryden
// lateral and vertical spectra are second order and are approximated by the same first-order form.
// Discretised exactly: g(k+1) = phi g(k) + sigma sqrt(1 - phi^2) n, phi = exp(-dt / tau), started
// from the stationary distribution. The wind acts as a force through two drag terms on the
// air-relative velocity v_rel = w - v:
//   - the rotor (blade-flapping and induced) drag, linear in the body frame: m R D R^T v_rel,
//     D = QuadrotorParams::drag_B_per_s (Faessler, Franchi & Scaramuzza, "Differential flatness of
//     quadrotor dynamics subject to rotor drag", RA-L 2018). The vehicle already applies -m R D R^T v
//     (its still-air drag); the wind adds m R D R^T w;
//   - an optional quadratic body drag 0.5 rho Cd A |v_rel| v_rel (body_cd_area_m2 = Cd A).
// The force is evaluated at the start of each physics step and held over it (the steps are 2 ms).
// The flight controller does not know the wind: it rejects the force as a disturbance.
//
// Deterministic: both models draw from the std::mt19937_64 streams they are given.
#pragma once

#include <cstddef>
#include <random>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "aerotrack/hal/sim/quadrotor.hpp"
#include "aerotrack/hal/sim/scenario.hpp"

namespace aerotrack::hal::sim {

/// The odometry frame's pose in the world, T_OW: p_O = R_z(yaw_rad) p_W + t_m.
struct OdometryFrameError {
  Eigen::Vector3d t_m = Eigen::Vector3d::Zero();
  double yaw_rad = 0.0;

  Eigen::Matrix3d rotationOW() const { return Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }
  Eigen::Vector3d toOdometry(const Eigen::Vector3d& p_W_m) const { return rotationOW() * p_W_m + t_m; }
  Eigen::Vector3d toWorld(const Eigen::Vector3d& p_O_m) const { return rotationOW().transpose() * (p_O_m - t_m); }
};

/// The vehicle's state expressed in the odometry frame (what VIO reports and what the flight
/// controller flies): position, velocity, acceleration and attitude turned and moved by T_OW; the
/// body rates, thrust and ground contact unchanged.
QuadrotorState inOdometryFrame(const OdometryFrameError& T_OW, const QuadrotorState& state_W);

/// A world-frame setpoint expressed in the odometry frame (for truth-fed followers: the flight
/// controller takes its setpoints in O).
hal::Setpoint inOdometryFrame(const OdometryFrameError& T_OW, const hal::Setpoint& setpoint_W);

/// The drift and jumps of T_OW (see the file comment). Value type; one thread.
class OdometryDrift {
 public:
  /// walk_rng draws the random walk, jump_rng the seeded jumps (two streams: changing one does not
  /// move the other). start_p_W_m: the drone's position at t = 0, where the frames coincide.
  OdometryDrift(const OdometryDriftSpec& spec, std::mt19937_64 walk_rng, std::mt19937_64 jump_rng,
                const Eigen::Vector3d& start_p_W_m);

  /// Advances to t_s (seconds since the start; not before the last update) with the drone now at
  /// p_W_m (the distance flown is the straight line from the last update's position, so update
  /// often: the simulation does at the odometry rate). Applies the jumps due by t_s.
  void update(double t_s, const Eigen::Vector3d& p_W_m);

  const OdometryFrameError& error() const { return error_; }
  double distanceFlownM() const { return distance_m_; }
  std::size_t jumpsApplied() const { return jumps_applied_; }

 private:
  /// Steps the drone's reported position by dp_O_m and turns the frame by dyaw_rad about it.
  void apply(const Eigen::Vector3d& dp_O_m, double dyaw_rad, const Eigen::Vector3d& p_W_m);
  double drawNextRandomJumpS(double after_s);

  OdometryDriftSpec spec_;
  std::mt19937_64 walk_rng_, jump_rng_;
  OdometryFrameError error_;
  Eigen::Vector3d last_p_W_m_;
  double last_t_s_ = 0.0;
  double distance_m_ = 0.0;
  std::size_t next_jump_ = 0;
  double next_random_jump_s_ = 0.0;
  std::size_t jumps_applied_ = 0;
};

/// Mean wind plus first-order Gauss-Markov gusts per world axis (see the file comment).
class WindField {
 public:
  /// The gusts start from their stationary distribution (drawn from rng).
  WindField(const WindSpec& spec, std::mt19937_64 rng);
  /// Advances the gusts by dt_s (exact discretisation; dt_s <= 0: no-op).
  void step(double dt_s);
  /// Wind velocity in W: mean + gust.
  Eigen::Vector3d velocityW() const { return spec_.mean_W_mps + gust_W_mps_; }
  const Eigen::Vector3d& gustW() const { return gust_W_mps_; }
  const WindSpec& spec() const { return spec_; }

 private:
  WindSpec spec_;
  std::mt19937_64 rng_;
  Eigen::Vector3d gust_W_mps_ = Eigen::Vector3d::Zero();
};

/// The force the wind adds to the vehicle (W, N), beyond the still-air drag the vehicle model
/// applies itself: m R D R^T w (the linear rotor drag on the air-relative velocity, less its
/// still-air part) + 0.5 rho CdA |w - v| (w - v) (quadratic body drag). Zero for w = 0 and CdA = 0.
Eigen::Vector3d windForceW(const QuadrotorParams& params, const QuadrotorState& state,
                           const Eigen::Vector3d& wind_W_mps, const WindSpec& spec);

}  // namespace aerotrack::hal::sim
