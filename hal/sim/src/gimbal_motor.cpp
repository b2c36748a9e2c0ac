// Gimbal yaw motor: see gimbal_motor.hpp.
#include "aerotrack/hal/sim/gimbal_motor.hpp"

#include <algorithm>
#include <cmath>

namespace aerotrack::hal::sim {

void GimbalMotor::step(const GimbalCommand& command, double dt_s) {
  double limit = spec_.max_rate_radps;
  double desired = 0.0;
  if (command.mode == GimbalCommand::Mode::kRate) {
    desired = command.rate_radps;
  } else {
    if (command.max_rate_radps > 0.0) limit = std::min(limit, command.max_rate_radps);
    desired = spec_.angle_gain_per_s * (command.angle_rad - angle_rad_);
  }
  desired = std::clamp(desired, -limit, limit);
  // Exact discretisation of the first-order lag; the angle integrates the rate's exact path.
  const double alpha = std::exp(-dt_s / spec_.time_constant_s);
  const double new_rate = desired + (rate_radps_ - desired) * alpha;
  angle_rad_ += desired * dt_s + (rate_radps_ - desired) * spec_.time_constant_s * (1.0 - alpha);
  rate_radps_ = new_rate;
}

GimbalState GimbalMotor::encoder(TimeNs stamp_ns) const {
  GimbalState s;
  s.stamp_ns = stamp_ns;
  const double res = spec_.encoder_resolution_rad;
  s.angle_rad = res > 0.0 ? std::round(angle_rad_ / res) * res : angle_rad_;
  s.rate_radps = rate_radps_;
  return s;
}

}  // namespace aerotrack::hal::sim
