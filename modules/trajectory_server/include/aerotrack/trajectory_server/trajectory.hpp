// What the planner hands the trajectory server: a trajectory in the world frame, sampled by
// time since its start. The optimiser's piecewise polynomial (issue 8, paper Sect. V-C) and the
// foundation's minimum-jerk tour implement it. Implementations are immutable after construction
// and shared by handle between the planning and trajectory-server threads.
#pragma once

#include <memory>

#include <Eigen/Core>

#include "aerotrack/rt/time.hpp"

namespace aerotrack::trajectory_server {

struct TrajectorySample {
  Eigen::Vector3d p_W_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_W_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d a_W_mps2 = Eigen::Vector3d::Zero();
};

class Trajectory {
 public:
  virtual ~Trajectory() = default;
  virtual double durationS() const = 0;
  /// State at t_s seconds after the start; t_s is clamped to [0, durationS()]. Thread-safe.
  virtual TrajectorySample sample(double t_s) const = 0;
};

/// A trajectory and the time it starts, on the executor's clock.
struct TimedTrajectory {
  std::shared_ptr<const Trajectory> trajectory;
  rt::TimeNs start_ns = 0;
  /// Capture time of the newest image whose measurement the plan used (-1: none, e.g. a take-off), so
  /// the server can measure the end-to-end latency from image capture to the first setpoint using it.
  rt::TimeNs source_capture_ns = -1;
};

}  // namespace aerotrack::trajectory_server
