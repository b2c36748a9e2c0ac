// One replanning cycle of the tracking planner (paper Sect. V; issue 8 item 4):
//   0. take-off: a start below takeoff_below_m (on the ground, inside the floor's inflation margin)
//      climbs straight up to flight_altitude_m;
//   1. start state: where the current trajectory will be when the new one takes over, at
//      now + planning_budget_s (position, velocity and acceleration, so the hand-over is smooth); from
//      odometry instead when there is no current trajectory or the drone has strayed from it;
//   2. prediction: the person's path, a Bezier QP over their recent estimates (Sect. V-A,
//      modules/prediction); a constant-velocity extrapolation while the predictor has too few samples;
//   3. goal and search: the tracking goal mixed from the person's current and predicted states, and the
//      occlusion-aware kinodynamic search towards it (Sect. V-B, modules/planning/search);
//   4. corridor: overlapping free boxes along the search path (Sect. V-C, modules/planning/corridor);
//   5. optimisation: the minimum-jerk spline in the corridor (Sect. V-C, modules/planning/trajectory);
//   6. final check: limits, inflated grid, FCL against the octree (trajectory_check.hpp), and the minimum
//      distance to the person's predicted path (never fly into them). A trajectory over the dynamic limits
//      only (the optimiser's penalties are soft) is repaired first: re-timed slower by the stretch the
//      worst violation needs, from the same start state, and checked again in full (issue 21).
// A cycle that fails at any stage publishes nothing: the current trajectory continues (the trajectory
// server holds its end at rest). If the person, on their predicted path, would come within
// min_person_distance_m of the drone even if it braked (they walk at it, or double back past it), the drone
// moves out of their way instead (evadePeople, issue 21: a person too close is a reason to back away, not
// to stop planning; the gimbal stays on them and the next cycle plans to follow again); so it does for the
// other people the target task tracks (min_bystander_distance_m), also when hovering at its goal. If, in addition, the
// current trajectory's next stretch is no longer clear in the newest grid, a stopping trajectory (a minimum-jerk brake
// to rest along the current velocity) is issued instead. Pure: time, odometry, the estimate and the maps come in; no
// clock is read.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

#include <octomap/OcTree.h>

#include "aerotrack/estimation/target_estimator.hpp"
#include "aerotrack/hal/types.hpp"
#include "aerotrack/mapping/local_grid.hpp"
#include "aerotrack/mapping/trajectory_checker.hpp"
#include "aerotrack/planning/corridor.hpp"
#include "aerotrack/planning/kinodynamic_search.hpp"
#include "aerotrack/planning/polynomial_trajectory.hpp"
#include "aerotrack/planning/relocation_search.hpp"
#include "aerotrack/planning/trajectory_check.hpp"
#include "aerotrack/planning/trajectory_optimizer.hpp"
#include "aerotrack/prediction/target_predictor.hpp"
#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/field_table.hpp"
#include "aerotrack/trajectory_server/trajectory.hpp"

