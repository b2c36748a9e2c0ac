// Sim device views onto the point-mass world.
#include "aerotrack/hal/sim/devices.hpp"

namespace aerotrack::hal::sim {

DeviceHealth SimOdometry::health(TimeNs) const {
  return {DeviceHealth::State::kOk, "simulated ground truth", world_->truth().stamp_ns, 0};
}

std::optional<OdometrySample> SimOdometry::read(TimeNs) {
  const PointMassTruth truth = world_->truth();
  OdometrySample sample;
  sample.stamp_ns = truth.stamp_ns;
  sample.p_WB_m = truth.p_W_m;
  sample.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(truth.yaw_rad, Eigen::Vector3d::UnitZ()));
  sample.v_WB_mps = truth.v_W_mps;
  sample.w_WB_B_radps = Eigen::Vector3d(0.0, 0.0, truth.yaw_rate_radps);
  return sample;
}

DeviceHealth SimVehicleLink::health(TimeNs now_ns) const {
  return {DeviceHealth::State::kOk, "simulated flight controller", now_ns, 0};
}

}  // namespace aerotrack::hal::sim
