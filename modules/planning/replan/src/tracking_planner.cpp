// One replanning cycle: see tracking_planner.hpp.
#include "aerotrack/planning/tracking_planner.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace aerotrack::planning {
namespace {

// The person's torso for the camera-view term: every 50 ms (a runner moves 0.3 m) for up to 8 s.
constexpr double kPersonSampleStepS = 0.05;
constexpr std::size_t kPersonSamples = 161;
// escapeMargin: a free point farther than this means the drone is boxed in, not grazing a margin (the
// inflation radius is 0.35 m; two margins facing each other across a gap leave a free cell within 0.8 m).
constexpr double kEscapeRadiusM = 1.0;
constexpr std::size_t kEscapeCandidates = 16;
constexpr int kEscapeRetimes = 4;

// A minimum-jerk piece from rest to rest over distance d peaks at 1.875 d / T in speed and 5.77 d / T^2 in
// acceleration: the shortest T (at least min_s) that keeps both within v_max and a_max.
double restToRestDurationS(double distance_m, double v_max, double a_max, double min_s) {
  return std::max({min_s, 1.875 * distance_m / v_max, std::sqrt(5.7735 * distance_m / a_max)});
}

}  // namespace

std::string_view toString(PlanStatus status) {
  switch (status) {
    case PlanStatus::kPlanned:
      return "planned";
    case PlanStatus::kStopped:
      return "stopped";
    case PlanStatus::kTakeOff:
      return "take_off";
    case PlanStatus::kAtGoal:
      return "at_goal";
    case PlanStatus::kRelocating:
      return "relocating";
    case PlanStatus::kNoOdometry:
      return "no_odometry";
    case PlanStatus::kNoMap:
      return "no_map";
    case PlanStatus::kNoTarget:
      return "no_target";
    case PlanStatus::kSearchFailed:
      return "search_failed";
    case PlanStatus::kCorridorFailed:
      return "corridor_failed";
    case PlanStatus::kOptimizerFailed:
      return "optimizer_failed";
    case PlanStatus::kCheckFailed:
      return "check_failed";
    case PlanStatus::kEvading:
      return "evading";
    case PlanStatus::kEscaping:
      return "escaping";
  }
  return "unknown";
}

rt::Expected<TrackingPlanner> TrackingPlanner::create(const TrackingPlannerParams& params_in) {
  if (const rt::Status s = validate(params_in); !s) return rt::Error{"planning: " + s.error().message};
  // One set of dynamic limits (issue 21): the check's are the vehicle's; the optimiser's soft-penalty targets
  // lie inside them by the stated fraction, so its output tends to pass and the two cannot drift apart.
  TrackingPlannerParams params = params_in;
  params.optimizer.max_velocity_mps = params.optimizer_limit_fraction * params.check.max_velocity_mps;
  params.optimizer.max_acceleration_mps2 = params.optimizer_limit_fraction * params.check.max_acceleration_mps2;
  params.optimizer.max_jerk_mps3 = params.optimizer_limit_fraction * params.check.max_jerk_mps3;
  auto search = KinodynamicSearch::create(params.search);
  if (!search) return rt::Error{"planning: search: " + search.error().message};
  auto corridor = CorridorBuilder::create(params.corridor);
  if (!corridor) return rt::Error{"planning: corridor: " + corridor.error().message};
  TrajectoryOptimizerParams optimizer_params = params.optimizer;
  optimizer_params.max_pieces = std::max(optimizer_params.max_pieces, params.corridor.max_boxes);
  auto optimizer = TrajectoryOptimizer::create(optimizer_params);
  if (!optimizer) return rt::Error{"planning: " + optimizer.error().message};
  auto predictor = prediction::TargetPredictor::create(params.prediction);
  if (!predictor) return rt::Error{"planning: prediction: " + predictor.error().message};
  auto checker = mapping::TrajectoryChecker::create(params.collision);
  if (!checker) return rt::Error{"planning: collision: " + checker.error().message};
  return TrackingPlanner(params, std::move(search.value()), std::move(corridor.value()), std::move(optimizer.value()),
                         std::move(predictor.value()), checker.value());
}

TrackingPlanner::TrackingPlanner(const TrackingPlannerParams& params, KinodynamicSearch search,
                                 CorridorBuilder corridor, TrajectoryOptimizer optimizer,
                                 prediction::TargetPredictor predictor, mapping::TrajectoryChecker checker)
    : params_(params),
      search_(std::move(search)),
      corridor_builder_(std::move(corridor)),
      optimizer_(std::move(optimizer)),
      predictor_(std::move(predictor)),
      checker_(checker) {
  search_.setAltitudeBand(params.min_altitude_m, params.max_altitude_m);
  corridor_builder_.setAltitudeBand(params.min_altitude_m, params.max_altitude_m);
  // The longest search path: every expansion adds a primitive, plus the one-shot.
  const double longest_s = params.search.primitive_duration_s * (params.search.max_expansions + 1) + 10.0;
  polyline_.reserve(static_cast<std::size_t>(std::min(longest_s / params.path_sample_step_s, 1e5)) + 2);
  const auto boxes = static_cast<std::size_t>(params.corridor.max_boxes);
  corridor_.boxes.reserve(boxes);
  corridor_.waypoints_W_m.reserve(boxes);
  corridor_.waypoint_path_index.reserve(boxes);
  durations_s_.reserve(boxes);
  person_torso_W_m_.reserve(kPersonSamples);
  stop_spline_.reset(StatePva::Zero(), StatePva::Zero(), 1);
  one_duration_.resize(1);
}

