// The planning config section and the planner's parameter checks: see tracking_planner.hpp. One field
// table (rt/field_table.hpp) drives parsing, validate() and printing (--print-config); each nested
// section's table is owned by the module of its struct.
#include "aerotrack/planning/tracking_planner.hpp"

namespace aerotrack::planning {

const rt::FieldTable<TrackingPlannerParams>& trackingPlannerFields() {
  using P = TrackingPlannerParams;
  using rt::Range;
  static const rt::FieldTable<P> kTable(
      {
          rt::number("planning_budget_s", &P::planning_budget_s, Range::closedOpen(0.0, 1.0)),
          rt::number("path_sample_step_s", &P::path_sample_step_s, Range::closed(1e-3, 1.0)),
          rt::number("min_piece_duration_s", &P::min_piece_duration_s, Range::closed(1e-3, 10.0)),
          rt::number("replan_reset_distance_m", &P::replan_reset_distance_m, Range::closed(0.01, 100.0)),
          rt::number("stop_check_horizon_s", &P::stop_check_horizon_s, Range::closed(0.0, 60.0)),
          rt::number("flight_altitude_m", &P::flight_altitude_m, Range::closed(0.1, 100.0)),
          rt::number("person_sight_height_m", &P::person_sight_height_m, Range::closed(0.1, 5.0)),
          rt::number("person_torso_half_m", &P::person_torso_half_m, Range::closed(0.0, 1.0)),
          rt::number("takeoff_below_m", &P::takeoff_below_m, Range::closed(0.0, 100.0)),
          rt::number("min_altitude_m", &P::min_altitude_m, Range::closed(0.0, 100.0)),
          rt::number("max_altitude_m", &P::max_altitude_m, Range::closed(0.1, 1000.0)),
          rt::number("min_person_distance_m", &P::min_person_distance_m, Range::closed(0.0, 50.0)),
          rt::number("min_bystander_distance_m", &P::min_bystander_distance_m, Range::closed(0.0, 50.0)),
          rt::number("bystander_sight_radius_m", &P::bystander_sight_radius_m, Range::closed(0.0, 5.0)),
          rt::number("optimizer_limit_fraction", &P::optimizer_limit_fraction, Range::openClosed(0.0, 1.0)),
          rt::number("time_weight_reference_speed_mps", &P::time_weight_reference_speed_mps,
                     Range::openClosed(0.0, 100.0)),
          rt::number("time_weight_reference_speed_change_mps", &P::time_weight_reference_speed_change_mps,
                     Range::closed(0.0, 100.0)),
          rt::number("max_time_weight_scale", &P::max_time_weight_scale, Range::closed(1.0, 1000.0)),
          rt::section("goal", &P::goal, trackingGoalFields()),
          rt::section("search", &P::search, kinodynamicSearchFields()),
          rt::section("corridor", &P::corridor, corridorFields()),
          rt::section("optimizer", &P::optimizer, trajectoryOptimizerFields()),
          rt::section("prediction", &P::prediction, prediction::targetPredictorFields()),
          rt::section("check", &P::check, trajectoryCheckFields()),
          rt::section("collision", &P::collision, mapping::trajectoryCheckerFields()),
          rt::section("relocation", &P::relocation, relocationSearchFields()),
      },
      {{"flight_altitude_m", "must be > takeoff_below_m",
        [](const P& p) { return p.flight_altitude_m > p.takeoff_below_m; }},
       {"flight_altitude_m", "must lie in [min_altitude_m, max_altitude_m]", [](const P& p) {
          return p.min_altitude_m <= p.flight_altitude_m && p.flight_altitude_m <= p.max_altitude_m;
        }}});
  return kTable;
}

rt::Status validate(const TrackingPlannerParams& params) {
  return trackingPlannerFields().validate(params);
}

TrackingPlannerParams parseTrackingPlannerParams(const rt::ConfigNode& node) {
  return trackingPlannerFields().parse(node);
}

}  // namespace aerotrack::planning