namespace aerotrack::planning {

struct TrackingPlannerParams {
  double planning_budget_s = 0.05;       ///< The new trajectory takes over at now + this; >= 0.
  double path_sample_step_s = 0.02;      ///< The search path is cut into chords this long for the corridor; > 0.
  double min_piece_duration_s = 0.05;    ///< Initial durations are at least this; > 0.
  double replan_reset_distance_m = 1.0;  ///< Drone this far from the current trajectory: start from odometry; > 0.
  double stop_check_horizon_s = 1.0;     ///< On a failed cycle, this much of the current trajectory must be clear.
  double flight_altitude_m = 1.5;        ///< The goal's height (W z); > takeoff_below_m.
  double takeoff_below_m = 0.5;          ///< A start lower than this climbs straight to flight_altitude_m first; >= 0.
  /// The heights (W z) the search's paths and the corridor's boxes keep to (a start outside climbs or sinks
  /// back, never away); min_altitude_m <= flight_altitude_m <= max_altitude_m. Why (issue 21): unknown space
  /// counts as free (Fast-Tracker), and a crosser's legs, below the depth camera's view at close range, left
  /// free-looking space under their mapped torso: the path dived to 0.5 m and the drone stuck in the floor's
  /// margin. Fast-Planner bounds its search's height the same way (a ground and a ceiling).
  double min_altitude_m = 1.0;
  double max_altitude_m = 3.0;
  /// The height (W z) at which the planner sees the person: lines of sight for the occlusion term and the
  /// visible goal end at the estimate's horizontal position at this height (the torso's centre). The
  /// estimate's own z is the localization regression's ground-plane constant (the paper's assumption 1),
  /// about 0.3 m below the ground: sight lines to it crossed the ground and every node was occluded.
  double person_sight_height_m = 1.1;  ///< > 0.
  /// Half the person's shoulders-to-hips length: the optimiser keeps both ends of the torso (about the sight
  /// height) in the camera's vertical field of view (optimizer.camera_view_weight, camera_view.hpp); >= 0.
  double person_torso_half_m = 0.25;
  /// Never fly into the person: a trajectory that comes horizontally closer to their predicted path than
  /// this (or than it starts, if it starts closer) is refused by the final check; >= 0.
  double min_person_distance_m = 1.0;
  /// Never fly into anyone else either: the other people the target task tracks (TargetEstimate::others) are
  /// kept this far, horizontally, along their constant-velocity paths (held after prediction.horizon_s), or
  /// no closer than they start; a person walking at the drone is moved away from (evadePeople); 0: off; >= 0.
  /// Why (issue 21 item 5): the crowd's people walked into the drone's path faster than the map showed
  /// them there (crowd seed 19: a walker 14 degrees ahead, in both cameras' view, came within reach while the
  /// drone flew on at 1.8 m/s; the map-based stop came at 0.5 m). The drone's radius plus a person's half
  /// width (0.25 m each) plus room for the estimate's error at a few metres and a brake.
  double min_bystander_distance_m = 0.8;
  /// Occlusion-aware mode: the other people the target task tracks hide the person from a point when one of them
  /// stands within this of the line of sight to the person, in front of them (peopleBlockSight) -- for the visible
  /// goal (now and at the prediction horizon) and the search's occlusion penalty, along their constant-velocity
  /// paths; 0: off (only the map occludes); >= 0. Why (issue 22 item 2): see SightBlockers. A person's half
  /// width plus the other's (0.25 m each): their silhouettes overlap.
  double bystander_sight_radius_m = 0.0;
  /// The optimiser's velocity, acceleration and jerk targets are this fraction of the check's (the
  /// vehicle's) limits, set by create(): one set of limits, the soft penalties' targets inside it by a
  /// stated margin (issue 21). The optimizer section's own limit fields are overwritten; in (0, 1].
  double optimizer_limit_fraction = 0.93;
  /// The optimiser's time weight rho_t is scaled by (v / this)^2 for a person walking at v faster than this,
  /// at most by max_time_weight_scale (1: never). Why (issue 21): a plan's natural duration under
  /// J = jerk^2 + rho_t T, over the distance the person covers in it, is T^4 = 3600 v^2 / rho_t (a
  /// rest-to-rest min-jerk piece); a fixed rho_t either dawdles behind a runner (rho_t 20: forest at 4 m/s,
  /// farther than 5 m in 10 of 10 trials) or hunts after a walker's estimate noise (rho_t 200: a median
  /// commanded acceleration of 1.2 m/s^2 at 1.5 m/s, and the body's tilt tripled the estimate's error).
  double time_weight_reference_speed_mps = 1.5;  ///< > 0.
  /// ... or by (dv / this)^2 where larger, dv the horizontal speed change the plan asks for (the goal's velocity
  /// less the start's); 0: off. Why (issue 21): a person setting off is slow for the first half second, so
  /// their speed alone keeps rho_t a walker's while the drone falls behind a runner who accelerates at 3 m/s^2;
  /// the change the plan must make is what a short plan needs (T^4 = 3600 dv^2 / rho_t).
  double time_weight_reference_speed_change_mps = 0.0;  ///< >= 0.
  double max_time_weight_scale = 10.0;                  ///< >= 1.
  TrackingGoalParams goal;
  KinodynamicSearchParams search;
  CorridorParams corridor;
  TrajectoryOptimizerParams optimizer;
  prediction::TargetPredictorParams prediction;
  TrajectoryCheckParams check;
  mapping::TrajectoryCheckerParams collision;
  /// The search pattern after a relocation's predicted path (issue 21 item 3; the planning task runs it).
  RelocationSearchParams relocation;
};

/// The `planning:` config section: the scalars above and the sub-sections goal, search, corridor,
/// optimizer, prediction, check, collision (each its module's table); every key required. The one list
/// of keys and ranges that parsing, validate() and printing (--print-config) share (rt/field_table.hpp);
/// the ranges are in planner_config.cpp, with the rule flight_altitude_m > takeoff_below_m.
const rt::FieldTable<TrackingPlannerParams>& trackingPlannerFields();
/// Every field (sub-sections included) in its range, and every rule; the error names the key path
/// ("goal.predicted_weight must be in [0, 1], got 2").
rt::Status validate(const TrackingPlannerParams& params);
/// trackingPlannerFields().parse. Throws rt::ConfigError naming the file, line and key.
TrackingPlannerParams parseTrackingPlannerParams(const rt::ConfigNode& node);

enum class PlanStatus : std::uint8_t {
  kPlanned,          ///< A checked trajectory was produced.
  kStopped,          ///< The cycle failed (any reason below) and the current trajectory was blocked: a stop.
  kTakeOff,          ///< The start was below takeoff_below_m: a vertical climb to the flight altitude.
  kAtGoal,           ///< The search's path is too short to fly (the drone is at the goal): nothing published.
  kRelocating,       ///< As kPlanned, towards the person's last predicted path (relocation).
  kNoOdometry,       ///< No odometry yet.
  kNoMap,            ///< No local grid yet.
  kNoTarget,         ///< No live estimate of the person (never seen, or lost).
  kSearchFailed,     ///< The search found no path (start blocked, no path, invalid input).
  kCorridorFailed,   ///< The corridor could not be built along the path.
  kOptimizerFailed,  ///< The optimiser refused the problem.
  kCheckFailed,      ///< The optimised trajectory failed the final check.
  /// The cycle failed (any reason above), or the drone was at its goal, with the person (or someone else)
  /// coming within min_person_distance_m (min_bystander_distance_m) of a drone that would only brake or hover:
  /// a move away from their predicted paths was flown instead (issue 21, evadePeople).
  kEvading,
  /// The start lay in an obstacle's inflation margin, where no search can begin (start_blocked): a short move
  /// to rest at the nearest free point in plain sight was flown instead (issue 21, escapeMargin).
  kEscaping,
};
inline constexpr int kPlanStatusCount = 14;
std::string_view toString(PlanStatus status);

/// What a cycle reads.
struct PlanInputs {
  rt::TimeNs now_ns = 0;
  const hal::OdometrySample* odometry = nullptr;
  const estimation::TargetEstimate* target = nullptr;
  const mapping::LocalGrid* grid = nullptr;
  const octomap::OcTree* octree = nullptr;                      ///< Null: no FCL check (grid check only).
  const trajectory_server::TimedTrajectory* current = nullptr;  ///< What the server flies now; may be empty.
  /// Relocation (the supervisor's relocate mode, the paper's target-relocating strategy): with no live
  /// estimate, fly along the last predicted path (continued at its end velocity) instead of failing.
  bool relocate = false;
  /// The relocation's search (issue 21 item 3): with no live estimate, fly to this viewpoint (to rest) with the
  /// relocation machinery, keeping the point it looks at in sight (the occlusion term), instead of the last path.
  const Viewpoint* look = nullptr;
};

/// What a cycle did (counters for the statistics, and the trajectory written into `out`).
struct PlanReport {
  PlanStatus status = PlanStatus::kNoOdometry;
  rt::TimeNs start_ns = 0;  ///< When the new trajectory takes over (kPlanned, kStopped).
  SearchStatus search_status = SearchStatus::kNoPath;
  int search_expansions = 0;
  int corridor_boxes = 0;
  OptimizerStatus optimizer_status = OptimizerStatus::kConverged;
  int optimizer_iterations = 0;
  CheckVerdict check = CheckVerdict::kOk;        ///< The final verdict (after any repair).
  CheckVerdict first_check = CheckVerdict::kOk;  ///< The optimiser's output's verdict, before any repair.
  double repair_stretch = 1.0;  ///< The time stretch a repair applied (1: none); with check kOk: repaired.
  bool predicted = false;       ///< The Bezier prediction was used (else constant velocity).
};

/// Not thread-safe (one planning thread). create() allocates all scratch memory; a warm cycle allocates
/// only when the piece count changes (the L-BFGS history) or inside FCL.
class TrackingPlanner {
 public:
  static rt::Expected<TrackingPlanner> create(const TrackingPlannerParams& params);