void TrackingPlanner::observeTarget(const estimation::TargetEstimate& estimate) {
  if (!estimate.initialised || estimate.lost) {
    if (estimate.initialised && estimate.lost) predictor_.reset();
    return;
  }
  if (estimate.stamp_ns <= last_target_stamp_ns_) return;
  last_target_stamp_ns_ = estimate.stamp_ns;
  predictor_.add(estimate.stamp_ns, estimate.p_WT_m, estimate.v_WT_mps);
}

StatePva TrackingPlanner::startState(const PlanInputs& inputs, rt::TimeNs start_ns) const {
  StatePva start = StatePva::Zero();
  start.col(0) = inputs.odometry->p_WB_m;
  start.col(1) = inputs.odometry->v_WB_mps;
  if (inputs.current == nullptr || !inputs.current->trajectory) return start;
  const trajectory_server::Trajectory& current = *inputs.current->trajectory;
  // How far the drone is from where the trajectory wants it now: too far (a gust, a failed tracking
  // controller, a trajectory from long ago) and continuing it would command a jump.
  const double now_s = rt::nsToSeconds(inputs.now_ns - inputs.current->start_ns);
  if ((current.sample(now_s).p_W_m - inputs.odometry->p_WB_m).norm() > params_.replan_reset_distance_m) return start;
  const double t_s = rt::nsToSeconds(start_ns - inputs.current->start_ns);
  const trajectory_server::TrajectorySample s = current.sample(t_s);
  start.col(0) = s.p_W_m;
  if (t_s <= current.durationS()) {  // after its end the server holds the end at rest
    start.col(1) = s.v_W_mps;
    start.col(2) = s.a_W_mps2;
  }
  return start;
}

bool TrackingPlanner::currentBlocked(const PlanInputs& inputs) const {
  if (inputs.current == nullptr || !inputs.current->trajectory) return false;
  const trajectory_server::Trajectory& current = *inputs.current->trajectory;
  const double t0 = rt::nsToSeconds(inputs.now_ns - inputs.current->start_ns);
  if (t0 >= current.durationS()) return false;  // already holding at rest
  const double t1 = std::min(current.durationS(), t0 + params_.stop_check_horizon_s);
  MarginWalk margin(params_.check.margin_escape_s);
  for (double t = t0; t <= t1; t += params_.check.sample_step_s) {
    if (margin.blocked(t - t0, inputs.grid->isOccupied(current.sample(t).p_W_m))) return true;
  }
  return false;
}

void TrackingPlanner::makeMoveTrajectory(const StatePva& start, const Eigen::Vector3d& end_W_m,
                                         PolynomialTrajectory& out) {
  // At half the optimiser's limits (a gentle manoeuvre).
  const double distance_m = (end_W_m - start.col(0)).norm();
  const double v_max = 0.5 * params_.optimizer.max_velocity_mps;
  const double a_max = 0.5 * params_.optimizer.max_acceleration_mps2;
  const double duration_s = restToRestDurationS(distance_m, v_max, a_max, 0.5);
  onePieceToRest(start, end_W_m, duration_s, out);
}

bool TrackingPlanner::pieceToRest(const StatePva& start, const Eigen::Vector3d& end_W_m, double duration_s) {
  StatePva end = StatePva::Zero();
  end.col(0) = end_W_m;
  stop_spline_.reset(start, end, 1);
  one_duration_(0) = duration_s;
  const Eigen::Matrix3Xd no_waypoints(3, 0);
  return stop_spline_.generate(no_waypoints, one_duration_);
}

void TrackingPlanner::onePieceToRest(const StatePva& start, const Eigen::Vector3d& end_W_m, double duration_s,
                                     PolynomialTrajectory& out) {
  if (pieceToRest(start, end_W_m, duration_s)) out.assign(stop_spline_);
}

namespace {

// The predicted path is checked for obstacles at this many points up to the goal's lead (every 0.1 s at 3 s).
constexpr int kGoalLeadSteps = 30;

// Below this speed (m/s) and acceleration (m/s^2) a trajectory's end is at rest: no brake is appended.
constexpr double kAtRest = 1e-3;

// Constant deceleration a_max / 2 from speed v stops in 2 v / a_max seconds over v^2 / a_max metres;
// the minimum-jerk piece with that duration and end point stays within the limit (its peak deceleration
// is about 1.9 times the mean, and the mean is a_max / 2).
double stopDurationS(double speed_mps, double max_acceleration_mps2) {
  return std::max(0.5, 2.0 * speed_mps / max_acceleration_mps2);
}

}  // namespace

void TrackingPlanner::makeStopTrajectory(const StatePva& start, PolynomialTrajectory& out) {
  const double duration_s = stopDurationS(start.col(1).norm(), params_.optimizer.max_acceleration_mps2);
  onePieceToRest(start, start.col(0) + start.col(1) * (duration_s / 2.0), duration_s, out);
}

