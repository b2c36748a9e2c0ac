// The trajectory server (paper Sect. V-C, last step; DESIGN.md data flow): samples the current
// trajectory at a fixed rate into full-state setpoints for the flight controller. The body's yaw
// follows the direction of horizontal velocity, because the gimbal, not the body, looks at the
// person (paper Sect. III-B); when nearly still, the last yaw is held. Pure: time comes in.
#pragma once

#include <optional>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/trajectory_server/trajectory.hpp"

namespace aerotrack::trajectory_server {

struct TrajectoryServerParams {
  double yaw_min_speed_mps = 0.3;  ///< Below this horizontal speed the yaw is held.
  double initial_yaw_rad = 0.0;    ///< Yaw held until the first motion (the vehicle's start yaw; not in YAML).
};

class TrajectoryServer {
 public:
  explicit TrajectoryServer(const TrajectoryServerParams& params)
      : params_(params), held_yaw_rad_(params.initial_yaw_rad) {}

  /// Replaces the trajectory being served (the planner's newest). An empty handle stops serving.
  void setTrajectory(const TimedTrajectory& trajectory) { current_ = trajectory; }

  /// Setpoint at now_ns, or nothing if no trajectory was given. Before its start the trajectory's
  /// first state is served, after its end the last (a hold). Not thread-safe (one task).
  std::optional<hal::Setpoint> sample(rt::TimeNs now_ns);

 private:
  TrajectoryServerParams params_;
  TimedTrajectory current_;
  double held_yaw_rad_;
};

}  // namespace aerotrack::trajectory_server
