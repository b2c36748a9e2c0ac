// The planning section as YAML: see planning_yaml.hpp.
#include "planning_yaml.hpp"

#include <vector>

namespace aerotrack::app {
namespace {

template <class T>
void key(YAML::Emitter& out, const char* name, const T& value) {
  out << YAML::Key << name << YAML::Value << value;
}

}  // namespace

void emitPlanningYaml(YAML::Emitter& out, const planning::TrackingPlannerParams& p) {
  out << YAML::BeginMap;
  key(out, "planning_budget_s", p.planning_budget_s);
  key(out, "path_sample_step_s", p.path_sample_step_s);
  key(out, "min_piece_duration_s", p.min_piece_duration_s);
  key(out, "replan_reset_distance_m", p.replan_reset_distance_m);
  key(out, "stop_check_horizon_s", p.stop_check_horizon_s);
  key(out, "flight_altitude_m", p.flight_altitude_m);
  key(out, "person_sight_height_m", p.person_sight_height_m);
  key(out, "takeoff_below_m", p.takeoff_below_m);
  key(out, "min_person_distance_m", p.min_person_distance_m);
  out << YAML::Key << "goal" << YAML::Value << YAML::BeginMap;
  key(out, "predicted_weight", p.goal.predicted_weight);
  key(out, "tracking_distance_m", p.goal.tracking_distance_m);
  key(out, "visible_step_rad", p.goal.visible_step_rad);
  key(out, "visible_max_turn_rad", p.goal.visible_max_turn_rad);
  out << YAML::EndMap;
  const planning::KinodynamicSearchParams& s = p.search;
  out << YAML::Key << "search" << YAML::Value << YAML::BeginMap;
  key(out, "max_velocity_mps", s.max_velocity_mps);
  key(out, "max_acceleration_mps2", s.max_acceleration_mps2);
  key(out, "acceleration_steps", s.acceleration_steps);
  key(out, "primitive_duration_s", s.primitive_duration_s);
  key(out, "time_weight", s.time_weight);
  key(out, "heuristic_weight", s.heuristic_weight);
  key(out, "time_penalty_per_s", s.time_penalty_per_s);
  key(out, "occlusion_penalty", s.occlusion_penalty);
  key(out, "occlusion_aware", s.occlusion_aware);
  key(out, "position_resolution_m", s.position_resolution_m);
  key(out, "velocity_resolution_mps", s.velocity_resolution_mps);
  key(out, "goal_tolerance_m", s.goal_tolerance_m);
  key(out, "goal_velocity_tolerance_mps", s.goal_velocity_tolerance_mps);
  key(out, "one_shot_distance_m", s.one_shot_distance_m);
  key(out, "max_expansions", s.max_expansions);
  key(out, "max_nodes", s.max_nodes);
  out << YAML::EndMap;
  out << YAML::Key << "corridor" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "max_box_size_m" << YAML::Value << YAML::Flow
      << std::vector<double>{p.corridor.max_box_size_m.x(), p.corridor.max_box_size_m.y(),
                             p.corridor.max_box_size_m.z()};
  key(out, "max_boxes", p.corridor.max_boxes);
  key(out, "max_path_cells", p.corridor.max_path_cells);
  key(out, "corner_tolerance_m", p.corridor.corner_tolerance_m);
  out << YAML::EndMap;
  const planning::TrajectoryOptimizerParams& o = p.optimizer;
  out << YAML::Key << "optimizer" << YAML::Value << YAML::BeginMap;
  key(out, "max_velocity_mps", o.max_velocity_mps);
  key(out, "max_acceleration_mps2", o.max_acceleration_mps2);
  key(out, "max_jerk_mps3", o.max_jerk_mps3);
  key(out, "barrier_weight", o.barrier_weight);
  key(out, "time_weight", o.time_weight);
  key(out, "waypoint_velocity_weight", o.waypoint_velocity_weight);
  key(out, "waypoint_acceleration_weight", o.waypoint_acceleration_weight);
  key(out, "corridor_weight", o.corridor_weight);
  key(out, "corridor_margin_m", o.corridor_margin_m);
  key(out, "sample_velocity_weight", o.sample_velocity_weight);
  key(out, "sample_acceleration_weight", o.sample_acceleration_weight);
  key(out, "sample_jerk_weight", o.sample_jerk_weight);
  key(out, "samples_per_piece", o.samples_per_piece);
  key(out, "max_iterations", o.max_iterations);
  key(out, "relative_cost_tolerance", o.relative_cost_tolerance);
  key(out, "gradient_tolerance", o.gradient_tolerance);
  key(out, "memory", o.memory);
  key(out, "max_pieces", o.max_pieces);
  out << YAML::EndMap;
  const prediction::TargetPredictorParams& r = p.prediction;
  out << YAML::Key << "prediction" << YAML::Value << YAML::BeginMap;
  key(out, "bezier_degree", r.bezier_degree);
  key(out, "window_s", r.window_s);
  key(out, "horizon_s", r.horizon_s);
  key(out, "weight_half_life_s", r.weight_half_life_s);
  key(out, "accel_energy_weight_s3", r.accel_energy_weight_s3);
  key(out, "max_speed_mps", r.max_speed_mps);
  key(out, "max_accel_mps2", r.max_accel_mps2);
  key(out, "fit_z", r.fit_z);
  key(out, "pin_to_newest", r.pin_to_newest);
  key(out, "min_samples", r.min_samples);
  key(out, "max_data_age_s", r.max_data_age_s);
  key(out, "max_samples", r.max_samples);
  key(out, "qp_max_iterations", r.qp_max_iterations);
  out << YAML::EndMap;
  const planning::TrajectoryCheckParams& c = p.check;
  out << YAML::Key << "check" << YAML::Value << YAML::BeginMap;
  key(out, "max_velocity_mps", c.max_velocity_mps);
  key(out, "max_acceleration_mps2", c.max_acceleration_mps2);
  key(out, "max_jerk_mps3", c.max_jerk_mps3);
  key(out, "tolerance", c.tolerance);
  key(out, "sample_step_s", c.sample_step_s);
  key(out, "horizon_s", c.horizon_s);
  key(out, "margin_escape_s", c.margin_escape_s);
  out << YAML::EndMap;
  out << YAML::Key << "collision" << YAML::Value << YAML::BeginMap;
  key(out, "radius_m", p.collision.radius_m);
  key(out, "sample_step_m", p.collision.sample_step_m);
  key(out, "margin_m", p.collision.margin_m);
  key(out, "broad_phase_group", p.collision.broad_phase_group);
  out << YAML::EndMap;
  out << YAML::EndMap;
}

}  // namespace aerotrack::app