void TrackingPlanner::appendStop(PolynomialTrajectory& out) {
  const double end_s = out.durationS();
  const trajectory_server::TrajectorySample end = out.sample(end_s);
  if (end.v_W_mps.norm() < kAtRest && end.a_W_mps2.norm() < kAtRest) return;
  StatePva start;
  start << end.p_W_m, end.v_W_mps, end.a_W_mps2;
  const double duration_s = stopDurationS(end.v_W_mps.norm(), params_.optimizer.max_acceleration_mps2);
  if (pieceToRest(start, end.p_W_m + end.v_W_mps * (duration_s / 2.0), duration_s)) {
    out.append(stop_spline_.coefficients().topRows<6>(), duration_s);
  }
}

PlanReport TrackingPlanner::plan(const PlanInputs& inputs, PolynomialTrajectory& out) {
  PlanReport report;
  if (inputs.odometry == nullptr) return report;
  const rt::TimeNs start_ns = inputs.now_ns + rt::secondsToNs(params_.planning_budget_s);
  report.start_ns = start_ns;
  const StatePva start = startState(inputs, start_ns);

  // Take-off: on (or near) the ground the start lies in the floor's inflation margin, where no search can
  // begin; climb straight up to the flight altitude first. It needs no map (a vertical climb from where
  // the drone stands), so the drone does not wait on the ground for the first depth images. (The
  // supervisor of issue 9 owns take-off and landing as modes; this keeps the planner usable on its own.)
  if (start(2, 0) < params_.takeoff_below_m) {
    makeMoveTrajectory(start, Eigen::Vector3d(start(0, 0), start(1, 0), params_.flight_altitude_m), out);
    report.status = PlanStatus::kTakeOff;
    return report;
  }
  if (inputs.grid == nullptr) {
    report.status = PlanStatus::kNoMap;
    return report;
  }
  const mapping::LocalGrid& grid = *inputs.grid;
  auto fail = [&](PlanStatus status) { return failCycle(report, status, inputs, start, out); };

  const std::optional<PersonMotion> person = predictPerson(inputs);  // 1. Sect. V-A
  if (!person) return fail(PlanStatus::kNoTarget);
  report.predicted = person->prediction != nullptr;
  // From here a failed cycle first asks whether someone is about to walk into a braking drone (7.).
  auto fail_or_evade = [&](PlanStatus status) {
    if (evadePeople(start, grid, inputs.octree, *person, start_ns, out)) {
      report.status = PlanStatus::kEvading;
      return report;
    }
    return fail(status);
  };

  KinematicState goal = selectGoal(grid, *person, start, start_ns);  // 2. Sect. V-B
  // A relocation's search (issue 21 item 3): to the viewpoint, to rest.
  if (inputs.look != nullptr && !person->live) {
    goal.p_W_m = inputs.look->p_W_m;
    goal.v_W_mps.setZero();
  }
  time_weight_scale_ =
      timeWeightScale(person->velocityAt(start_ns).head<2>().norm(), (goal.v_W_mps - start.col(1)).head<2>().norm());
  report.search_status = searchTrackingPath(grid, start, start_ns, goal, *person);  // 3. Sect. V-B
  report.search_expansions = path_.expansions;
  if (person->live && path_.status == SearchStatus::kReachedGoal && !search_goal_clipped_)
    arrival_s_ = path_.duration_s;
  // Only a start in a margin is escaped (searchTrackingPath clamps the start's velocity into the search's limits,
  // the other reason for start_blocked; a start outside the window has nowhere known to go).
  if (path_.status == SearchStatus::kStartBlocked && grid.inWindow(start.col(0)) && grid.isOccupied(start.col(0)) &&
      escapeMargin(start, grid, inputs.octree, out)) {
    report.status = PlanStatus::kEscaping;
    return report;
  }
  if (path_.status != SearchStatus::kReachedGoal && path_.status != SearchStatus::kPartial)
    return fail_or_evade(PlanStatus::kSearchFailed);
  if (path_.duration_s <= params_.min_piece_duration_s) {
    // Nothing to fly: the current trajectory (or its hold) stands -- unless someone walks into it (7.).
    report.status =
        evadePeople(start, grid, inputs.octree, *person, start_ns, out) ? PlanStatus::kEvading : PlanStatus::kAtGoal;
    return report;
  }

  if (!buildCorridor(grid, start)) return fail_or_evade(PlanStatus::kCorridorFailed);  // 4. Sect. V-C
  report.corridor_boxes = static_cast<int>(corridor_.boxes.size());

  person_torso_W_m_.clear();  // only the camera-view term reads the samples: none when it is off
  if (params_.optimizer.camera_view_weight > 0.0) samplePersonTorso(*person, start_ns);
  const auto optimized = optimizeTrajectory(grid, start, out);  // 5. Sect. V-C
  if (!optimized) return fail_or_evade(PlanStatus::kOptimizerFailed);
  report.optimizer_status = optimized->status;
  report.optimizer_iterations = optimized->iterations;

  CheckResult check = checkPlannedTrajectory(out, grid, inputs.octree, *person, start_ns);  // 6.
  report.first_check = check.verdict;
  if (isDynamicLimit(check.verdict))
    check = repairPlannedTrajectory(check, start, out, grid, inputs.octree, *person, start_ns, report.repair_stretch);
  report.check = check.verdict;
  if (report.check != CheckVerdict::kOk) return fail_or_evade(PlanStatus::kCheckFailed);
  report.status = person->live ? PlanStatus::kPlanned : PlanStatus::kRelocating;
  return report;
}

