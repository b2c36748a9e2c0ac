// Tasks that connect devices to channels: the capture side of the HAL. Thin by design.
#pragma once

#include <memory>

#include "aerotrack/hal/devices.hpp"
#include "aerotrack/hal/sim/point_mass_world.hpp"
#include "aerotrack/rt/latest_slot.hpp"
#include "aerotrack/rt/task.hpp"

namespace aerotrack::app {

/// Polls the odometry device and publishes each new sample (by stamp) on the odometry channel.
class OdometryTask final : public rt::Task {
 public:
  OdometryTask(hal::Odometry& device, rt::LatestSlot<hal::OdometrySample>& out) : device_(device), out_(out) {}
  void step(rt::TimeNs now_ns) override {
    const auto sample = device_.read(now_ns);
    if (!sample || sample->stamp_ns <= last_stamp_ns_) return;
    last_stamp_ns_ = sample->stamp_ns;
    out_.write(*sample);
  }

 private:
  hal::Odometry& device_;
  rt::LatestSlot<hal::OdometrySample>& out_;
  rt::TimeNs last_stamp_ns_ = -1;
};

/// Advances the simulated world to the executor's time (the physics step of sim backends).
class SimWorldTask final : public rt::Task {
 public:
  explicit SimWorldTask(std::shared_ptr<hal::sim::PointMassWorld> world) : world_(std::move(world)) {}
  void step(rt::TimeNs now_ns) override { world_->step(now_ns); }

 private:
  std::shared_ptr<hal::sim::PointMassWorld> world_;
};

}  // namespace aerotrack::app
