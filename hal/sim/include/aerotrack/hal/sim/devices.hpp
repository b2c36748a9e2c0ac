// Sim backends of the HAL devices, views onto the simulated world. Odometry is the world's truth
// (noise and latency arrive with the full simulator, issue 3); the vehicle link forwards
// setpoints to the world's flight controller and reports an armed, offboard vehicle.
#pragma once

#include <memory>

#include "aerotrack/hal/devices.hpp"
#include "aerotrack/hal/sim/point_mass_world.hpp"

namespace aerotrack::hal::sim {

class SimOdometry final : public Odometry {
 public:
  explicit SimOdometry(std::shared_ptr<PointMassWorld> world) : world_(std::move(world)) {}
  std::string_view backend() const override { return "sim"; }
  DeviceHealth health(TimeNs now_ns) const override;
  std::optional<OdometrySample> read(TimeNs now_ns) override;

 private:
  std::shared_ptr<PointMassWorld> world_;
};

class SimVehicleLink final : public VehicleLink {
 public:
  explicit SimVehicleLink(std::shared_ptr<PointMassWorld> world) : world_(std::move(world)) {}
  std::string_view backend() const override { return "sim"; }
  DeviceHealth health(TimeNs now_ns) const override;
  void send(const Setpoint& setpoint) override { world_->setSetpoint(setpoint); }
  VehicleStatus status(TimeNs now_ns) override { return {now_ns, true, true, FlightMode::kOffboard}; }

 private:
  std::shared_ptr<PointMassWorld> world_;
};

}  // namespace aerotrack::hal::sim
