// Trajectory sampling into setpoints: see trajectory_server.hpp.
#include "aerotrack/trajectory_server/trajectory_server.hpp"

#include <cmath>

namespace aerotrack::trajectory_server {

void TrajectoryServer::setTrajectory(const TimedTrajectory& trajectory) {
  if (!trajectory.trajectory || !current_.trajectory) {
    current_ = trajectory;
    pending_ = {};
    first_sample_ = true;
    return;
  }
  pending_ = trajectory;
}

std::optional<hal::Setpoint> TrajectoryServer::sample(rt::TimeNs now_ns) {
  if (pending_.trajectory && now_ns >= pending_.start_ns) {
    if (rt::nsToSeconds(now_ns - pending_.start_ns) > params_.max_late_takeover_s) {
      ++late_refusals_;  // planned from a state the vehicle has left: keep flying the current one
      last_refused_start_ns_ = pending_.start_ns;
    } else {
      current_ = std::move(pending_);
      first_sample_ = true;
    }
    pending_ = {};
  }
  if (!current_.trajectory) return std::nullopt;
  if (first_sample_) {
    first_sample_ = false;
    if (current_.source_capture_ns >= 0) capture_to_setpoint_.record(now_ns - current_.source_capture_ns);
  }
  const double t_s = rt::nsToSeconds(now_ns - current_.start_ns);
  TrajectorySample s = current_.trajectory->sample(t_s);
  if (t_s > current_.trajectory->durationS()) {  // finished: hold the end at rest
    s.v_W_mps.setZero();
    s.a_W_mps2.setZero();
  }
  hal::Setpoint sp;
  sp.stamp_ns = now_ns;
  sp.p_W_m = s.p_W_m;
  sp.v_W_mps = s.v_W_mps;
  sp.a_W_mps2 = s.a_W_mps2;
  const double vx = s.v_W_mps.x();
  const double vy = s.v_W_mps.y();
  const double speed2 = vx * vx + vy * vy;
  if (speed2 >= params_.yaw_min_speed_mps * params_.yaw_min_speed_mps) {
    held_yaw_rad_ = std::atan2(vy, vx);
    // d/dt atan2(vy, vx) = (vx ay - vy ax) / (vx^2 + vy^2)
    sp.yaw_rate_radps = (vx * s.a_W_mps2.y() - vy * s.a_W_mps2.x()) / speed2;
  }
  sp.yaw_rad = held_yaw_rad_;
  return sp;
}

}  // namespace aerotrack::trajectory_server

namespace aerotrack::trajectory_server {

std::optional<hal::Setpoint> TrajectoryServer::sampleFacing(rt::TimeNs now_ns, const Eigen::Vector3d& face_W_m) {
  std::optional<hal::Setpoint> sp = sample(now_ns);
  if (!sp) return sp;
  const Eigen::Vector2d d = (face_W_m - sp->p_W_m).head<2>();
  if (d.norm() > 0.3) {  // closer than that the bearing is noise: keep the last yaw
    held_yaw_rad_ = std::atan2(d.y(), d.x());
  }
  sp->yaw_rad = held_yaw_rad_;
  sp->yaw_rate_radps = 0.0;
  return sp;
}

}  // namespace aerotrack::trajectory_server