double TrackingPlanner::keepAwayDistanceM(const PolynomialTrajectory& trajectory, const PersonMotion& person,
                                          rt::TimeNs start_ns) const {
  const bool the_person = person.live && person.keep_away && params_.min_person_distance_m > 0.0;
  const std::size_t others = params_.min_bystander_distance_m > 0.0 ? person.otherCount() : 0;
  const double other_offset_m = params_.min_person_distance_m - params_.min_bystander_distance_m;
  double min_m = std::numeric_limits<double>::infinity();
  for (double t = 0.0; t <= params_.check.horizon_s; t += params_.check.sample_step_s) {
    const rt::TimeNs t_ns = start_ns + rt::secondsToNs(t);
    const Eigen::Vector2d p = trajectory.sample(t).p_W_m.head<2>();
    if (the_person) min_m = std::min(min_m, (p - person.positionAt(t_ns).head<2>()).norm());
    for (std::size_t i = 0; i < others; ++i)
      min_m = std::min(min_m, (p - person.otherAt(i, t_ns).head<2>()).norm() + other_offset_m);
  }
  return min_m;
}

bool TrackingPlanner::evadePeople(const StatePva& start, const mapping::LocalGrid& grid, const octomap::OcTree* octree,
                                  const PersonMotion& person, rt::TimeNs start_ns, PolynomialTrajectory& out) {
  const bool the_person = person.live && person.keep_away && params_.min_person_distance_m > 0.0;
  const bool others = params_.min_bystander_distance_m > 0.0 && person.otherCount() > 0;
  if (!the_person && !others) return false;
  // Candidate 0 is the brake to rest; its distance decides whether evading is needed at all.
  const double brake_s = stopDurationS(start.col(1).norm(), params_.optimizer.max_acceleration_mps2);
  const Eigen::Vector3d brake_end_W_m = start.col(0) + start.col(1) * (brake_s / 2.0);
  if (!pieceToRest(start, brake_end_W_m, brake_s)) return false;
  out.assign(stop_spline_);
  if (keepAwayDistanceM(out, person, start_ns) >= params_.min_person_distance_m) return false;

  // Each candidate: a move of d metres (the tracking distance, where the goal would be held) to rest,
  // timed as makeMoveTrajectory at the optimiser's full limits, then slowed by the stretch its dynamic peaks
  // need (the start velocity, often towards the person, adds to them). Score: the minimum distance to the
  // person, capped at the tracking distance (beyond it, farther is no better); ties go to the shorter move.
  const double d_m = std::max(params_.goal.tracking_distance_m, params_.min_person_distance_m);
  const double v_max = params_.optimizer.max_velocity_mps;
  const double a_max = params_.optimizer.max_acceleration_mps2;
  const double move_s = restToRestDurationS(d_m, v_max, a_max, 0.5);
  struct Candidate {
    Eigen::Vector3d end_W_m;
    double duration_s = 0.0;
    double score_m = -1.0;
  };
  std::array<Candidate, kEvasionDirections + 1> candidates;
  candidates[0] = {brake_end_W_m, brake_s, std::min(keepAwayDistanceM(out, person, start_ns), d_m)};
  for (int k = 0; k < kEvasionDirections; ++k) {
    const double angle_rad = 2.0 * M_PI * k / kEvasionDirections;
    Candidate& c = candidates[static_cast<std::size_t>(k) + 1];
    c.end_W_m = start.col(0) + d_m * Eigen::Vector3d(std::cos(angle_rad), std::sin(angle_rad), 0.0);
    c.duration_s = move_s;
    if (grid.isOccupied(c.end_W_m)) continue;  // score stays -1: never chosen
    if (!pieceToRest(start, c.end_W_m, c.duration_s)) continue;
    out.assign(stop_spline_);
    c.duration_s *= dynamicStretchFactor(out, params_.check);
    if (!pieceToRest(start, c.end_W_m, c.duration_s)) continue;
    out.assign(stop_spline_);
    c.score_m = std::min(keepAwayDistanceM(out, person, start_ns), d_m);
  }
  // Best first; then the full check, until one passes.
  std::array<int, kEvasionDirections + 1> order{};
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  // Scores within kTieM of each other are equal (whole steps of it, so the order is a strict weak one): among
  // them the brake (the shortest move) wins, then the directions in order.
  constexpr double kTieM = 0.05;
  auto step_of = [&](int i) { return std::floor(candidates[static_cast<std::size_t>(i)].score_m / kTieM); };
  for (std::size_t i = 1; i < order.size(); ++i) {  // insertion sort: stable, and no buffer to allocate
    for (std::size_t j = i; j > 0 && step_of(order[j]) > step_of(order[j - 1]); --j) std::swap(order[j], order[j - 1]);
  }
  for (const int i : order) {
    const Candidate& c = candidates[static_cast<std::size_t>(i)];
    if (c.score_m < 0.0) break;
    if (!pieceToRest(start, c.end_W_m, c.duration_s)) continue;
    out.assign(stop_spline_);
    if (checkTrajectory(out, params_.check, grid, checker_, octree).verdict == CheckVerdict::kOk) return true;
  }
  return false;
}

