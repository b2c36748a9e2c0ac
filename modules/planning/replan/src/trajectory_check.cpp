// Final trajectory check: see trajectory_check.hpp.
#include "aerotrack/planning/trajectory_check.hpp"

#include <algorithm>
#include <cmath>

namespace aerotrack::planning {

std::string_view toString(CheckVerdict verdict) {
  switch (verdict) {
    case CheckVerdict::kOk:
      return "ok";
    case CheckVerdict::kVelocity:
      return "velocity";
    case CheckVerdict::kAcceleration:
      return "acceleration";
    case CheckVerdict::kJerk:
      return "jerk";
    case CheckVerdict::kGridBlocked:
      return "grid_blocked";
    case CheckVerdict::kCollision:
      return "collision";
    case CheckVerdict::kCheckerError:
      return "checker_error";
    case CheckVerdict::kTooCloseToPerson:
      return "too_close_to_person";
  }
  return "unknown";
}

rt::Status validate(const TrajectoryCheckParams& p) {
  if (!(p.max_velocity_mps > 0.0)) return rt::Error{"max_velocity_mps must be > 0"};
  if (!(p.max_acceleration_mps2 > 0.0)) return rt::Error{"max_acceleration_mps2 must be > 0"};
  if (!(p.max_jerk_mps3 > 0.0)) return rt::Error{"max_jerk_mps3 must be > 0"};
  if (!(p.tolerance >= 0.0 && p.tolerance <= 1.0)) return rt::Error{"tolerance must be in [0, 1]"};
  if (!(p.sample_step_s > 0.0)) return rt::Error{"sample_step_s must be > 0"};
  if (!(p.horizon_s > 0.0)) return rt::Error{"horizon_s must be > 0"};
  if (!(p.margin_escape_s > 0.0)) return rt::Error{"margin_escape_s must be > 0"};
  return rt::ok();
}

TrajectoryCheckParams parseTrajectoryCheckParams(const rt::ConfigNode& node) {
  TrajectoryCheckParams p;
  p.max_velocity_mps = node.getDouble("max_velocity_mps", 0.1, 30.0);
  p.max_acceleration_mps2 = node.getDouble("max_acceleration_mps2", 0.1, 50.0);
  p.max_jerk_mps3 = node.getDouble("max_jerk_mps3", 0.1, 1e4);
  p.tolerance = node.getDouble("tolerance", 0.0, 1.0);
  p.sample_step_s = node.getDouble("sample_step_s", 1e-3, 1.0);
  p.horizon_s = node.getDouble("horizon_s", 0.1, 60.0);
  p.margin_escape_s = node.getDouble("margin_escape_s", 0.01, 10.0);
  node.finish();
  return p;
}

CheckResult checkTrajectory(const PolynomialTrajectory& trajectory, const TrajectoryCheckParams& params,
                            const mapping::LocalGrid& grid, const mapping::TrajectoryChecker& checker,
                            const octomap::OcTree* octree) {
  const double end_s = std::min(trajectory.durationS(), params.horizon_s);
  const double scale = 1.0 + params.tolerance;
  const double v2 = std::pow(params.max_velocity_mps * scale, 2);
  const double a2 = std::pow(params.max_acceleration_mps2 * scale, 2);
  const double j2 = std::pow(params.max_jerk_mps3 * scale, 2);
  const int steps = std::max(1, static_cast<int>(std::ceil(end_s / params.sample_step_s)));
  MarginWalk margin(params.margin_escape_s);
  for (int k = 0; k <= steps; ++k) {
    const double t = end_s * k / steps;
    const trajectory_server::TrajectorySample s = trajectory.sample(t);
    if (s.v_W_mps.squaredNorm() > v2) return {CheckVerdict::kVelocity, t};
    if (s.a_W_mps2.squaredNorm() > a2) return {CheckVerdict::kAcceleration, t};
    if (trajectory.derivative(3, t).squaredNorm() > j2) return {CheckVerdict::kJerk, t};
    if (margin.blocked(t, grid.isOccupied(s.p_W_m))) return {CheckVerdict::kGridBlocked, t};
  }
  if (octree != nullptr) {
    const auto report = checker.check(trajectory, 0.0, end_s, *octree);
    if (!report) return {CheckVerdict::kCheckerError, 0.0};
    if (!report->collision_free) return {CheckVerdict::kCollision, report->first_collision_t_s.value_or(0.0)};
  }
  return {};
}

}  // namespace aerotrack::planning
