// The test seam of TrackingPlanner (its friend), shared by the planning tests that run the stages of plan()
// one at a time.
#pragma once

#include "aerotrack/planning/tracking_planner.hpp"

namespace aerotrack::planning {

class TrackingPlannerStages {
 public:
  using PersonMotion = TrackingPlanner::PersonMotion;
  explicit TrackingPlannerStages(TrackingPlanner& planner) : planner_(planner) {}
  /// A live person as the planner sees one: their estimate extrapolated at constant velocity (no Bezier fit).
  static PersonMotion liveMotion(const TrackingPlanner& planner, const estimation::TargetEstimate& person) {
    PersonMotion m;
    m.estimate = &person;
    m.live = true;
    m.horizon_s = planner.params().prediction.horizon_s;
    m.sight_height_m = planner.params().person_sight_height_m;
    return m;
  }
  std::optional<PersonMotion> predictPerson(const PlanInputs& inputs) { return planner_.predictPerson(inputs); }
  KinematicState selectGoal(const mapping::LocalGrid& grid, const PersonMotion& person, const StatePva& start,
                            rt::TimeNs start_ns) const {
    return planner_.selectGoal(grid, person, start, start_ns);
  }
  SearchStatus searchTrackingPath(const mapping::LocalGrid& grid, const StatePva& start, rt::TimeNs start_ns,
                                  const KinematicState& goal, const PersonMotion& person) {
    return planner_.searchTrackingPath(grid, start, start_ns, goal, person);
  }
  rt::Status buildCorridor(const mapping::LocalGrid& grid, const StatePva& start) {
    return planner_.buildCorridor(grid, start);
  }
  rt::Expected<OptimizerResult> optimizeTrajectory(const mapping::LocalGrid& grid, const StatePva& start,
                                                   PolynomialTrajectory& out) {
    return planner_.optimizeTrajectory(grid, start, out);
  }
  CheckResult checkPlannedTrajectory(const PolynomialTrajectory& trajectory, const mapping::LocalGrid& grid,
                                     const PersonMotion& person, rt::TimeNs start_ns) const {
    return planner_.checkPlannedTrajectory(trajectory, grid, nullptr, person, start_ns);
  }
  double goalLeadS() const { return planner_.goalLeadS(); }
  /// The person's torso samples the last optimisation was given (the camera-view term).
  const std::vector<Eigen::Vector3d>& personTorso() const { return planner_.person_torso_W_m_; }
  void samplePersonTorso(const PersonMotion& person, rt::TimeNs start_ns) {
    planner_.samplePersonTorso(person, start_ns);
  }
  /// As if the last complete path to a live person's goal had lasted this long.
  void setArrivalS(double arrival_s) { planner_.arrival_s_ = arrival_s; }
  CheckResult repairPlannedTrajectory(CheckResult check, const StatePva& start, PolynomialTrajectory& out,
                                      const mapping::LocalGrid& grid, const PersonMotion& person, double& stretch) {
    return planner_.repairPlannedTrajectory(check, start, out, grid, nullptr, person, 0, stretch);
  }

 private:
  TrackingPlanner& planner_;
};

}  // namespace aerotrack::planning
