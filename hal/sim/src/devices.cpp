// Sim device views onto the simulation.
#include "aerotrack/hal/sim/devices.hpp"

namespace aerotrack::hal::sim {
namespace {

DeviceHealth simulated(const char* what, TimeNs last_ns) {
  return {DeviceHealth::State::kOk, what, last_ns, 0};
}

}  // namespace

DeviceHealth SimOdometry::health(TimeNs) const {
  const auto last = sim_->odometryOut().read();
  return simulated("simulated odometry (truth + noise, delayed)", last ? last->stamp_ns : 0);
}

DeviceHealth SimVehicleLink::health(TimeNs now_ns) const {
  return simulated("simulated flight controller", now_ns);
}

DeviceHealth SimGimbal::health(TimeNs) const {
  const auto last = sim_->gimbalOut().read();
  return simulated("simulated gimbal motor", last ? last->stamp_ns : 0);
}

DeviceHealth SimGimbalCamera::health(TimeNs now_ns) const {
  return simulated("simulated gimbal camera, keypoint mode", now_ns);
}

DeviceHealth SimDepthCamera::health(TimeNs) const {
  const auto last = sim_->depthOut().read();
  return simulated("simulated depth camera", last ? last->stamp_ns : 0);
}

DepthFrameHandle SimDepthCamera::grab(TimeNs) {
  const std::uint64_t version = sim_->depthOut().version();
  if (version == version_) return {};
  version_ = version;
  return sim_->depthOut().read();
}

}  // namespace aerotrack::hal::sim