  const TrackingPlannerParams& params() const { return params_; }
  /// The factor on the optimiser's time weight for a person at this horizontal speed and a plan asking for this
  /// horizontal speed change: the larger of (v / reference)^2 and (dv / reference)^2, in [1, max_time_weight_scale].
  double timeWeightScale(double person_speed_mps, double speed_change_mps = 0.0) const;
  /// The baseline mode of the paper's comparison: no occlusion term in the search.
  void setOcclusionAware(bool aware) { search_.setOcclusionAware(aware); }

  /// Feeds the person's estimate to the predictor (call every cycle; repeats and lost estimates are ignored).
  void observeTarget(const estimation::TargetEstimate& estimate);

  /// One cycle: the stages below in turn, each one's result the next one's input. On kPlanned, kStopped
  /// and kTakeOff the trajectory to fly is in `out` (starting at report.start_ns); on other statuses `out`
  /// may hold a rejected attempt and must not be flown.
  PlanReport plan(const PlanInputs& inputs, PolynomialTrajectory& out);

  /// The state a cycle starts from (exposed for tests): the current trajectory at start_ns, or the
  /// odometry (acceleration zero) when there is none or the drone strayed from it.
  StatePva startState(const PlanInputs& inputs, rt::TimeNs start_ns) const;
  /// The search path cut into the polyline the corridor follows (exposed for tests).
  const std::vector<Eigen::Vector3d>& polyline() const { return polyline_; }
  const Corridor& corridor() const { return corridor_; }
  const SearchPath& searchPath() const { return path_; }
  /// The newest Bezier prediction of a live person (the one relocation flies along), if any.
  const std::optional<prediction::TargetPrediction>& lastPrediction() const { return last_prediction_; }