bool TrackingPlanner::escapeMargin(const StatePva& start, const mapping::LocalGrid& grid, const octomap::OcTree* octree,
                                   PolynomialTrajectory& out) {
  const Eigen::Vector3d p0 = start.col(0);
  const double resolution_m = grid.params().resolution_m;
  const int reach = static_cast<int>(std::ceil(kEscapeRadiusM / resolution_m));
  const mapping::CellIndex centre = (p0 / resolution_m).array().floor().cast<int>();
  const double min_z_m = std::min(params_.min_altitude_m, p0.z());
  const double max_z_m = std::max(params_.max_altitude_m, p0.z());
  // The kEscapeCandidates nearest unblocked cell centres, nearest first (a fixed buffer: no allocation).
  struct Candidate {
    Eigen::Vector3d p_W_m;
    double distance_m;
  };
  std::array<Candidate, kEscapeCandidates> best{};
  std::size_t found = 0;
  for (int dz = -reach; dz <= reach; ++dz) {
    for (int dy = -reach; dy <= reach; ++dy) {
      for (int dx = -reach; dx <= reach; ++dx) {
        const Eigen::Vector3d c =
            ((centre + mapping::CellIndex(dx, dy, dz)).cast<double>().array() + 0.5) * resolution_m;
        const double d = (c - p0).norm();
        if (d > kEscapeRadiusM || c.z() < min_z_m || c.z() > max_z_m) continue;
        if (found == best.size() && d >= best.back().distance_m) continue;
        if (!grid.inWindow(c) || grid.isOccupied(c)) continue;
        std::size_t i = std::min(found, best.size() - 1);
        for (; i > 0 && best[i - 1].distance_m > d; --i) best[i] = best[i - 1];
        best[i] = {c, d};
        found = std::min(found + 1, best.size());
      }
    }
  }
  // Timed as makeMoveTrajectory at the check's full limits, then stretched to them; the check may find the
  // start in the margin for the whole move (it is what the move leaves), never a raw obstacle on the way.
  TrajectoryCheckParams check = params_.check;
  const double v_max = params_.check.max_velocity_mps;
  const double a_max = params_.check.max_acceleration_mps2;
  for (std::size_t i = 0; i < found; ++i) {
    const Eigen::Vector3d& end_W_m = best[i].p_W_m;
    if (!grid.lineOfSight(p0, end_W_m)) continue;
    const double d = best[i].distance_m;
    // Stretched until within the limits (a start still braking makes the peaks shrink slower than 1/k).
    double duration_s = restToRestDurationS(d, v_max, a_max, 0.3);
    for (int attempt = 0; attempt < kEscapeRetimes; ++attempt) {
      if (!pieceToRest(start, end_W_m, duration_s)) break;
      out.assign(stop_spline_);
      check.margin_escape_s = std::max(params_.check.margin_escape_s, duration_s);
      const CheckResult result = checkTrajectory(out, check, grid, checker_, octree);
      if (result.verdict == CheckVerdict::kOk) return true;
      if (!isDynamicLimit(result.verdict)) break;
      duration_s *= std::max(1.1, dynamicStretchFactor(out, params_.check));
    }
  }
  return false;
}

PlanReport TrackingPlanner::failCycle(PlanReport report, PlanStatus status, const PlanInputs& inputs,
                                      const StatePva& start, PolynomialTrajectory& out) {
  report.status = status;
  if (currentBlocked(inputs)) {
    makeStopTrajectory(start, out);
    report.status = PlanStatus::kStopped;
  }
  return report;
}

Eigen::Vector3d TrackingPlanner::PersonMotion::positionAt(rt::TimeNs t_ns) const {
  Eigen::Vector3d p;
  if (prediction != nullptr) {
    const rt::TimeNs end_ns = prediction->end_ns;
    p = t_ns <= end_ns ? prediction->position(t_ns)
                       : Eigen::Vector3d(prediction->position(end_ns) +
                                         rt::nsToSeconds(t_ns - end_ns) * prediction->velocity(end_ns));
  } else {
    const double ahead_s = std::min(rt::nsToSeconds(t_ns - estimate->stamp_ns), horizon_s);
    p = estimate->p_WT_m + ahead_s * estimate->v_WT_mps;
  }
  p.z() = sight_height_m;
  return p;
}

Eigen::Vector3d TrackingPlanner::PersonMotion::otherAt(std::size_t i, rt::TimeNs t_ns) const {
  const estimation::OtherPerson& other = people->others[i];
  const double ahead_s = std::clamp(rt::nsToSeconds(t_ns - people->stamp_ns), 0.0, horizon_s);
  Eigen::Vector3d p = other.p_W_m + ahead_s * other.v_W_mps;
  p.z() = sight_height_m;
  return p;
}

Eigen::Vector3d TrackingPlanner::PersonMotion::velocityAt(rt::TimeNs t_ns) const {
  if (prediction != nullptr) return prediction->velocity(std::min(t_ns, prediction->end_ns));
  return estimate->v_WT_mps;
}

