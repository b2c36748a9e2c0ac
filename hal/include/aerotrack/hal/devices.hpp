// Device interfaces (DESIGN.md: hal/). A backend implements them for real hardware (real/),
// recorded files (replay/), the simulator (sim/) or nothing at all (null/); the modules cannot
// tell them apart. All calls are non-blocking: a capture task polls its device at the device's
// rate. Each device is used by one task thread (calls on one device are not concurrent) unless
// its backend says otherwise; health() may be called from any thread.
//
// The clock is a device too (DESIGN.md rule 2): it is rt::Clock -- rt::MonotonicClock on the drone
// and in 1x replay, the lockstep executor's rt::ManualClock in simulation -- and every stamp_ns
// below is on that clock.
#pragma once

#include <optional>
#include <string_view>

#include "aerotrack/hal/types.hpp"

namespace aerotrack::hal {

class Device {
 public:
  virtual ~Device() = default;
  /// Backend name as written in config ("null", "sim", ...).
  virtual std::string_view backend() const = 0;
  virtual DeviceHealth health(TimeNs now_ns) const = 0;
};

class GimbalCamera : public Device {
 public:
  /// The newest frame not returned before, or an empty handle if there is none.
  virtual ImageFrameHandle grab(TimeNs now_ns) = 0;
  /// Keypoint-mode cameras (the simulator's) deliver what a detector would output instead of
  /// images: the oldest detection result not returned before, or nothing. Image cameras return
  /// nothing here, and their images go through the detector.
  virtual std::optional<DetectionFrame> grabDetections(TimeNs /*now_ns*/) { return std::nullopt; }
};

class DepthCamera : public Device {
 public:
  /// The newest depth frame not returned before, or an empty handle.
  virtual DepthFrameHandle grab(TimeNs now_ns) = 0;
};

class Gimbal : public Device {
 public:
  virtual void command(const GimbalCommand& command) = 0;
  /// Newest encoder reading, or nothing if none has arrived.
  virtual std::optional<GimbalState> read(TimeNs now_ns) = 0;
};

class Odometry : public Device {
 public:
  /// Newest state estimate, or nothing if none has arrived. May repeat the previous sample;
  /// compare stamp_ns to detect new data.
  virtual std::optional<OdometrySample> read(TimeNs now_ns) = 0;
};

class VehicleLink : public Device {
 public:
  /// One task sends setpoints (the trajectory server, or the simulator's baseline_follow
  /// stand-in): backends may assume a single caller.
  virtual void send(const Setpoint& setpoint) = 0;
  virtual VehicleStatus status(TimeNs now_ns) = 0;
};

}  // namespace aerotrack::hal
