// Rigid-body quadrotor with first-order thrust and rate lags, exact per-step discretisation and a
// ground plane: see quadrotor.hpp for the model and the equations.
#include "aerotrack/hal/sim/quadrotor.hpp"

#include <algorithm>
#include <cmath>

#include "aerotrack/hal/sim/so3.hpp"

namespace aerotrack::hal::sim {
namespace {

bool finite(const Eigen::Vector3d& v) {
  return v.allFinite();
}

/// exp(-dt/tau) and the mean of the unit step response's remaining part over [0, dt]:
/// (1/dt) int_0^dt exp(-s/tau) ds = tau/dt (1 - exp(-dt/tau)). tau = 0: instant response.
void lagCoefficients(double dt_s, double tau_s, double& decay, double& mean) {
  if (tau_s <= 0.0) {
    decay = 0.0;
    mean = 0.0;
    return;
  }
  const double x = dt_s / tau_s;
  decay = std::exp(-x);
  mean = -std::expm1(-x) / x;
}

/// For u' = c - d u over [0, dt]: e = exp(-d dt), phi1 = int_0^dt exp(-d s) ds = (1 - e)/d and
/// phi2 = int_0^dt phi1(s) ds = (dt - phi1)/d; the limits for d -> 0 are dt and dt^2/2.
void dragCoefficients(double dt_s, double d_per_s, double& decay, double& phi1, double& phi2) {
  const double x = d_per_s * dt_s;
  if (x < 1e-2) {  // series: the closed form loses digits to cancellation in dt - phi1
    decay = std::exp(-x);
    phi1 = dt_s * (1.0 - x / 2.0 * (1.0 - x / 3.0 * (1.0 - x / 4.0 * (1.0 - x / 5.0))));
    phi2 = dt_s * dt_s * (0.5 - x / 6.0 * (1.0 - x / 4.0 * (1.0 - x / 5.0 * (1.0 - x / 6.0))));
    return;
  }
  decay = std::exp(-x);
  phi1 = -std::expm1(-x) / d_per_s;
  phi2 = (dt_s - phi1) / d_per_s;
}

/// Rotation about world z by the heading of R's x axis (the attitude levelled, heading kept).
Eigen::Matrix3d levelled(const Eigen::Matrix3d& R) {
  const double yaw_rad = std::atan2(R(1, 0), R(0, 0));
  const double c = std::cos(yaw_rad);
  const double s = std::sin(yaw_rad);
  Eigen::Matrix3d out;
  out << c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0;
  return out;
}

}  // namespace

rt::Expected<Quadrotor> Quadrotor::create(const QuadrotorParams& params, const QuadrotorState& initial) {
  const QuadrotorParams& p = params;
  if (!(std::isfinite(p.mass_kg) && p.mass_kg > 0.0)) return rt::Error{"quadrotor: mass_kg must be > 0"};
  if (!(std::isfinite(p.gravity_mps2) && p.gravity_mps2 >= 0.0))
    return rt::Error{"quadrotor: gravity_mps2 must be >= 0"};
  if (!(std::isfinite(p.min_thrust_n) && p.min_thrust_n >= 0.0))
    return rt::Error{"quadrotor: min_thrust_n must be >= 0"};
  if (!(std::isfinite(p.max_thrust_n) && p.max_thrust_n > p.min_thrust_n))
    return rt::Error{"quadrotor: max_thrust_n must be > min_thrust_n"};
  if (!(finite(p.max_body_rate_radps) && p.max_body_rate_radps.minCoeff() > 0.0))
    return rt::Error{"quadrotor: max_body_rate_radps must be > 0 on every axis"};
  if (!(std::isfinite(p.body_rate_time_constant_s) && p.body_rate_time_constant_s >= 0.0))
    return rt::Error{"quadrotor: body_rate_time_constant_s must be >= 0"};
  if (!(std::isfinite(p.thrust_time_constant_s) && p.thrust_time_constant_s >= 0.0))
    return rt::Error{"quadrotor: thrust_time_constant_s must be >= 0"};
  if (!(finite(p.drag_B_per_s) && p.drag_B_per_s.minCoeff() >= 0.0))
    return rt::Error{"quadrotor: drag_B_per_s must be >= 0 on every axis"};

  const QuadrotorState& s = initial;
  if (!(finite(s.p_W_m) && finite(s.v_W_mps) && s.R_WB.allFinite() && finite(s.w_B_radps) &&
        std::isfinite(s.thrust_n) && finite(s.a_W_mps2)))
    return rt::Error{"quadrotor: initial state is not finite"};
  if (s.p_W_m.z() < 0.0) return rt::Error{"quadrotor: initial p_W_m.z must be >= 0 (ground at z = 0)"};
  if ((s.R_WB.transpose() * s.R_WB - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-6 ||
      s.R_WB.determinant() <= 0.0)
    return rt::Error{"quadrotor: initial R_WB is not a rotation matrix"};
  if (s.on_ground && s.p_W_m.z() > 1e-6) return rt::Error{"quadrotor: initial on_ground requires p_W_m.z = 0"};
  return Quadrotor(params, initial);
}

Quadrotor::Quadrotor(const QuadrotorParams& params, const QuadrotorState& initial) : params_(params), state_(initial) {
  state_.R_WB = so3::reorthonormalize(state_.R_WB);
  if (state_.on_ground) {
    state_.p_W_m.z() = 0.0;
    state_.v_W_mps.setZero();
    state_.w_B_radps.setZero();
    state_.a_W_mps2.setZero();
  }
}

void Quadrotor::updateCoefficients(double dt_s) {
  if (dt_s == coeff_dt_s_) return;
  coeff_dt_s_ = dt_s;
  lagCoefficients(dt_s, params_.thrust_time_constant_s, thrust_decay_, thrust_mean_);
  lagCoefficients(dt_s, params_.body_rate_time_constant_s, rate_decay_, rate_mean_);
  for (int i = 0; i < 3; ++i)
    dragCoefficients(dt_s, params_.drag_B_per_s[i], drag_decay_[i], drag_phi1_[i], drag_phi2_[i]);
}

void Quadrotor::touchDown() {
  state_.p_W_m.z() = 0.0;
  state_.v_W_mps.setZero();
  state_.w_B_radps.setZero();
  state_.a_W_mps2.setZero();
  state_.R_WB = levelled(state_.R_WB);
  state_.on_ground = true;
}

void Quadrotor::step(const QuadrotorCommand& command, double dt_s, const Eigen::Vector3d& f_ext_W_n) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) return;
  updateCoefficients(dt_s);
  const QuadrotorParams& p = params_;
  QuadrotorState& s = state_;
  // Skipped entirely when zero, so runs without wind stay bit-identical.
  const bool external = f_ext_W_n.allFinite() && !f_ext_W_n.isZero(0.0);