std::optional<TrackingPlanner::PersonMotion> TrackingPlanner::predictPerson(const PlanInputs& inputs) {
  PersonMotion person;
  person.estimate = inputs.target;
  person.people = inputs.target;
  person.live = inputs.target != nullptr && inputs.target->initialised && !inputs.target->lost;
  person.horizon_s = params_.prediction.horizon_s;
  person.sight_height_m = params_.person_sight_height_m;
  if (person.live) {
    // The Bezier prediction, or constant velocity until the predictor has enough estimates.
    if (auto predicted = predictor_.predict(inputs.now_ns)) {
      last_prediction_ = *predicted;
      person.prediction = &*last_prediction_;
    }
  } else if (inputs.look != nullptr) {  // a relocation's search: the look point, as a person standing still
    look_estimate_.stamp_ns = inputs.now_ns;
    look_estimate_.initialised = true;
    look_estimate_.p_WT_m = inputs.look->look_W_m;
    look_estimate_.v_WT_mps.setZero();
    person.estimate = &look_estimate_;
    person.keep_away = false;
  } else if (inputs.relocate && last_prediction_) {
    person.prediction = &*last_prediction_;  // relocation: the last predicted path
  } else {
    return std::nullopt;
  }
  return person;
}

KinematicState TrackingPlanner::selectGoal(const mapping::LocalGrid& grid, const PersonMotion& person,
                                           const StatePva& start, rt::TimeNs start_ns) const {
  KinematicState person_now;
  person_now.p_W_m = person.positionAt(start_ns);
  person_now.v_W_mps = person.velocityAt(start_ns);
  // The predicted path up to `limit_s` after the hand-over, or to its last sample before it enters an obstacle.
  const auto free_until_s = [&](double limit_s) {
    double free_s = 0.0;
    for (int k = 1; k <= kGoalLeadSteps; ++k) {
      const double t_s = limit_s * k / kGoalLeadSteps;
      if (grid.isOccupied(person.positionAt(start_ns + rt::secondsToNs(t_s)))) break;
      free_s = t_s;
    }
    return free_s;
  };
  const rt::TimeNs predicted_ns = start_ns + rt::secondsToNs(free_until_s(goalLeadS()));  // x_tp
  KinematicState person_predicted;
  person_predicted.p_W_m = person.positionAt(predicted_ns);
  person_predicted.v_W_mps = person.velocityAt(predicted_ns);
  // The goal is held at the flight altitude (makeTrackingGoal keeps the height of the point it is given).
  const Eigen::Vector3d p_drone_at_altitude(start(0, 0), start(1, 0), params_.flight_altitude_m);
  // Proposed mode: a goal that sees the person, now and at the prediction horizon (the baseline, Fast-Tracker
  // 1.0, has no visibility terms).
  if (!search_.occlusionAware())
    return makeTrackingGoal(person_now, person_predicted, p_drone_at_altitude, params_.goal);
  const rt::TimeNs ahead_ns = start_ns + rt::secondsToNs(free_until_s(params_.prediction.horizon_s));
  const Eigen::Vector3d p_ahead_W_m = person.positionAt(ahead_ns);
  // The others where they stand now and where they walk by the horizon (PersonMotion::otherAt).
  std::array<Eigen::Vector2d, estimation::kMaxOtherPeople> others_now;
  std::array<Eigen::Vector2d, estimation::kMaxOtherPeople> others_ahead;
  const std::size_t others =
      params_.bystander_sight_radius_m > 0.0 ? std::min(person.otherCount(), others_now.size()) : 0;
  for (std::size_t i = 0; i < others; ++i) {
    others_now[i] = person.otherAt(i, start_ns).head<2>();
    others_ahead[i] = person.otherAt(i, ahead_ns).head<2>();
  }
  const SightBlockers blockers{std::span<const Eigen::Vector2d>(others_now.data(), others),
                               std::span<const Eigen::Vector2d>(others_ahead.data(), others),
                               params_.bystander_sight_radius_m};
  return makeVisibleTrackingGoal(grid, person_now, person_predicted, p_drone_at_altitude, params_.goal, &p_ahead_W_m,
                                 blockers);
}

double TrackingPlanner::timeWeightScale(double person_speed_mps, double speed_change_mps) const {
  const double ratio = person_speed_mps / params_.time_weight_reference_speed_mps;
  double scale = ratio * ratio;
  if (params_.time_weight_reference_speed_change_mps > 0.0) {
    const double change_ratio = speed_change_mps / params_.time_weight_reference_speed_change_mps;
    scale = std::max(scale, change_ratio * change_ratio);
  }
  return std::clamp(scale, 1.0, params_.max_time_weight_scale);
}

double TrackingPlanner::goalLeadS() const {
  if (!(params_.goal.max_lead_s > 0.0)) return params_.prediction.horizon_s;
  return std::clamp(arrival_s_, 0.0, params_.goal.max_lead_s);
}

