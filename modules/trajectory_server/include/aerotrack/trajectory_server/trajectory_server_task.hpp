// Task glue for the trajectory server: reads the newest trajectory from its channel, samples it
// and sends the setpoint to the vehicle link, and publishes it for other tasks (gimbal feed-
// forward, recorder). Periodic (default 100 Hz in the task table). It is the link's one caller, so it
// also reads the link's status each step and reports a lost link (up once, down now) to the supervisor,
// and each trajectory it refused for taking over late to the planner.
#pragma once

#include <atomic>
#include <functional>
#include <optional>

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
  const TrajectoryServer& server() const { return server_; }
  /// Where the body must face at a time, or nothing to follow the velocity (set once, before start).
  using FaceFn = std::function<std::optional<Eigen::Vector3d>(rt::TimeNs)>;
  /// Baseline mode: the body yaws to face the point `face` gives (the person's estimate).
  void faceTowards(FaceFn face) { face_ = std::move(face); }
  /// Where to report the link's loss (set once, before start). A link never up is not "lost": a vehicle
  /// without a link (null backend) flies nothing, and one that never connects has no odometry either.
  void reportLinkLossTo(std::atomic<bool>& link_lost) { link_lost_ = &link_lost; }
  /// Where to report the start time of each trajectory refused for taking over late (set once, before
  /// start): the planner must not continue a plan that is not flown.
  void reportLateRefusalsTo(std::atomic<rt::TimeNs>& refused_start_ns) { refused_start_ns_ = &refused_start_ns; }

  void step(rt::TimeNs now_ns) override {
    if (trajectories_.version() != trajectory_version_) {
      trajectory_version_ = trajectories_.version();
      if (const auto handle = trajectories_.read()) server_.setTrajectory(*handle);
    }
    std::optional<hal::Setpoint> setpoint;
    if (face_) {
      const std::optional<Eigen::Vector3d> face = face_(now_ns);
      setpoint = face ? server_.sampleFacing(now_ns, *face) : server_.sample(now_ns);
    } else {
      setpoint = server_.sample(now_ns);
    }
    if (refused_start_ns_ != nullptr && server_.lateRefusals() != late_refusals_) {
      late_refusals_ = server_.lateRefusals();
      refused_start_ns_->store(server_.lastRefusedStartNs(), std::memory_order_release);
    }
    if (setpoint) {
      vehicle_.send(*setpoint);
      setpoints_.write(*setpoint);
    }
    if (link_lost_ != nullptr) {
      const bool link_ok = vehicle_.status(now_ns).link_ok;
      link_was_up_ = link_was_up_ || link_ok;
      link_lost_->store(link_was_up_ && !link_ok, std::memory_order_relaxed);
    }
  }

 private:
  TrajectoryServer server_;
  const rt::SharedSlot<TimedTrajectory>& trajectories_;
  std::uint64_t trajectory_version_ = 0;
  hal::VehicleLink& vehicle_;
  rt::LatestSlot<hal::Setpoint>& setpoints_;
  FaceFn face_;
  std::atomic<bool>* link_lost_ = nullptr;
  bool link_was_up_ = false;
  std::atomic<rt::TimeNs>* refused_start_ns_ = nullptr;
  std::uint64_t late_refusals_ = 0;
};

}  // namespace aerotrack::trajectory_server