  // Thrust lag (exact), and the mean thrust over the step.
  const double thrust_cmd_n =
      std::isfinite(command.thrust_n) ? std::clamp(command.thrust_n, p.min_thrust_n, p.max_thrust_n) : p.min_thrust_n;
  const double thrust_mean_n = thrust_cmd_n + (s.thrust_n - thrust_cmd_n) * thrust_mean_;
  s.thrust_n = thrust_cmd_n + (s.thrust_n - thrust_cmd_n) * thrust_decay_;

  if (s.on_ground) {
    // Resting on its legs: no motion until the thrust's vertical component exceeds the weight.
    const double lift_n = thrust_mean_n * s.R_WB(2, 2) + (external ? f_ext_W_n.z() : 0.0);
    if (!(lift_n > p.mass_kg * p.gravity_mps2)) {
      s.a_W_mps2.setZero();
      return;
    }
    s.on_ground = false;  // lift off; the rates start from rest (they were held at 0)
  }

  // Rate lag (exact) and the mean rate over the step.
  Eigen::Vector3d w_cmd = command.w_B_radps;
  for (int i = 0; i < 3; ++i) {
    const double limit = p.max_body_rate_radps[i];
    w_cmd[i] = std::isfinite(w_cmd[i]) ? std::clamp(w_cmd[i], -limit, limit) : 0.0;
  }
  const Eigen::Vector3d w_mean = w_cmd + rate_mean_ * (s.w_B_radps - w_cmd);
  s.w_B_radps = w_cmd + rate_decay_ * (s.w_B_radps - w_cmd);

  // Attitude: two half steps of the exact rotation, the midpoint attitude serves the translation.
  const Eigen::Matrix3d half_turn = so3::expMap((0.5 * dt_s) * w_mean);
  const Eigen::Matrix3d R_mid = s.R_WB * half_turn;
  s.R_WB = so3::reorthonormalize(R_mid * half_turn);

  // Translation: exact for the frozen midpoint attitude, per axis of B_mid where drag is diagonal.
  const Eigen::Vector3d u0 = R_mid.transpose() * s.v_W_mps;
  Eigen::Vector3d c = -p.gravity_mps2 * R_mid.row(2).transpose();  // gravity in B_mid
  c.z() += thrust_mean_n / p.mass_kg;
  if (external) c += R_mid.transpose() * (f_ext_W_n / p.mass_kg);
  const Eigen::Vector3d u1 = u0.cwiseProduct(drag_decay_) + c.cwiseProduct(drag_phi1_);
  const Eigen::Vector3d dp_B = u0.cwiseProduct(drag_phi1_) + c.cwiseProduct(drag_phi2_);
  s.v_W_mps = R_mid * u1;
  s.p_W_m += R_mid * dp_B;

  if (s.p_W_m.z() < 0.0) {
    touchDown();
    return;
  }
  // Acceleration at the end of the step.
  const Eigen::Vector3d v_B = s.R_WB.transpose() * s.v_W_mps;
  Eigen::Vector3d a_B = -p.drag_B_per_s.cwiseProduct(v_B);
  a_B.z() += s.thrust_n / p.mass_kg;
  s.a_W_mps2 = s.R_WB * a_B;
  s.a_W_mps2.z() -= p.gravity_mps2;
  if (external) s.a_W_mps2 += f_ext_W_n / p.mass_kg;
}

}  // namespace aerotrack::hal::sim
