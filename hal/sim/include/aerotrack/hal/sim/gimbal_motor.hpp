// The gimbal's yaw motor (paper Sect. III-B: a 1-DOF gimbal on a slip ring, so it spins without
// limit). The motor's own speed loop is a first-order lag towards the commanded rate, limited in
// rate; angle commands go through a proportional loop whose rate is limited as well. The encoder
// reports the unwrapped angle quantised to its resolution. Pure and deterministic.
#pragma once

#include "aerotrack/hal/sim/scenario.hpp"
#include "aerotrack/hal/types.hpp"

namespace aerotrack::hal::sim {

class GimbalMotor {
 public:
  explicit GimbalMotor(const GimbalSpec& spec, double start_angle_rad = 0.0)
      : spec_(spec), angle_rad_(start_angle_rad) {}

  /// Advances the motor by dt_s under the given command. No allocation.
  void step(const GimbalCommand& command, double dt_s);

  /// True (unquantised) angle about the body z axis, unwrapped, and rate.
  double angleRad() const { return angle_rad_; }
  double rateRadps() const { return rate_radps_; }
  /// What the encoder reports: the angle quantised to the encoder's resolution.
  GimbalState encoder(TimeNs stamp_ns) const;

 private:
  GimbalSpec spec_;
  double angle_rad_;
  double rate_radps_ = 0.0;
};

}  // namespace aerotrack::hal::sim
