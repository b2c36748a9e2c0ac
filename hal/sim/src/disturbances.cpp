// Odometry drift and wind: see disturbances.hpp for the models and their sources.
#include "aerotrack/hal/sim/disturbances.hpp"

#include <cmath>
#include <limits>

namespace aerotrack::hal::sim {

QuadrotorState inOdometryFrame(const OdometryFrameError& T_OW, const QuadrotorState& state_W) {
  const Eigen::Matrix3d R_OW = T_OW.rotationOW();
  QuadrotorState s = state_W;
  s.p_W_m = R_OW * state_W.p_W_m + T_OW.t_m;
  s.v_W_mps = R_OW * state_W.v_W_mps;
  s.a_W_mps2 = R_OW * state_W.a_W_mps2;
  s.R_WB = R_OW * state_W.R_WB;
  return s;
}

hal::Setpoint inOdometryFrame(const OdometryFrameError& T_OW, const hal::Setpoint& setpoint_W) {
  const Eigen::Matrix3d R_OW = T_OW.rotationOW();
  hal::Setpoint s = setpoint_W;
  s.p_W_m = R_OW * setpoint_W.p_W_m + T_OW.t_m;
  s.v_W_mps = R_OW * setpoint_W.v_W_mps;
  s.a_W_mps2 = R_OW * setpoint_W.a_W_mps2;
  s.yaw_rad = setpoint_W.yaw_rad + T_OW.yaw_rad;
  return s;
}

OdometryDrift::OdometryDrift(const OdometryDriftSpec& spec, std::mt19937_64 walk_rng, std::mt19937_64 jump_rng,
                             const Eigen::Vector3d& start_p_W_m)
    : spec_(spec), walk_rng_(walk_rng), jump_rng_(jump_rng), last_p_W_m_(start_p_W_m) {
  next_random_jump_s_ = drawNextRandomJumpS(0.0);
}

double OdometryDrift::drawNextRandomJumpS(double after_s) {
  if (!(spec_.random_jumps_per_min > 0.0)) return std::numeric_limits<double>::infinity();
  return after_s + std::exponential_distribution<double>(spec_.random_jumps_per_min / 60.0)(jump_rng_);
}

void OdometryDrift::apply(const Eigen::Vector3d& dp_O_m, double dyaw_rad, const Eigen::Vector3d& p_W_m) {
  // x_O' = R_z(dyaw) (x_O - c) + c + dp for every point, c the drone's reported position:
  // R' = R_z(dyaw) R, t' = R_z(dyaw) (t - c) + c + dp.
  const Eigen::Vector3d c_O = error_.toOdometry(p_W_m);
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(dyaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  error_.t_m = turn * (error_.t_m - c_O) + c_O + dp_O_m;
  error_.yaw_rad = std::remainder(error_.yaw_rad + dyaw_rad, 2.0 * M_PI);
}

void OdometryDrift::update(double t_s, const Eigen::Vector3d& p_W_m) {
  const double dt_s = std::max(0.0, t_s - last_t_s_);
  const double ds_m = (p_W_m - last_p_W_m_).norm();
  last_t_s_ = std::max(last_t_s_, t_s);
  last_p_W_m_ = p_W_m;
  distance_m_ += ds_m;
  const OdometryDriftSpec& d = spec_;
  const double time_var = d.position_m_per_sqrt_s * d.position_m_per_sqrt_s * dt_s;
  const double sigma_xy = std::sqrt(d.position_m_per_sqrt_m * d.position_m_per_sqrt_m * ds_m + time_var);
  const double sigma_z = std::sqrt(d.z_m_per_sqrt_m * d.z_m_per_sqrt_m * ds_m + time_var);
  const double sigma_yaw = std::sqrt(d.yaw_rad_per_sqrt_m * d.yaw_rad_per_sqrt_m * ds_m +
                                     d.yaw_rad_per_sqrt_s * d.yaw_rad_per_sqrt_s * dt_s);
  if (sigma_xy > 0.0 || sigma_z > 0.0 || sigma_yaw > 0.0) {
    std::normal_distribution<double> unit(0.0, 1.0);
    const double nx = unit(walk_rng_), ny = unit(walk_rng_), nz = unit(walk_rng_), nyaw = unit(walk_rng_);
    apply(Eigen::Vector3d(sigma_xy * nx, sigma_xy * ny, sigma_z * nz), sigma_yaw * nyaw, p_W_m);
  }
  while (next_jump_ < d.jumps.size() && d.jumps[next_jump_].t_s <= t_s) {
    apply(d.jumps[next_jump_].dp_m, d.jumps[next_jump_].dyaw_rad, p_W_m);
    ++next_jump_;
    ++jumps_applied_;
  }
  while (next_random_jump_s_ <= t_s) {
    const double heading_rad = std::uniform_real_distribution<double>(-M_PI, M_PI)(jump_rng_);
    const double sign = std::bernoulli_distribution(0.5)(jump_rng_) ? 1.0 : -1.0;
    apply(d.random_jump_position_m * Eigen::Vector3d(std::cos(heading_rad), std::sin(heading_rad), 0.0),
          sign * d.random_jump_yaw_rad, p_W_m);
    ++jumps_applied_;
    next_random_jump_s_ = drawNextRandomJumpS(next_random_jump_s_);
  }
}

WindField::WindField(const WindSpec& spec, std::mt19937_64 rng) : spec_(spec), rng_(rng) {
  std::normal_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 3; ++i) gust_W_mps_[i] = spec_.gust_sigma_mps[i] * unit(rng_);
}

void WindField::step(double dt_s) {
  if (!(dt_s > 0.0)) return;
  std::normal_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 3; ++i) {
    const double sigma = spec_.gust_sigma_mps[i];
    if (!(sigma > 0.0)) continue;
    const double phi = std::exp(-dt_s / spec_.gust_time_constant_s[i]);
    gust_W_mps_[i] = phi * gust_W_mps_[i] + sigma * std::sqrt(1.0 - phi * phi) * unit(rng_);
  }
}

Eigen::Vector3d windForceW(const QuadrotorParams& params, const QuadrotorState& state,
                           const Eigen::Vector3d& wind_W_mps, const WindSpec& spec) {
  const Eigen::Matrix3d& R = state.R_WB;
  Eigen::Vector3d f_W_n =
      params.mass_kg * (R * params.drag_B_per_s.cwiseProduct(R.transpose() * wind_W_mps));  // rotor drag, wind part
  if (spec.body_cd_area_m2 > 0.0) {
    const Eigen::Vector3d v_rel = wind_W_mps - state.v_W_mps;
    f_W_n += 0.5 * spec.air_density_kgpm3 * spec.body_cd_area_m2 * v_rel.norm() * v_rel;
  }
  return f_W_n;
}

}  // namespace aerotrack::hal::sim
