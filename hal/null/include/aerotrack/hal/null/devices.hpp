// Null backends: the device is not on this vehicle (DESIGN.md rule 5: unsimulated hardware gets a
// null device, never a null pointer). They produce no data, swallow commands, and report their
// health as kAbsent so the supervisor can tell "absent by configuration" from "failed".
#pragma once

#include "aerotrack/hal/devices.hpp"

namespace aerotrack::hal::null {

inline DeviceHealth absentHealth() {
  return {DeviceHealth::State::kAbsent, "null backend: no device", 0, 0};
}

class NullGimbalCamera final : public GimbalCamera {
 public:
  std::string_view backend() const override { return "null"; }
  DeviceHealth health(TimeNs) const override { return absentHealth(); }
  ImageFrameHandle grab(TimeNs) override { return {}; }
};

class NullDepthCamera final : public DepthCamera {
 public:
  std::string_view backend() const override { return "null"; }
  DeviceHealth health(TimeNs) const override { return absentHealth(); }
  DepthFrameHandle grab(TimeNs) override { return {}; }
};

class NullGimbal final : public Gimbal {
 public:
  std::string_view backend() const override { return "null"; }
  DeviceHealth health(TimeNs) const override { return absentHealth(); }
  void command(const GimbalCommand&) override {}
  std::optional<GimbalState> read(TimeNs) override { return std::nullopt; }
};

class NullOdometry final : public Odometry {
 public:
  std::string_view backend() const override { return "null"; }
  DeviceHealth health(TimeNs) const override { return absentHealth(); }
  std::optional<OdometrySample> read(TimeNs) override { return std::nullopt; }
};

class NullVehicleLink final : public VehicleLink {
 public:
  std::string_view backend() const override { return "null"; }
  DeviceHealth health(TimeNs) const override { return absentHealth(); }
  void send(const Setpoint&) override {}
  VehicleStatus status(TimeNs now_ns) override { return {now_ns, false, false, FlightMode::kUnknown}; }
};

}  // namespace aerotrack::hal::null
