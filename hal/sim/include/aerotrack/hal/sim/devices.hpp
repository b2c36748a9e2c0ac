// Sim backends of the HAL devices: views onto one Simulation through its thread-safe channels,
// so the modules cannot tell them from real devices.
#pragma once

#include <deque>
#include <memory>
#include <random>

#include "aerotrack/hal/devices.hpp"
#include "aerotrack/hal/sim/simulation.hpp"
#include "aerotrack/rt/lending_pool.hpp"

namespace aerotrack::hal::sim {

class SimOdometry final : public Odometry {
 public:
  explicit SimOdometry(std::shared_ptr<Simulation> sim) : sim_(std::move(sim)) {}
  std::string_view backend() const override { return "sim"; }
  DeviceHealth health(TimeNs now_ns) const override;
  std::optional<OdometrySample> read(TimeNs now_ns) override;

 private:
  std::shared_ptr<Simulation> sim_;
  std::optional<OdometrySample> frozen_;  ///< odometry_freeze fault: the sample repeated
};

class SimVehicleLink final : public VehicleLink {
 public:
  explicit SimVehicleLink(std::shared_ptr<Simulation> sim) : sim_(std::move(sim)) {}
  std::string_view backend() const override { return "sim"; }
  DeviceHealth health(TimeNs now_ns) const override;
  void send(const Setpoint& setpoint) override;
  /// The link is up, armed, offboard -- down (and the flight controller holding) in a vehicle_link_lost
  /// fault, as the MAVLink driver reports a link whose heartbeats stopped.
  VehicleStatus status(TimeNs now_ns) override;

 private:
  std::shared_ptr<Simulation> sim_;
};

class SimGimbal final : public Gimbal {
 public:
  explicit SimGimbal(std::shared_ptr<Simulation> sim) : sim_(std::move(sim)) {}
  std::string_view backend() const override { return "sim"; }
  DeviceHealth health(TimeNs now_ns) const override;
  void command(const GimbalCommand& command) override;
  std::optional<GimbalState> read(TimeNs now_ns) override;

 private:
  std::shared_ptr<Simulation> sim_;
};

/// The gimbal camera, in the scenario's mode (sensors.gimbal_camera.mode):
///  - keypoints: grabDetections() delivers the simulated detector output; grab() returns nothing;
///  - image: grab() renders the newest exposure the simulation took since the last call (hal/sim/render)
///    into an ImageFrame stamped at its exposure time, at most one per exposure, so at the camera's
///    rate when called at least that often (older waiting exposures are skipped: sequence gaps);
///    grabDetections() returns nothing. Rendering (a few ms) runs on the caller's thread. Frames come
///    from a small pool (rt::LendingPool): a frame is reused once no one holds it, so after warm-up
///    nothing is allocated.
/// One task uses the device (the simulation's camera queues have one consumer).
class SimGimbalCamera final : public GimbalCamera {
 public:
  explicit SimGimbalCamera(std::shared_ptr<Simulation> sim) : sim_(std::move(sim)) {}
  std::string_view backend() const override { return "sim"; }
  DeviceHealth health(TimeNs now_ns) const override;
  ImageFrameHandle grab(TimeNs now_ns) override;
  std::optional<DetectionFrame> grabDetections(TimeNs now_ns) override;

 private:
  std::shared_ptr<ImageFrame> freeFrame();

  std::shared_ptr<Simulation> sim_;
  std::deque<DetectionFrame> late_;            ///< camera_late fault: frames held until 0.5 s after exposure
  std::deque<CameraExposure> late_exposures_;  ///< camera_late fault, image mode: the same for exposures
  std::mt19937_64 garbage_rng_{23};            ///< detector_garbage fault
  rt::LendingPool<ImageFrame> pool_{4, ImageFrame{}};
  RenderScratch scratch_;
  TimeNs last_stamp_ns_ = 0;
};

class SimDepthCamera final : public DepthCamera {
 public:
  explicit SimDepthCamera(std::shared_ptr<Simulation> sim) : sim_(std::move(sim)) {}
  std::string_view backend() const override { return "sim"; }
  DeviceHealth health(TimeNs now_ns) const override;
  DepthFrameHandle grab(TimeNs now_ns) override;

 private:
  std::shared_ptr<Simulation> sim_;
  std::uint64_t version_ = 0;
  std::shared_ptr<DepthFrame> zeros_;  ///< depth_zero fault: the frame of zeros, reused
};

}  // namespace aerotrack::hal::sim