  /// Evasion's candidate directions, evenly spaced round the horizontal plane (22.5 degrees apart: fine
  /// enough to find a gap between trees, few enough that scoring all costs a few hundred samples).
  static constexpr int kEvasionDirections = 16;

  /// A minimum-jerk move from `start` to rest at end_W_m, at half the optimiser's limits.
  void makeMoveTrajectory(const StatePva& start, const Eigen::Vector3d& end_W_m, PolynomialTrajectory& out);
  /// A minimum-jerk brake from `start` to rest, along the current velocity, within the acceleration limit.
  void makeStopTrajectory(const StatePva& start, PolynomialTrajectory& out);
  /// Appends to `out` a brake from its end state to rest (as makeStopTrajectory), unless it ends at rest.
  void appendStop(PolynomialTrajectory& out);

 private:
  friend class TrackingPlannerStages;  // the test seam: tests/unit/planning runs the stages one by one

  TrackingPlanner(const TrackingPlannerParams& params, KinodynamicSearch search, CorridorBuilder corridor,
                  TrajectoryOptimizer optimizer, prediction::TargetPredictor predictor,
                  mapping::TrajectoryChecker checker);
  bool currentBlocked(const PlanInputs& inputs) const;

  /// The person's motion as the stages after the prediction see it (what predictPerson gives them).
  struct PersonMotion {
    /// The Bezier prediction (live) or the last one (relocation); null: constant velocity from `estimate`.
    const prediction::TargetPrediction* prediction = nullptr;
    const estimation::TargetEstimate* estimate = nullptr;  ///< Used only when `prediction` is null.
    bool live = false;                                     ///< A live estimate (else relocation).
    double horizon_s = 0.0;       ///< Constant velocity runs on this far past the estimate at most.
    double sight_height_m = 0.0;  ///< The W z of every position (the torso's centre).
    /// The final check keeps min_person_distance_m from it (false for a search's look point, where nobody is
    /// known to be: the drone may fly close to it and look behind it).
    bool keep_away = true;
    /// The person's position at t_ns (W, m) at the sight height. Past its end a prediction is continued at
    /// its end velocity (a Bezier extrapolated would diverge).
    Eigen::Vector3d positionAt(rt::TimeNs t_ns) const;
    /// Their velocity at t_ns (W, m/s): the prediction's, held after its end, or the estimate's.
    Eigen::Vector3d velocityAt(rt::TimeNs t_ns) const;
    /// The other people tracked (the estimate's `others`, whatever the person's own state; null: none).
    const estimation::TargetEstimate* people = nullptr;
    std::size_t otherCount() const { return people == nullptr ? 0 : people->other_count; }
    /// Other person i's position at t_ns (W, m, at the sight height): constant velocity from the estimate's
    /// stamp for at most horizon_s, then held.
    Eigen::Vector3d otherAt(std::size_t i, rt::TimeNs t_ns) const;
  };

