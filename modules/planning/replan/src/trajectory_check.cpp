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
    case CheckVerdict::kTooCloseToBystander:
      return "too_close_to_bystander";
  }
  return "unknown";
}

const rt::FieldTable<TrajectoryCheckParams>& trajectoryCheckFields() {
  using P = TrajectoryCheckParams;
  using rt::Range;
  static const rt::FieldTable<P> kTable({
      rt::number("max_velocity_mps", &P::max_velocity_mps, Range::closed(0.1, 30.0)),
      rt::number("max_acceleration_mps2", &P::max_acceleration_mps2, Range::closed(0.1, 50.0)),
      rt::number("max_jerk_mps3", &P::max_jerk_mps3, Range::closed(0.1, 1e4)),
      rt::number("tolerance", &P::tolerance, Range::closed(0.0, 1.0)),
      rt::number("sample_step_s", &P::sample_step_s, Range::closed(1e-3, 1.0)),
      rt::number("horizon_s", &P::horizon_s, Range::closed(0.1, 60.0)),
      rt::number("margin_escape_s", &P::margin_escape_s, Range::closed(0.01, 10.0)),
      rt::number("max_repair_stretch", &P::max_repair_stretch, Range::closed(1.0, 10.0)),
  });
  return kTable;
}

rt::Status validate(const TrajectoryCheckParams& params) {
  return trajectoryCheckFields().validate(params);
}

TrajectoryCheckParams parseTrajectoryCheckParams(const rt::ConfigNode& node) {
  return trajectoryCheckFields().parse(node);
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

double dynamicStretchFactor(const PolynomialTrajectory& trajectory, const TrajectoryCheckParams& params) {
  const double end_s = std::min(trajectory.durationS(), params.horizon_s);
  const int steps = std::max(1, static_cast<int>(std::ceil(end_s / params.sample_step_s)));
  double v_max = 0.0;
  double a_max = 0.0;
  double j_max = 0.0;
  for (int k = 0; k <= steps; ++k) {
    const double t = end_s * k / steps;
    const trajectory_server::TrajectorySample s = trajectory.sample(t);
    v_max = std::max(v_max, s.v_W_mps.norm());
    a_max = std::max(a_max, s.a_W_mps2.norm());
    j_max = std::max(j_max, trajectory.derivative(3, t).norm());
  }
  return std::max({1.0, v_max / params.max_velocity_mps, std::sqrt(a_max / params.max_acceleration_mps2),
                   std::cbrt(j_max / params.max_jerk_mps3)});
}

}  // namespace aerotrack::planning
