// Rest-to-rest minimum-jerk tour: see min_jerk_tour.hpp.
#include "aerotrack/trajectory_server/min_jerk_tour.hpp"

#include <algorithm>
#include <cmath>

namespace aerotrack::trajectory_server {
namespace {

constexpr double kPeakSpeedFactor = 1.875;              // max s'(tau)
const double kPeakAccelFactor = 10.0 / std::sqrt(3.0);  // max |s''(tau)|

}  // namespace

rt::Expected<MinJerkTour> MinJerkTour::create(std::vector<Eigen::Vector3d> waypoints_W_m, double max_speed_mps,
                                              double max_accel_mps2) {
  if (waypoints_W_m.size() < 2) return rt::Error{"a tour needs at least two waypoints"};
  if (!(max_speed_mps > 0.0) || !(max_accel_mps2 > 0.0))
    return rt::Error{"tour speed and acceleration limits must be > 0"};
  for (const Eigen::Vector3d& w : waypoints_W_m)
    if (!w.allFinite()) return rt::Error{"a tour waypoint is not finite"};
  MinJerkTour tour;
  tour.leg_start_s_.push_back(0.0);
  for (std::size_t i = 1; i < waypoints_W_m.size(); ++i) {
    const double d_m = (waypoints_W_m[i] - waypoints_W_m[i - 1]).norm();
    const double t_s =
        std::max({kPeakSpeedFactor * d_m / max_speed_mps, std::sqrt(kPeakAccelFactor * d_m / max_accel_mps2), 1e-3});
    tour.leg_duration_s_.push_back(t_s);
    tour.leg_start_s_.push_back(tour.leg_start_s_.back() + t_s);
  }
  tour.waypoints_W_m_ = std::move(waypoints_W_m);
  return tour;
}

TrajectorySample MinJerkTour::sample(double t_s) const {
  t_s = std::clamp(t_s, 0.0, durationS());
  // The leg containing t_s: the last leg whose start is <= t_s.
  const auto it = std::upper_bound(leg_start_s_.begin(), leg_start_s_.end() - 1, t_s);
  const std::size_t leg =
      std::min<std::size_t>(static_cast<std::size_t>(it - leg_start_s_.begin()) - 1, leg_duration_s_.size() - 1);
  const double T = leg_duration_s_[leg];
  const double tau = std::clamp((t_s - leg_start_s_[leg]) / T, 0.0, 1.0);
  const double tau2 = tau * tau;
  const double s = tau2 * tau * (10.0 - 15.0 * tau + 6.0 * tau2);
  const double ds = 30.0 * tau2 * (1.0 - 2.0 * tau + tau2) / T;              // 30 tau^2 (1 - tau)^2 / T
  const double dds = 60.0 * tau * (1.0 - 3.0 * tau + 2.0 * tau2) / (T * T);  // 60 tau (1 - tau)(1 - 2 tau) / T^2
  const Eigen::Vector3d delta = waypoints_W_m_[leg + 1] - waypoints_W_m_[leg];
  TrajectorySample out;
  out.p_W_m = waypoints_W_m_[leg] + s * delta;
  out.v_W_mps = ds * delta;
  out.a_W_mps2 = dds * delta;
  return out;
}

}  // namespace aerotrack::trajectory_server