  // The stages of plan(), in order. Each allocates nothing once warm (the optimiser's L-BFGS history aside).

  /// Stage 1, prediction (paper Sect. V-A): with a live estimate, the predictor's Bezier QP fit of the
  /// recent estimates (kept for relocation), or constant velocity while it has too few of them; when
  /// relocating without one, the last prediction. Nothing when neither (the cycle fails: kNoTarget).
  /// The result points into `inputs` and into this planner: valid for this cycle only.
  std::optional<PersonMotion> predictPerson(const PlanInputs& inputs);
  /// Stage 2, goal selection (Sect. V-B): x_g mixed from the person's state at the hand-over (start_ns)
  /// and x_tp, held at the tracking distance and the flight altitude; in the proposed (occlusion-aware)
  /// mode moved round the person to where they are in sight. x_tp is taken at goalLeadS() after the
  /// hand-over, or earlier where the predicted path first enters an obstacle (people walk round walls and
  /// trees; a constant-velocity extrapolation does not).
  KinematicState selectGoal(const mapping::LocalGrid& grid, const PersonMotion& person, const StatePva& start,
                            rt::TimeNs start_ns) const;
  /// How long after the hand-over x_tp is taken: the prediction horizon, or with goal.max_lead_s > 0 the
  /// duration of the last complete path to a live person's goal (when the drone would get there), capped.
  double goalLeadS() const;
  /// Stage 3, occlusion-aware kinodynamic search (Sect. V-B) from the start (its velocity clipped to the
  /// search's per-axis limit) to the goal, checking sight lines to the person's path; the path in path_.
  /// Returns the search's status.
  SearchStatus searchTrackingPath(const mapping::LocalGrid& grid, const StatePva& start, rt::TimeNs start_ns,
                                  const KinematicState& goal, const PersonMotion& person);
  /// Stage 4, corridor (Sect. V-C): path_ cut into chords of about path_sample_step_s (polyline_, its first
  /// point exactly the start) and the overlapping free boxes along them (corridor_), or the builder's error.
  rt::Status buildCorridor(const mapping::LocalGrid& grid, const StatePva& start);
  /// Stage 5, optimisation (Sect. V-C): the minimum-jerk spline through corridor_ from `start` to the end
  /// of path_ (initial guess: the corridor's waypoints, timed as the path passes them), then a brake to
  /// rest appended (appendStop). The path's end velocity (a partial search's too) is kept if the drone can
  /// brake from it in free space, else lowered until it can (in steps of a fifth), else the end is at rest.
  /// The camera-view term sees the person's torso as samplePersonTorso last left it (none: no term).
  rt::Expected<OptimizerResult> optimizeTrajectory(const mapping::LocalGrid& grid, const StatePva& start,
                                                   PolynomialTrajectory& out);
  /// Stage 6, final check (issue 8 item 3): limits, inflated grid and FCL against the octree (when there is
  /// one), then never closer horizontally to the person's path than min_person_distance_m (or than it
  /// starts, if closer), nor to another person's than min_bystander_distance_m (kTooCloseToBystander),
  /// within check.horizon_s of start_ns.
  CheckResult checkPlannedTrajectory(const PolynomialTrajectory& trajectory, const mapping::LocalGrid& grid,
                                     const octomap::OcTree* octree, const PersonMotion& person,
                                     rt::TimeNs start_ns) const;
  /// Stage 6b, repair (issue 21): while the verdict is a dynamic limit (isDynamicLimit), re-time `out` from
  /// `start` by dynamicStretchFactor (retimeKeepingStart) and check again in full, at most kRepairAttempts
  /// times and up to check.max_repair_stretch in all. Returns the last verdict; the stretch in `stretch`.
  CheckResult repairPlannedTrajectory(CheckResult check, const StatePva& start, PolynomialTrajectory& out,
                                      const mapping::LocalGrid& grid, const octomap::OcTree* octree,
                                      const PersonMotion& person, rt::TimeNs start_ns, double& stretch);
  /// Stage 7, evasion (issue 21 items 2 and 5), on a failed cycle or at the goal: if braking to rest would let
  /// the live person's predicted path come within min_person_distance_m, or another person's within
  /// min_bystander_distance_m (horizontally, within check.horizon_s; keepAwayDistanceM), one minimum-jerk
  /// move to rest from `start` is written into `out` -- the brake itself, or a move of
  /// goal.tracking_distance_m in one of kEvasionDirections horizontal directions -- whichever keeps the
  /// largest keep-away distance (up to the tracking distance; ties: the shortest move) and passes the final
  /// check's limits, grid and FCL. False (out undefined) when no evasion is needed or none passes.
  bool evadePeople(const StatePva& start, const mapping::LocalGrid& grid, const octomap::OcTree* octree,
                   const PersonMotion& person, rt::TimeNs start_ns, PolynomialTrajectory& out);
  /// The start lies in the inflation margin (the search said start_blocked): writes into `out` one minimum-jerk
  /// move to rest at the nearest cell centre within kEscapeRadiusM that is unblocked, in the altitude band (or
  /// no farther from it than the start), and joined to the start by a segment through no raw-occupied cell,
  /// timed at the final check's limits; it must pass that check, with the margin left within the move.
  /// False (out undefined) when none of the kEscapeCandidates nearest passes. Why (issue 21): a bystander
  /// mapped beside a hovering drone, or a brake that ended in a margin, made every later search start blocked;
  /// the drone stopped for good (crossing seed 18: 30 s) while the person walked on.
  bool escapeMargin(const StatePva& start, const mapping::LocalGrid& grid, const octomap::OcTree* octree,
                    PolynomialTrajectory& out);
  /// The smallest horizontal distance (m) between `trajectory` (held at its end after it) and the live person's
  /// predicted path over check.horizon_s from start_ns, or another person's path less (min_bystander_distance_m -
  /// min_person_distance_m): one scale, on which min_person_distance_m is the limit for everyone.
  double keepAwayDistanceM(const PolynomialTrajectory& trajectory, const PersonMotion& person,
                           rt::TimeNs start_ns) const;
  /// A failed cycle: `status`, or kStopped with a stop written into `out` if the current trajectory is
  /// blocked ahead.
  PlanReport failCycle(PlanReport report, PlanStatus status, const PlanInputs& inputs, const StatePva& start,
                       PolynomialTrajectory& out);
  /// The polyline's chord count along path_ (at least 1); each chord lasts path_.duration_s / that.
  int chordCount() const;

