// Task glue for the trajectory server: reads the newest trajectory from its channel, samples it
// and sends the setpoint to the vehicle link, and publishes it for other tasks (gimbal feed-
// forward, recorder). Periodic (default 100 Hz in the task table).
#pragma once

#include "aerotrack/hal/devices.hpp"
#include "aerotrack/rt/latest_slot.hpp"
#include "aerotrack/rt/shared_slot.hpp"
#include "aerotrack/rt/task.hpp"
#include "aerotrack/trajectory_server/trajectory_server.hpp"

namespace aerotrack::trajectory_server {

class TrajectoryServerTask final : public rt::Task {
 public:
  TrajectoryServerTask(const TrajectoryServerParams& params, const rt::SharedSlot<TimedTrajectory>& trajectories,
                       hal::VehicleLink& vehicle, rt::LatestSlot<hal::Setpoint>& setpoints)
      : server_(params), trajectories_(trajectories), vehicle_(vehicle), setpoints_(setpoints) {}

  TrajectoryServer& server() { return server_; }

  void step(rt::TimeNs now_ns) override {
    if (trajectories_.version() != trajectory_version_) {
      trajectory_version_ = trajectories_.version();
      if (const auto handle = trajectories_.read()) server_.setTrajectory(*handle);
    }
    if (const auto setpoint = server_.sample(now_ns)) {
      vehicle_.send(*setpoint);
      setpoints_.write(*setpoint);
    }
  }

 private:
  TrajectoryServer server_;
  const rt::SharedSlot<TimedTrajectory>& trajectories_;
  std::uint64_t trajectory_version_ = 0;
  hal::VehicleLink& vehicle_;
  rt::LatestSlot<hal::Setpoint>& setpoints_;
};

}  // namespace aerotrack::trajectory_server
