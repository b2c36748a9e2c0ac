// Rigid-body quadrotor for the closed-loop simulator, at the level a flight controller's attitude
// loop sees it: the input is a collective thrust and a body-rate command (what a geometric attitude
// controller sends to the inner rate loop); the rate loop and the motors are first-order lags.
//   T'  = (T_c - T) / tau_T,          w' = (w_c - w) / tau_w          (w: body rates in B)
//   R'  = R [w]x
//   m a = R e3 T - m g e3 - m R D R^T v + F_ext                       (D = diag(drag_B_per_s))
// F_ext: an external force in W (wind, hal/sim/disturbances.hpp), an input of each step, held
// constant over it; the flight controller does not know it (it rejects it as a disturbance).
// with the commands clamped to the vehicle's limits, and a flat ground at z = 0.
//
// Discretisation of one step of length dt (commands held constant over the step):
//   - lags: exact, T(dt) = T_c + (T0 - T_c) exp(-dt/tau); the step also uses the exact mean of the
//     lagged thrust and rate over the step, e.g. mean(T) = T_c + (T0 - T_c) tau/dt (1 - exp(-dt/tau));
//   - attitude: R(dt) = R0 exp(dt [mean w]x) by Rodrigues' formula (exact for a constant rate, and for
//     any rate of fixed direction), then re-orthonormalised;
//   - translation: exact solution of the linear ODE v' = c - R D R^T v with the attitude frozen at
//     the step's midpoint R_mid = R0 exp(dt/2 [mean w]x) and the mean thrust; in B_mid the drag is
//     diagonal so each axis is  u(dt) = u0 e + c (1 - e)/d,  dp = u0 (1 - e)/d + c (dt - (1 - e)/d)/d,
//     e = exp(-d dt). Exact for constant attitude (free fall, level climb, drag decay); second order
//     in dt when the attitude turns during the step.
// Ground contact (z = 0): a step that would end below the ground ends on it instead: z = 0, v = 0,
// body rates 0 and the attitude levelled to its heading (the vehicle settles on its legs). On the
// ground the vehicle stays put (no sliding, no tipping, no spinning) until the vertical component of
// its thrust (plus that of F_ext) exceeds its weight; it then lifts off within that step.
#pragma once

#include <type_traits>

#include <Eigen/Core>

#include "aerotrack/rt/bitwise_copyable.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::sim {

/// Physical and flight-controller parameters. Defaults: a 1 kg quadrotor with thrust-to-weight 2.5.
struct QuadrotorParams {
  double mass_kg = 1.0;
  double gravity_mps2 = 9.81;
  /// Maximum collective thrust. Default 2.5 m g for the default mass and gravity; it does NOT
  /// follow mass_kg automatically: set it when changing the mass.
  double max_thrust_n = 2.5 * 1.0 * 9.81;
  double min_thrust_n = 0.0;
  /// Limit of the body-rate command per body axis (roll, pitch, yaw), rad/s.
  Eigen::Vector3d max_body_rate_radps = Eigen::Vector3d(6.0, 6.0, 3.0);
  /// First-order time constant of the inner rate loop (actual rate follows the command); 0: instant.
  double body_rate_time_constant_s = 0.03;
  /// First-order time constant of the motors' collective thrust; 0: instant.
  double thrust_time_constant_s = 0.02;
  /// Linear drag per body axis (FLU): drag acceleration = -R diag(drag_B_per_s) R^T v, 1/s.
  Eigen::Vector3d drag_B_per_s = Eigen::Vector3d(0.3, 0.3, 0.1);
};

/// Full state of the vehicle. W: world ENU (z up); B: body FLU.
struct QuadrotorState {
  Eigen::Vector3d p_W_m = Eigen::Vector3d::Zero();      ///< Position of B in W.
  Eigen::Vector3d v_W_mps = Eigen::Vector3d::Zero();    ///< Velocity of B in W, expressed in W.
  Eigen::Matrix3d R_WB = Eigen::Matrix3d::Identity();   ///< Attitude: rotates B vectors into W.
  Eigen::Vector3d w_B_radps = Eigen::Vector3d::Zero();  ///< Body rates (of B w.r.t. W), expressed in B.
  double thrust_n = 0.0;                                ///< Actual collective thrust along body z.
  Eigen::Vector3d a_W_mps2 = Eigen::Vector3d::Zero();   ///< Acceleration at the end of the last step (0 on the ground).
  bool on_ground = false;                               ///< Resting on the ground plane z = 0.
};

/// What an attitude controller sends to the flight controller's rate loop.
struct QuadrotorCommand {
  double thrust_n = 0.0;                                ///< Collective thrust along body z, N.
  Eigen::Vector3d w_B_radps = Eigen::Vector3d::Zero();  ///< Body-rate command in B, rad/s.
};

}  // namespace aerotrack::hal::sim

// QuadrotorState may travel through an rt::LatestSlot (plain arrays of doubles and a bool).
static_assert(std::is_standard_layout_v<aerotrack::hal::sim::QuadrotorState>);
template <>
struct aerotrack::rt::IsBitwiseCopyable<aerotrack::hal::sim::QuadrotorState> : std::true_type {};

namespace aerotrack::hal::sim {

/// The simulated vehicle. Value type: copyable, no heap memory. Not thread-safe: one thread steps
/// it and reads its state (copy the state to share it).
class Quadrotor {
 public:
  /// Validates the parameters (positive mass, ordered thrust limits, positive rate limits,
  /// non-negative time constants and drag, all finite) and the initial state (finite, p_W_m.z >= 0,
  /// R_WB a rotation to 1e-6, which is then re-orthonormalised; on_ground requires z <= 1e-6, and
  /// sets z, v and the body rates to 0). Allocates only for an error message.
  static rt::Expected<Quadrotor> create(const QuadrotorParams& params, const QuadrotorState& initial);

  /// Advances the vehicle by dt_s seconds with the command held over the step (see the file
  /// comment). The thrust command is clamped to [min_thrust_n, max_thrust_n] and each body-rate
  /// component to +-max_body_rate_radps; non-finite command values count as min thrust / zero rate.
  /// dt_s <= 0 or not finite: no-op. Allocation-free; exp() is re-evaluated only when dt_s changes.
  /// f_ext_W_n: external force in W held over the step (see the file comment); non-finite: none.
  /// A zero force leaves the step bit-identical to a step without one.
  void step(const QuadrotorCommand& command, double dt_s, const Eigen::Vector3d& f_ext_W_n = Eigen::Vector3d::Zero());

  const QuadrotorState& state() const { return state_; }
  const QuadrotorParams& params() const { return params_; }

 private:
  Quadrotor(const QuadrotorParams& params, const QuadrotorState& initial);
  void updateCoefficients(double dt_s);
  void touchDown();

  QuadrotorParams params_;
  QuadrotorState state_;
  // Discretisation coefficients for the last dt (see the file comment), cached.
  double coeff_dt_s_ = -1.0;
  double thrust_decay_ = 0.0;  ///< exp(-dt / tau_T)
  double thrust_mean_ = 0.0;   ///< tau_T / dt (1 - exp(-dt / tau_T))
  double rate_decay_ = 0.0;
  double rate_mean_ = 0.0;
  Eigen::Vector3d drag_decay_ = Eigen::Vector3d::Zero();  ///< exp(-d dt) per body axis
  Eigen::Vector3d drag_phi1_ = Eigen::Vector3d::Zero();   ///< (1 - exp(-d dt)) / d
  Eigen::Vector3d drag_phi2_ = Eigen::Vector3d::Zero();   ///< (dt - phi1) / d
};

}  // namespace aerotrack::hal::sim