  TrackingPlannerParams params_;
  KinodynamicSearch search_;
  CorridorBuilder corridor_builder_;
  TrajectoryOptimizer optimizer_;
  prediction::TargetPredictor predictor_;
  mapping::TrajectoryChecker checker_;
  rt::TimeNs last_target_stamp_ns_ = -1;
  SearchPath path_;
  std::vector<Eigen::Vector3d> polyline_;
  Corridor corridor_;
  std::vector<double> durations_s_;
  /// The live person's torso centre every kPersonSampleStepS from the hand-over, for the optimiser's
  /// camera-view term (empty when no live person: a relocation's search).
  std::vector<Eigen::Vector3d> person_torso_W_m_;
  void samplePersonTorso(const PersonMotion& person, rt::TimeNs start_ns);
  /// One minimum-jerk piece from `start` to rest at end_W_m in duration_s (the stop, take-off and land moves).
  void onePieceToRest(const StatePva& start, const Eigen::Vector3d& end_W_m, double duration_s,
                      PolynomialTrajectory& out);
  /// The same piece, generated into stop_spline_ only (false if the solve failed).
  bool pieceToRest(const StatePva& start, const Eigen::Vector3d& end_W_m, double duration_s);
  MinJerkSpline stop_spline_;
  MinJerkSpline repair_spline_;
  Eigen::VectorXd one_duration_;
  std::optional<prediction::TargetPrediction> last_prediction_;  ///< For relocation.
  estimation::TargetEstimate look_estimate_;                     ///< A search's look point, as a still person.
  double time_weight_scale_ = 1.0;                               ///< This cycle's timeWeightScale(), for the optimiser.
  double arrival_s_ = 0.0;            ///< The last complete search path's duration to a live person's goal (goalLeadS).
  bool search_goal_clipped_ = false;  ///< This cycle's goal lay beyond the grid's window (clipGoalToWindow).
};

}  // namespace aerotrack::planning