SearchStatus TrackingPlanner::searchTrackingPath(const mapping::LocalGrid& grid, const StatePva& start,
                                                 rt::TimeNs start_ns, const KinematicState& goal,
                                                 const PersonMotion& person) {
  // The search's inputs are per-axis limited: the optimised start may exceed them slightly.
  KinematicState search_start;
  search_start.p_W_m = start.col(0);
  const double v_axis = params_.search.max_velocity_mps;
  search_start.v_W_mps = start.col(1).cwiseMax(-v_axis).cwiseMin(v_axis);
  const double start_time_s = rt::nsToSeconds(start_ns);
  // One reference captured: small enough for std::function to keep inline (no allocation).
  const PersonPositionFn person_fn = [&person](double t_s) { return person.positionAt(rt::secondsToNs(t_s)); };
  // A goal beyond the grid's window is searched for at the window's edge (clipGoalToWindow), with room for a
  // primitive at full speed inside it; its path is not a complete one (arrival_s_ stays).
  KinematicState search_goal = goal;
  const double margin_m = params_.search.primitive_duration_s * params_.search.max_velocity_mps;
  search_goal_clipped_ = clipGoalToWindow(grid, search_start.p_W_m, margin_m, search_goal);
  // The other people, as the final check predicts them (PersonMotion::otherAt), from the search's start.
  std::array<MovingPerson, kMaxSearchPeople> people{};
  std::size_t people_count = 0;
  const bool keep_clear = params_.min_bystander_distance_m > 0.0;
  if ((keep_clear || params_.bystander_sight_radius_m > 0.0) && person.otherCount() > 0) {
    const double since_s = rt::nsToSeconds(start_ns - person.people->stamp_ns);
    for (std::size_t i = 0; i < person.otherCount() && people_count < people.size(); ++i) {
      people[people_count++] = {person.otherAt(i, start_ns).head<2>(), person.people->others[i].v_W_mps.head<2>(),
                                std::max(0.0, person.horizon_s - since_s)};
    }
  }
  // One grid cell wider than the check keeps them, as the map's inflation is one cell wider than the drone: the
  // optimised trajectory leaves the path by a few centimetres, and at the check's own distance half of the plans
  // past someone failed by that much (crowd seed 14: 0.75-0.80 m against 0.8 m).
  search_.setPeople(std::span<const MovingPerson>(people.data(), people_count),
                    keep_clear ? params_.min_bystander_distance_m + grid.params().resolution_m : 0.0,
                    params_.bystander_sight_radius_m);
  return search_.search(grid, search_start, search_goal, start_time_s, person_fn, path_);
}

int TrackingPlanner::chordCount() const {
  return std::max(1, static_cast<int>(std::ceil(path_.duration_s / params_.path_sample_step_s)));
}

rt::Status TrackingPlanner::buildCorridor(const mapping::LocalGrid& grid, const StatePva& start) {
  polyline_.clear();
  const int steps = chordCount();
  const double dt_s = path_.duration_s / steps;
  for (int k = 0; k <= steps; ++k) polyline_.push_back(path_.stateAt(k * dt_s).p_W_m);
  polyline_.front() = start.col(0);
  return corridor_builder_.build(grid, polyline_, corridor_);
}

void TrackingPlanner::samplePersonTorso(const PersonMotion& person, rt::TimeNs start_ns) {
  person_torso_W_m_.clear();
  if (!person.live) return;
  // Past the path's duration twice over (the optimiser may slow down), at least a second: held beyond.
  const double horizon_s = std::clamp(2.0 * path_.duration_s, 1.0, kPersonSampleStepS * (kPersonSamples - 1));
  const auto samples = static_cast<std::size_t>(std::ceil(horizon_s / kPersonSampleStepS)) + 1;
  for (std::size_t k = 0; k < samples && k < kPersonSamples; ++k) {
    const double t_s = kPersonSampleStepS * static_cast<double>(k);
    person_torso_W_m_.push_back(person.positionAt(start_ns + rt::secondsToNs(t_s)));  // z: the sight height
  }
}

