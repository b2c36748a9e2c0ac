// The trajectory server (paper Sect. V-C, last step; DESIGN.md data flow): samples the current
// trajectory at a fixed rate into full-state setpoints for the flight controller. The body's yaw
// follows the direction of horizontal velocity, because the gimbal, not the body, looks at the
// person (paper Sect. III-B); when nearly still, the last yaw is held. Pure: time comes in.
// Replanning (issue 8): the planner starts each new trajectory from the state the current one will
// have at the new one's start time, a little in the future; the server keeps flying the current one
// until then and switches exactly at that time, so the setpoints stay continuous. After a
// trajectory's end its last position is held at rest (velocity and acceleration zero): a planner that
// stops publishing leaves the vehicle hovering, not drifting with a stale velocity feed-forward.
// A trajectory that would take over long after its start (a planner held up past its budget: issue 23's
// task overrun) is refused: it begins at a state the vehicle has since left, and taking it over would
// make the setpoint jump by as far as the two trajectories drifted apart (0.53 m after a 2 s stall on
// sharp_turn). The current one stays; the planner, told of the refusal (TrajectoryServerTask), plans the
// next one from the vehicle's state rather than continuing the refused one.
#pragma once

#include <optional>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/timing_stats.hpp"
#include "aerotrack/trajectory_server/trajectory.hpp"

namespace aerotrack::trajectory_server {

struct TrajectoryServerParams {
  double yaw_min_speed_mps = 0.3;  ///< Below this horizontal speed the yaw is held.
  double initial_yaw_rad = 0.0;    ///< Yaw held until the first motion (the vehicle's start yaw; not in YAML).
  /// A trajectory due to take over more than this after its start is refused (while another is served).
  double max_late_takeover_s = 0.1;
};

class TrajectoryServer {
 public:
  explicit TrajectoryServer(const TrajectoryServerParams& params)
      : params_(params), held_yaw_rad_(params.initial_yaw_rad) {}

  /// Hands over the planner's newest trajectory. If one is being served, the new one takes over at its
  /// start_ns (at once if that has passed); a newer hand-over replaces one still waiting. With nothing
  /// served yet it is served at once. An empty handle stops serving (at once).
  void setTrajectory(const TimedTrajectory& trajectory);

  /// Setpoint at now_ns, or nothing if no trajectory was given. Before its start the trajectory's
  /// first state is served, after its end the last position at rest (a hold). Not thread-safe (one task).
  std::optional<hal::Setpoint> sample(rt::TimeNs now_ns);
  /// Same, but the body's yaw faces face_W_m (horizontally) instead of following the velocity: the
  /// baseline's fixed camera (Fast-Tracker 1.0), which turns the whole drone to the person. Yaw rate 0.
  std::optional<hal::Setpoint> sampleFacing(rt::TimeNs now_ns, const Eigen::Vector3d& face_W_m);

  /// End-to-end latency (issue 9): for each trajectory that took over, its first setpoint's time minus
  /// the capture time of the image behind it (TimedTrajectory::source_capture_ns).
  const rt::LatencyHistogram& captureToSetpoint() const { return capture_to_setpoint_; }

  /// Trajectories refused for taking over more than max_late_takeover_s after their start.
  std::uint64_t lateRefusals() const { return late_refusals_; }
  /// The start time of the newest refused trajectory (-1: none), for the planner to know what is flown.
  rt::TimeNs lastRefusedStartNs() const { return last_refused_start_ns_; }

  /// The trajectory being served (after any switch due by the last sample()).
  const TimedTrajectory& current() const { return current_; }

 private:
  TrajectoryServerParams params_;
  TimedTrajectory current_;
  TimedTrajectory pending_;   ///< Takes over at its start_ns.
  bool first_sample_ = true;  ///< The current trajectory has not been sampled yet.
  rt::LatencyHistogram capture_to_setpoint_;
  double held_yaw_rad_;
  std::uint64_t late_refusals_ = 0;
  rt::TimeNs last_refused_start_ns_ = -1;
};

}  // namespace aerotrack::trajectory_server
