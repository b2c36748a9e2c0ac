// The planning config section and the planner's parameter checks: see tracking_planner.hpp.
#include <cmath>

#include "aerotrack/planning/tracking_planner.hpp"

namespace aerotrack::planning {

rt::Status validate(const TrackingPlannerParams& p) {
  if (!(p.planning_budget_s >= 0.0 && p.planning_budget_s < 1.0))
    return rt::Error{"planning_budget_s must be in [0, 1)"};
  if (!(p.path_sample_step_s > 0.0)) return rt::Error{"path_sample_step_s must be > 0"};
  if (!(p.min_piece_duration_s > 0.0)) return rt::Error{"min_piece_duration_s must be > 0"};
  if (!(p.replan_reset_distance_m > 0.0)) return rt::Error{"replan_reset_distance_m must be > 0"};
  if (!(p.stop_check_horizon_s >= 0.0)) return rt::Error{"stop_check_horizon_s must be >= 0"};
  if (!(p.takeoff_below_m >= 0.0)) return rt::Error{"takeoff_below_m must be >= 0"};
  if (!(p.min_person_distance_m >= 0.0)) return rt::Error{"min_person_distance_m must be >= 0"};
  if (!(p.flight_altitude_m > p.takeoff_below_m)) return rt::Error{"flight_altitude_m must exceed takeoff_below_m"};
  if (!(p.person_sight_height_m > 0.0)) return rt::Error{"person_sight_height_m must be > 0"};
  if (!(p.goal.predicted_weight >= 0.0 && p.goal.predicted_weight <= 1.0))
    return rt::Error{"goal.predicted_weight must be in [0, 1]"};
  if (!(p.goal.tracking_distance_m >= 0.0)) return rt::Error{"goal.tracking_distance_m must be >= 0"};
  if (const rt::Status s = validate(p.optimizer); !s) return rt::Error{"optimizer: " + s.error().message};
  if (const rt::Status s = validate(p.check); !s) return rt::Error{"check: " + s.error().message};
  return rt::ok();
}

namespace {

mapping::TrajectoryCheckerParams parseCollisionParams(const rt::ConfigNode& node) {
  mapping::TrajectoryCheckerParams p;
  p.radius_m = node.getDouble("radius_m", 0.01, 5.0);
  p.sample_step_m = node.getDouble("sample_step_m", 0.005, 5.0);
  p.margin_m = node.getDouble("margin_m", 0.0, 5.0);
  p.broad_phase_group = node.getInt("broad_phase_group", 1, 64);
  node.finish();
  return p;
}

TrackingGoalParams parseGoalParams(const rt::ConfigNode& node) {
  TrackingGoalParams p;
  p.predicted_weight = node.getDouble("predicted_weight", 0.0, 1.0);
  p.tracking_distance_m = node.getDouble("tracking_distance_m", 0.0, 50.0);
  p.visible_step_rad = node.getDouble("visible_step_rad", 0.01, 3.2);
  p.visible_max_turn_rad = node.getDouble("visible_max_turn_rad", 0.0, 3.2);
  node.finish();
  return p;
}

}  // namespace

TrackingPlannerParams parseTrackingPlannerParams(const rt::ConfigNode& node) {
  TrackingPlannerParams p;
  p.planning_budget_s = node.getDouble("planning_budget_s", 0.0, 0.999);
  p.path_sample_step_s = node.getDouble("path_sample_step_s", 1e-3, 1.0);
  p.min_piece_duration_s = node.getDouble("min_piece_duration_s", 1e-3, 10.0);
  p.replan_reset_distance_m = node.getDouble("replan_reset_distance_m", 0.01, 100.0);
  p.stop_check_horizon_s = node.getDouble("stop_check_horizon_s", 0.0, 60.0);
  p.flight_altitude_m = node.getDouble("flight_altitude_m", 0.1, 100.0);
  p.person_sight_height_m = node.getDouble("person_sight_height_m", 0.1, 5.0);
  p.takeoff_below_m = node.getDouble("takeoff_below_m", 0.0, 100.0);
  p.min_person_distance_m = node.getDouble("min_person_distance_m", 0.0, 50.0);
  p.goal = parseGoalParams(node.child("goal"));
  p.search = parseKinodynamicSearchParams(node.child("search"));
  p.corridor = parseCorridorParams(node.child("corridor"));
  p.optimizer = parseTrajectoryOptimizerParams(node.child("optimizer"));
  p.prediction = prediction::parseTargetPredictorParams(node.child("prediction"));
  p.check = parseTrajectoryCheckParams(node.child("check"));
  p.collision = parseCollisionParams(node.child("collision"));
  node.finish();
  return p;
}

}  // namespace aerotrack::planning