rt::Expected<OptimizerResult> TrackingPlanner::optimizeTrajectory(const mapping::LocalGrid& grid, const StatePva& start,
                                                                  PolynomialTrajectory& out) {
  // Initial guess: the waypoints the corridor chose, timed as the search path passes them.
  const double dt_s = path_.duration_s / chordCount();
  durations_s_.clear();
  double previous_s = 0.0;
  for (const int index : corridor_.waypoint_path_index) {
    const double t_s = index * dt_s;
    durations_s_.push_back(std::max(params_.min_piece_duration_s, t_s - previous_s));
    previous_s = std::max(previous_s, t_s);
  }
  durations_s_.push_back(std::max(params_.min_piece_duration_s, path_.duration_s - previous_s));

  StatePva end = StatePva::Zero();
  const KinematicState path_end = path_.stateAt(path_.duration_s);
  end.col(0) = path_end.p_W_m;
  // The path ends with its own velocity: a complete path at the goal with the person's velocity, a partial
  // one (the search's budget ran out) where it got closest to the goal, as fast as it was going there (issue
  // 21: ending those at rest made each plan a hop of a few metres to a stop, and a drone more than a search's
  // reach behind a runner fell further behind: forest at 4 m/s, mean distance 5.6 m against 5.1 m, 10 seeds).
  // Either way the drone must be able to brake from there (appendStop below: straight on over v T / 2)
  // without entering the inflated grid; the final check then proves the brake clear in full.
  end.col(1) = path_end.v_W_mps;
  if (end.col(1).norm() > params_.optimizer.max_velocity_mps)
    end.col(1) *= params_.optimizer.max_velocity_mps / end.col(1).norm();
  // A blocked brake lowers the end speed until the brake fits (its length falls with the square of the
  // speed), and only then to rest: a goal beside a wall whose velocity points into it, as at a corner the
  // person turned, or a tree within a runner's brake, which is common in a forest.
  const Eigen::Vector3d end_velocity = end.col(1);
  constexpr std::array<double, 5> kEndSpeedScales = {1.0, 0.8, 0.6, 0.4, 0.2};
  bool brake_free = false;
  for (const double scale : kEndSpeedScales) {
    end.col(1) = scale * end_velocity;
    const double brake_s = stopDurationS(end.col(1).norm(), params_.optimizer.max_acceleration_mps2);
    brake_free = grid.segmentFree(end.col(0), end.col(0) + end.col(1) * (brake_s / 2.0));
    if (brake_free) break;
  }
  if (!brake_free) end.col(1).setZero();
  TrajectoryProblem problem{start, end, corridor_.boxes, corridor_.waypoints_W_m, durations_s_};
  problem.time_weight_scale = time_weight_scale_;
  problem.person_torso_W_m = person_torso_W_m_;
  problem.person_sample_dt_s = kPersonSampleStepS;
  problem.person_torso_half_m = params_.person_torso_half_m;
  auto optimized = optimizer_.optimize(problem, out);
  if (!optimized) return optimized;

  // Every published trajectory ends at rest: the optimised part ends moving (towards the goal, or where a
  // partial search stopped), and the server holds a finished trajectory's end point. Without the brake
  // the drone would overshoot that point, into whatever lies beyond it, if no later plan took over (a
  // relocation flew into a wall that way). With it, the final check proves the brake clear too: the
  // drone can always stop on the trajectory it flies.
  appendStop(out);
  return optimized;
}

// Repairs are rare (1.7 % of the checks on sharp_turn at 3 m/s, 10 seeds) and each costs a spline solve and a full
// check: three attempts cover a stretch computed on a re-timed spline that, unlike a pure stretch, keeps the start.
constexpr int kRepairAttempts = 3;

CheckResult TrackingPlanner::repairPlannedTrajectory(CheckResult check, const StatePva& start,
                                                     PolynomialTrajectory& out, const mapping::LocalGrid& grid,
                                                     const octomap::OcTree* octree, const PersonMotion& person,
                                                     rt::TimeNs start_ns, double& stretch) {
  // The optimiser's penalties are soft (paper Sect. V-C), so its output may exceed the limits it aimed at.
  // The same path flown slower is within them (a pure stretch by k divides v, a, j by k, k^2, k^3), and
  // stays in the corridor it was optimised in; re-timing from the unchanged start state keeps the hand-over
  // smooth, at the price of small changes to the path between junctions: hence the full re-check.
  stretch = 1.0;
  for (int attempt = 0; attempt < kRepairAttempts && isDynamicLimit(check.verdict); ++attempt) {
    // At least the tolerance's worth more each time, so a re-timing that barely helped still progresses.
    const double k = std::max(dynamicStretchFactor(out, params_.check), 1.0 + params_.check.tolerance);
    if (stretch * k > params_.check.max_repair_stretch) break;
    if (!retimeKeepingStart(out, start, k, repair_spline_, out)) break;
    stretch *= k;
    check = checkPlannedTrajectory(out, grid, octree, person, start_ns);
  }
  return check;
}

CheckResult TrackingPlanner::checkPlannedTrajectory(const PolynomialTrajectory& trajectory,
                                                    const mapping::LocalGrid& grid, const octomap::OcTree* octree,
                                                    const PersonMotion& person, rt::TimeNs start_ns) const {
  CheckResult check = checkTrajectory(trajectory, params_.check, grid, checker_, octree);
  if (check.verdict != CheckVerdict::kOk) return check;
  const double end_s = std::min(trajectory.durationS(), params_.check.horizon_s);
  // Never closer than min_distance_m to `path`, or than at the start if closer already (they came near).
  auto keeps_away = [&](auto path, double min_distance_m) {
    auto distance_at = [&](double t_s) {
      const Eigen::Vector3d d = trajectory.sample(t_s).p_W_m - path(start_ns + rt::secondsToNs(t_s));
      return d.head<2>().norm();
    };
    const double limit_m = std::min(min_distance_m, distance_at(0.0)) - 1e-6;
    for (double t = 0.0; t <= end_s; t += params_.check.sample_step_s) {
      if (distance_at(t) < limit_m) return std::optional<double>(t);
    }
    return std::optional<double>();
  };
  if (params_.min_person_distance_m > 0.0 && person.keep_away) {
    const auto at = keeps_away([&](rt::TimeNs t_ns) { return person.positionAt(t_ns); }, params_.min_person_distance_m);
    if (at) return {CheckVerdict::kTooCloseToPerson, *at};
  }
  if (!(params_.min_bystander_distance_m > 0.0)) return check;
  for (std::size_t i = 0; i < person.otherCount(); ++i) {
    const auto at =
        keeps_away([&](rt::TimeNs t_ns) { return person.otherAt(i, t_ns); }, params_.min_bystander_distance_m);
    if (at) return {CheckVerdict::kTooCloseToBystander, *at};
  }
  return check;
}

}  // namespace aerotrack::planning
