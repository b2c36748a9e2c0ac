// Point-mass vehicle following setpoints: see point_mass_world.hpp.
#include "aerotrack/hal/sim/point_mass_world.hpp"

#include <algorithm>
#include <cmath>

namespace aerotrack::hal::sim {
namespace {

using rt::DurationNs;

double wrapPi(double angle_rad) {
  return std::remainder(angle_rad, 2.0 * M_PI);
}

}  // namespace

PointMassWorld::PointMassWorld(const PointMassParams& params, TimeNs start_ns) : params_(params) {
  state_.stamp_ns = start_ns;
  state_.p_W_m = params.start_p_W_m;
  state_.yaw_rad = params.start_yaw_rad;
  active_setpoint_.stamp_ns = start_ns;
  active_setpoint_.p_W_m = params.start_p_W_m;  // hold the start pose until told otherwise
  active_setpoint_.yaw_rad = params.start_yaw_rad;
  truth_.write(state_);
}

void PointMassWorld::step(TimeNs now_ns) {
  if (now_ns <= state_.stamp_ns) return;
  setpoint_.readIfNewer(setpoint_version_, active_setpoint_);
  const Setpoint& sp = active_setpoint_;
  const DurationNs substep_ns = std::max<DurationNs>(1, rt::secondsToNs(params_.substep_s));
  while (state_.stamp_ns < now_ns) {
    const DurationNs dt_ns = std::min(substep_ns, now_ns - state_.stamp_ns);
    const double dt_s = rt::nsToSeconds(dt_ns);
    Eigen::Vector3d a = sp.a_W_mps2 + params_.position_gain_per_s2 * (sp.p_W_m - state_.p_W_m) +
                        params_.velocity_gain_per_s * (sp.v_W_mps - state_.v_W_mps);
    const double a_norm = a.norm();
    if (a_norm > params_.max_accel_mps2) a *= params_.max_accel_mps2 / a_norm;
    state_.p_W_m += state_.v_W_mps * dt_s + 0.5 * a * dt_s * dt_s;
    state_.v_W_mps += a * dt_s;
    state_.a_W_mps2 = a;
    const double max_turn_rad = params_.max_yaw_rate_radps * dt_s;
    const double turn_rad = std::clamp(wrapPi(sp.yaw_rad - state_.yaw_rad), -max_turn_rad, max_turn_rad);
    state_.yaw_rad = wrapPi(state_.yaw_rad + turn_rad);
    state_.yaw_rate_radps = turn_rad / dt_s;
    state_.stamp_ns += dt_ns;
  }
  truth_.write(state_);
  const double error_m = (state_.p_W_m - sp.p_W_m).norm();
  ++tracking_.samples;
  tracking_.sum_error_m += error_m;
  tracking_.max_error_m = std::max(tracking_.max_error_m, error_m);
}

}  // namespace aerotrack::hal::sim
