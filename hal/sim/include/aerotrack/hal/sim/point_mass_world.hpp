// The foundation's simulated world: a point-mass vehicle that follows full-state setpoints the
// way a flight controller's position loop does (feed-forward acceleration plus PD on position and
// velocity, saturated), with yaw slewed towards the setpoint at a bounded rate. It stands in for
// the rigid-body quadrotor of the full simulator (issue 3) so the lockstep path runs end to end.
//
// Pure and deterministic: step(now) integrates from the last step to now in fixed substeps, with
// exact constant-acceleration updates inside a substep. Thread-safe where the sim devices need
// it: setSetpoint() and truth() use latest-value slots, so a real-time run may step the world on
// one thread while tasks send setpoints and read odometry on others. step() itself is called from
// one thread.
#pragma once

#include <cstdint>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/latest_slot.hpp"

namespace aerotrack::hal::sim {

struct PointMassParams {
  Eigen::Vector3d start_p_W_m = Eigen::Vector3d::Zero();
  double start_yaw_rad = 0.0;
  double position_gain_per_s2 = 6.0;  ///< Acceleration per metre of position error.
  double velocity_gain_per_s = 4.0;   ///< Acceleration per m/s of velocity error.
  double max_accel_mps2 = 8.0;        ///< Norm limit of the commanded acceleration.
  double max_yaw_rate_radps = 3.0;
  double substep_s = 0.001;  ///< Integration step (<= the physics task period).
};

/// Ground truth of the simulated vehicle.
struct PointMassTruth {
  TimeNs stamp_ns = 0;
  Eigen::Vector3d p_W_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_W_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d a_W_mps2 = Eigen::Vector3d::Zero();
  double yaw_rad = 0.0;
  double yaw_rate_radps = 0.0;
};

}  // namespace aerotrack::hal::sim

static_assert(std::is_standard_layout_v<aerotrack::hal::sim::PointMassTruth>);
template <>
struct aerotrack::rt::IsBitwiseCopyable<aerotrack::hal::sim::PointMassTruth> : std::true_type {};

namespace aerotrack::hal::sim {

/// Statistics the world keeps about how well the vehicle followed its setpoints.
struct TrackingStats {
  std::uint64_t samples = 0;
  double sum_error_m = 0.0;
  double max_error_m = 0.0;
  double meanErrorM() const { return samples == 0 ? 0.0 : sum_error_m / static_cast<double>(samples); }
};

class PointMassWorld {
 public:
  PointMassWorld(const PointMassParams& params, TimeNs start_ns);

  /// Integrates up to now_ns (no-op if now_ns is not after the last step). One thread.
  void step(TimeNs now_ns);

  /// Any thread: the newest setpoint wins. Before the first, the vehicle holds its start pose.
  void setSetpoint(const Setpoint& setpoint) { setpoint_.write(setpoint); }
  /// Any thread: the newest truth.
  PointMassTruth truth() const { return truth_.read().value_or(PointMassTruth{}); }
  /// The stepping thread only.
  const TrackingStats& trackingStats() const { return tracking_; }
  std::uint64_t setpointsReceived() const { return setpoint_.version(); }

 private:
  PointMassParams params_;
  PointMassTruth state_;
  Setpoint active_setpoint_;
  std::uint64_t setpoint_version_ = 0;
  rt::LatestSlot<Setpoint> setpoint_;
  rt::LatestSlot<PointMassTruth> truth_;
  TrackingStats tracking_;
};

}  // namespace aerotrack::hal::sim
