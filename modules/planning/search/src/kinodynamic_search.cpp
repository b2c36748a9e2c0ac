// Occlusion-aware kinodynamic hybrid A* (see kinodynamic_search.hpp; paper Sect. V-B).
#include "aerotrack/planning/kinodynamic_search.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include <Eigen/Geometry>

#include "aerotrack/planning/obvp.hpp"

namespace aerotrack::planning {
namespace {

bool finite(const Eigen::Vector3d& x) {
  return x.allFinite();
}

bool withinLimits(const Eigen::Vector3d& v, double limit) {
  return v.cwiseAbs().maxCoeff() <= limit + 1e-9;
}

Eigen::Vector3d positionOf(const PathSegment& s, double t) {
  return s.p0_W_m + t * (s.v0_W_mps + t * (0.5 * s.a0_W_mps2 + (t / 6.0) * s.jerk_W_mps3));
}

// A path is checked as a polyline of chords, each traced through the grid by DDA (every cell it passes
// through). A piece of duration dt whose acceleration stays below a strays from its chord by at most
// a dt^2 / 8; the chords are made short enough to keep that below kChordDeviationM.
constexpr double kChordDeviationM = 0.001;

int chordCount(double max_acceleration_mps2, double duration_s) {
  if (max_acceleration_mps2 <= 0.0) return 1;
  const double max_dt_s = std::sqrt(8.0 * kChordDeviationM / max_acceleration_mps2);
  return std::max(1, static_cast<int>(std::ceil(duration_s / max_dt_s)));
}

bool pointFree(const mapping::LocalGrid& grid, const Eigen::Vector3d& p) {
  return grid.inWindow(p) && !grid.isOccupied(p);
}

// Every cell the chord passes through (DDA) is unblocked and in the window.
bool chordFree(const mapping::LocalGrid& grid, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return pointFree(grid, b) && grid.segmentFree(a, b);
}

}  // namespace

std::string_view toString(SearchStatus status) {
  switch (status) {
    case SearchStatus::kReachedGoal:
      return "reached_goal";
    case SearchStatus::kPartial:
      return "partial";
    case SearchStatus::kNoPath:
      return "no_path";
    case SearchStatus::kStartBlocked:
      return "start_blocked";
    case SearchStatus::kInvalidInput:
      return "invalid_input";
  }
  return "unknown";
}

const rt::FieldTable<KinodynamicSearchParams>& kinodynamicSearchFields() {
  using P = KinodynamicSearchParams;
  using rt::Range;
  static const rt::FieldTable<P> kTable({
      rt::number("max_velocity_mps", &P::max_velocity_mps, Range::closed(0.1, 30.0)),
      rt::number("max_acceleration_mps2", &P::max_acceleration_mps2, Range::closed(0.1, 50.0)),
      rt::integer("acceleration_steps", &P::acceleration_steps, 1, 4),
      rt::number("primitive_duration_s", &P::primitive_duration_s, Range::closed(0.01, 2.0)),
      rt::number("time_weight", &P::time_weight, Range::closed(1e-3, 1e4)),
      rt::number("heuristic_weight", &P::heuristic_weight, Range::closed(0.0, 100.0)),
      rt::number("time_penalty_per_s", &P::time_penalty_per_s, Range::closed(0.0, 1e4)),
      rt::number("occlusion_penalty", &P::occlusion_penalty, Range::closed(0.0, 1e6)),
      rt::flag("occlusion_aware", &P::occlusion_aware),
      rt::number("position_resolution_m", &P::position_resolution_m, Range::closed(0.01, 5.0)),
      rt::number("velocity_resolution_mps", &P::velocity_resolution_mps, Range::closed(0.01, 10.0)),
      rt::number("goal_tolerance_m", &P::goal_tolerance_m, Range::closed(0.0, 5.0)),
      rt::number("goal_velocity_tolerance_mps", &P::goal_velocity_tolerance_mps, Range::closed(0.0, 10.0)),
      rt::number("one_shot_distance_m", &P::one_shot_distance_m, Range::closed(0.0, 50.0)),
      rt::integer("max_expansions", &P::max_expansions, 1, 10'000'000),
      rt::integer("max_nodes", &P::max_nodes, 2, 10'000'000),
  });
  return kTable;
}

rt::Status validate(const KinodynamicSearchParams& params) {
  return kinodynamicSearchFields().validate(params);
}

KinodynamicSearchParams parseKinodynamicSearchParams(const rt::ConfigNode& node) {
  return kinodynamicSearchFields().parse(node);
}

const rt::FieldTable<TrackingGoalParams>& trackingGoalFields() {
  using P = TrackingGoalParams;
  using rt::Range;
  static const rt::FieldTable<P> kTable({
      rt::number("predicted_weight", &P::predicted_weight, Range::closed(0.0, 1.0)),
      rt::number("tracking_distance_m", &P::tracking_distance_m, Range::closed(0.0, 50.0)),
      rt::number("visible_step_rad", &P::visible_step_rad, Range::closed(0.01, 3.2)),
      rt::number("visible_max_turn_rad", &P::visible_max_turn_rad, Range::closed(0.0, 3.2)),
      rt::number("max_lead_s", &P::max_lead_s, Range::closed(0.0, 10.0)),
      rt::number("trail_speed_mps", &P::trail_speed_mps, Range::closed(0.0, 50.0)),
  });
  return kTable;
}

rt::Status validate(const TrackingGoalParams& params) {
  return trackingGoalFields().validate(params);
}

KinematicState makeTrackingGoal(const KinematicState& person_now, const KinematicState& person_predicted,
                                const Eigen::Vector3d& p_drone_W_m, const TrackingGoalParams& params) {
  const double w = std::clamp(params.predicted_weight, 0.0, 1.0);
  const Eigen::Vector3d p_mix = (1.0 - w) * person_now.p_W_m + w * person_predicted.p_W_m;
  const Eigen::Vector3d v_mix = (1.0 - w) * person_now.v_W_mps + w * person_predicted.v_W_mps;
  Eigen::Vector2d away = (p_drone_W_m - p_mix).head<2>();
  if (away.norm() < 1e-6) away = -v_mix.head<2>();
  if (away.norm() < 1e-6) away = Eigen::Vector2d(-1.0, 0.0);
  away.normalize();
  // Trailing (issue 21): a walking person is followed from behind, the more so the faster they walk; a person
  // walking towards the drone is not (the drone would have to pass them): it backs off along `away`.
  const Eigen::Vector2d v_xy = v_mix.head<2>();
  const double speed_mps = v_xy.norm();
  if (params.trail_speed_mps > 0.0 && speed_mps > 1e-6 && away.dot(v_xy) <= 0.0) {
    const double beta = std::min(speed_mps / params.trail_speed_mps, 1.0);
    const Eigen::Vector2d blended = (1.0 - beta) * away - beta * v_xy / speed_mps;
    if (blended.norm() > 1e-6) away = blended.normalized();
  }
  KinematicState goal;
  goal.p_W_m.head<2>() = p_mix.head<2>() + params.tracking_distance_m * away;
  goal.p_W_m.z() = p_drone_W_m.z();
  goal.v_W_mps = Eigen::Vector3d(v_mix.x(), v_mix.y(), 0.0);
  return goal;
}

bool peopleBlockSight(const Eigen::Vector2d& from_W_m, const Eigen::Vector2d& to_W_m,
                      std::span<const Eigen::Vector2d> people_W_m, double radius_m) {
  if (!(radius_m > 0.0)) return false;
  const Eigen::Vector2d d = to_W_m - from_W_m;
  const double length_m = d.norm();
  if (!(length_m > 0.0)) return false;
  const Eigen::Vector2d u = d / length_m;
  for (const Eigen::Vector2d& q : people_W_m) {
    if ((q - to_W_m).norm() < radius_m) continue;  // on the person: maybe their own second track
    const Eigen::Vector2d r = q - from_W_m;
    const double along_m = r.dot(u);
    if (along_m > 0.0 && along_m < length_m && std::abs(u.x() * r.y() - u.y() * r.x()) < radius_m) return true;
  }
  return false;
}

KinematicState makeVisibleTrackingGoal(const mapping::LocalGrid& grid, const KinematicState& person_now,
                                       const KinematicState& person_predicted, const Eigen::Vector3d& p_drone_W_m,
                                       const TrackingGoalParams& params, const Eigen::Vector3d* p_ahead_W_m,
                                       const SightBlockers& others) {
  KinematicState goal = makeTrackingGoal(person_now, person_predicted, p_drone_W_m, params);
  const double w = std::clamp(params.predicted_weight, 0.0, 1.0);
  const Eigen::Vector3d p_person = (1.0 - w) * person_now.p_W_m + w * person_predicted.p_W_m;
  // Two passes: seeing the person now and at the horizon ahead; else seeing them now (before issue 21).
  const Eigen::Vector2d offset = goal.p_W_m.head<2>() - p_person.head<2>();
  const int steps = params.visible_step_rad > 0.0
                        ? static_cast<int>(std::floor(params.visible_max_turn_rad / params.visible_step_rad + 1e-9))
                        : 0;
  for (int pass = 0; pass < 2; ++pass) {
    const auto usable = [&](const Eigen::Vector3d& p) {
      return !grid.isOccupied(p) && grid.lineOfSight(p, p_person) &&
             !peopleBlockSight(p.head<2>(), p_person.head<2>(), others.now_W_m, others.radius_m) &&
             (pass == 1 || p_ahead_W_m == nullptr ||
              (grid.lineOfSight(p, *p_ahead_W_m) &&
               !peopleBlockSight(p.head<2>(), p_ahead_W_m->head<2>(), others.ahead_W_m, others.radius_m)));
    };
    if (usable(goal.p_W_m)) return goal;
    for (int k = 1; k <= steps; ++k) {
      for (const int sign : {1, -1}) {
        Eigen::Vector3d candidate = goal.p_W_m;
        candidate.head<2>() = p_person.head<2>() + Eigen::Rotation2Dd(sign * k * params.visible_step_rad) * offset;
        if (usable(candidate)) {
          goal.p_W_m = candidate;
          return goal;
        }
      }
    }
  }
  return goal;
}

bool clipGoalToWindow(const mapping::LocalGrid& grid, const Eigen::Vector3d& from_W_m, double margin_m,
                      KinematicState& goal) {
  // The margin is horizontal: the goal's height is the flight altitude, and the window's height (5 m) is
  // no room for a margin of a primitive's length. At least half a cell inside each face, and never an
  // empty box (a margin wider than half the window).
  const Eigen::Vector3d lo_raw = grid.windowMinM();
  const Eigen::Vector3d hi_raw = grid.windowMaxM();
  const Eigen::Vector3d centre = 0.5 * (lo_raw + hi_raw);
  const Eigen::Vector3d margin(std::max(margin_m, 0.0), std::max(margin_m, 0.0), 0.0);
  const Eigen::Vector3d inset = margin.cwiseMax(0.5 * grid.params().resolution_m).cwiseMin(0.5 * (hi_raw - lo_raw));
  const Eigen::Vector3d lo = (lo_raw + inset).cwiseMin(centre);
  const Eigen::Vector3d hi = (hi_raw - inset).cwiseMax(centre);
  const auto inside = [&](const Eigen::Vector3d& p) {
    return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
  };
  if (!goal.p_W_m.allFinite() || !from_W_m.allFinite() || inside(goal.p_W_m)) return false;
  if (!inside(from_W_m)) {
    goal.p_W_m = goal.p_W_m.cwiseMax(lo).cwiseMin(hi);
    return true;
  }
  // Largest s in [0, 1] with from + s (goal - from) inside [lo, hi] (slab clipping, per axis).
  const Eigen::Vector3d d = goal.p_W_m - from_W_m;
  double s_max = 1.0;
  for (int i = 0; i < 3; ++i) {
    if (d[i] > 0.0) s_max = std::min(s_max, (hi[i] - from_W_m[i]) / d[i]);
    if (d[i] < 0.0) s_max = std::min(s_max, (lo[i] - from_W_m[i]) / d[i]);
  }
  s_max = std::clamp(s_max, 0.0, 1.0);
  // Back towards from_W_m a cell at a time while the point is blocked (the search could not end there).
  const double length_m = s_max * d.norm();
  const double step_m = grid.params().resolution_m;
  const int steps = static_cast<int>(std::ceil(length_m / step_m));
  Eigen::Vector3d p = from_W_m + s_max * d;
  for (int k = 1; k <= steps && grid.isOccupied(p); ++k)
    p = from_W_m + (s_max * std::max(0.0, 1.0 - k * step_m / length_m)) * d;
  goal.p_W_m = p;
  return true;
}

KinematicState SearchPath::stateAt(double t_s) const {
  KinematicState state;
  if (segments.empty()) return state;
  double t = std::clamp(t_s, 0.0, duration_s);
  for (std::size_t i = 0; i < segments.size(); ++i) {
    const PathSegment& s = segments[i];
    if (t <= s.duration_s || i + 1 == segments.size()) {
      t = std::min(t, s.duration_s);
      state.p_W_m = positionOf(s, t);
      state.v_W_mps = s.v0_W_mps + t * (s.a0_W_mps2 + 0.5 * t * s.jerk_W_mps3);
      return state;
    }
    t -= s.duration_s;
  }
  return state;
}

Eigen::Vector3d SearchPath::accelerationAt(double t_s) const {
  if (segments.empty()) return Eigen::Vector3d::Zero();
  double t = std::clamp(t_s, 0.0, duration_s);
  for (std::size_t i = 0; i < segments.size(); ++i) {
    const PathSegment& s = segments[i];
    if (t <= s.duration_s || i + 1 == segments.size()) {
      t = std::min(t, s.duration_s);
      return s.a0_W_mps2 + t * s.jerk_W_mps3;
    }
    t -= s.duration_s;
  }
  return Eigen::Vector3d::Zero();
}

rt::Expected<KinodynamicSearch> KinodynamicSearch::create(const KinodynamicSearchParams& params) {
  if (const rt::Status valid = validate(params); !valid)
    return rt::Error{"kinodynamic search: " + valid.error().message};
  return KinodynamicSearch(params);
}

KinodynamicSearch::KinodynamicSearch(const KinodynamicSearchParams& params) : params_(params) {
  const int steps = params.acceleration_steps;
  const double step_mps2 = params.max_acceleration_mps2 / steps;
  for (int z = -steps; z <= steps; ++z) {
    for (int y = -steps; y <= steps; ++y) {
      for (int x = -steps; x <= steps; ++x) inputs_.emplace_back(x * step_mps2, y * step_mps2, z * step_mps2);
    }
  }
  nodes_.resize(static_cast<std::size_t>(params.max_nodes));
  std::size_t capacity = 1;
  while (capacity < 2 * nodes_.size()) capacity <<= 1;
  table_.assign(capacity, -1);
  table_stamp_.assign(capacity, 0);
  // One open entry per child generated and one more per occluded node: at most max_expansions * inputs +
  // max_nodes (capped; past the cap the open list may grow once, and keeps that capacity).
  const std::size_t pushes =
      static_cast<std::size_t>(params.max_expansions) * inputs_.size() + static_cast<std::size_t>(params.max_nodes);
  open_.reserve(std::min<std::size_t>(pushes, std::size_t{1} << 22));
  chain_.reserve(static_cast<std::size_t>(params.max_nodes));
}

std::int64_t KinodynamicSearch::keyOf(const Eigen::Vector3d& p, const Eigen::Vector3d& v) const {
  // 12 bits per position axis (+-409.6 m at 0.2 m), 9 bits per velocity axis: wraps harmlessly beyond (the
  // key only has to tell apart states inside one window).
  std::uint64_t key = 0;
  for (int i = 0; i < 3; ++i) {
    const auto cell = static_cast<std::int64_t>(std::floor(p[i] / params_.position_resolution_m));
    key = (key << 12) | (static_cast<std::uint64_t>(cell) & 0xFFFu);
  }
  for (int i = 0; i < 3; ++i) {
    const auto cell = static_cast<std::int64_t>(std::floor(v[i] / params_.velocity_resolution_mps));
    key = (key << 9) | (static_cast<std::uint64_t>(cell) & 0x1FFu);
  }
  return static_cast<std::int64_t>(key);
}

int* KinodynamicSearch::findSlot(std::int64_t key) {
  const std::size_t mask = table_.size() - 1;
  std::uint64_t h = static_cast<std::uint64_t>(key);  // splitmix64's finaliser: every key bit reaches every bit
  h = (h ^ (h >> 30)) * 0xBF58476D1CE4E5B9ull;
  h = (h ^ (h >> 27)) * 0x94D049BB133111EBull;
  h ^= h >> 31;
  std::size_t slot = static_cast<std::size_t>(h) & mask;
  while (true) {
    if (table_stamp_[slot] != stamp_) {
      table_stamp_[slot] = stamp_;
      table_[slot] = -1;
      return &table_[slot];
    }
    const int node = table_[slot];
    if (node < 0 || nodes_[static_cast<std::size_t>(node)].key == key) return &table_[slot];
    slot = (slot + 1) & mask;
  }
}

bool KinodynamicSearch::clearOfPeople(const Eigen::Vector3d& a, double ta_s, const Eigen::Vector3d& b,
                                      double tb_s) const {
  if (people_count_ == 0 || !(people_clearance_m_ > 0.0)) return true;  // none, or no clearance to keep
  // Points along the chord (position and time linear in between) no farther apart than a quarter of the
  // clearance (a chord can be a whole primitive long at speed) nor kPeopleStepS in time (someone walks into a
  // drone that hovers: a == b).
  constexpr double kPeopleStepS = 0.05;
  const int steps = std::max({1, static_cast<int>(std::ceil((b - a).head<2>().norm() / (0.25 * people_clearance_m_))),
                              static_cast<int>(std::ceil((tb_s - ta_s) / kPeopleStepS))});
  for (int k = 1; k <= steps; ++k) {
    const double f = static_cast<double>(k) / steps;
    const Eigen::Vector2d p = a.head<2>() + f * (b - a).head<2>();
    const double t_s = ta_s + f * (tb_s - ta_s);
    for (std::size_t i = 0; i < people_count_; ++i) {
      if (avoided_[i] && (p - people_[i].at(t_s)).norm() < people_clearance_m_) return false;
    }
  }
  return true;
}

bool KinodynamicSearch::peopleOcclude(const Eigen::Vector3d& p, const Eigen::Vector3d& person_W_m, double t_s) const {
  if (people_count_ == 0 || !(people_sight_radius_m_ > 0.0)) return false;
  std::array<Eigen::Vector2d, kMaxSearchPeople> at_W_m;
  for (std::size_t i = 0; i < people_count_; ++i) at_W_m[i] = people_[i].at(t_s);
  return peopleBlockSight(p.head<2>(), person_W_m.head<2>(),
                          std::span<const Eigen::Vector2d>(at_W_m.data(), people_count_), people_sight_radius_m_);
}

bool KinodynamicSearch::endClearOfPeople(const Eigen::Vector3d& end, double t_s) const {
  // The path ends at rest there (the planner appends a brake): held until everyone stands still.
  double still_s = t_s;
  for (std::size_t i = 0; i < people_count_; ++i) still_s = std::max(still_s, people_[i].moving_s);
  return clearOfPeople(end, t_s, end, still_s);
}

bool KinodynamicSearch::primitiveFree(const mapping::LocalGrid& grid, const Eigen::Vector3d& p,
                                      const Eigen::Vector3d& v, const Eigen::Vector3d& u, double duration_s,
                                      double t0_s) const {
  const Eigen::Vector3d end = p + duration_s * (v + 0.5 * duration_s * u);
  if (!pointFree(grid, end) || !inBand(end)) return false;  // cheap early reject
  const int chords = chordCount(u.norm(), duration_s);
  const double dt = duration_s / chords;
  Eigen::Vector3d previous = p;
  for (int i = 1; i <= chords; ++i) {
    const double t = i * dt;
    const Eigen::Vector3d next = p + t * (v + 0.5 * t * u);
    if (!inBand(next) || !chordFree(grid, previous, next) || !clearOfPeople(previous, t0_s + t - dt, next, t0_s + t))
      return false;
    previous = next;
  }
  return true;
}

bool KinodynamicSearch::oneShot(const mapping::LocalGrid& grid, const Node& from, const KinematicState& goal,
                                PathSegment& shot, double& cost) const {
  const ObvpSolution obvp = solveObvp(from.p, from.v, goal.p_W_m, goal.v_W_mps, params_.time_weight);
  const double t_end = obvp.duration_s;
  if (!(t_end > 1e-6)) return false;
  const ObvpCubic cubic = obvpCubic(from.p, from.v, goal.p_W_m, goal.v_W_mps, t_end);
  shot = PathSegment{from.p, from.v, cubic.a0_mps2, cubic.jerk_mps3, t_end};
  // Acceleration is linear in t: its ends bound it. Velocity is quadratic per axis: ends and the vertex.
  if (!withinLimits(cubic.a0_mps2, params_.max_acceleration_mps2) ||
      !withinLimits(cubic.a0_mps2 + t_end * cubic.jerk_mps3, params_.max_acceleration_mps2) ||
      !withinLimits(goal.v_W_mps, params_.max_velocity_mps)) {
    return false;
  }
  for (int i = 0; i < 3; ++i) {
    const double j = cubic.jerk_mps3[i];
    if (std::abs(j) < 1e-12) continue;
    const double t_vertex = -cubic.a0_mps2[i] / j;
    if (t_vertex > 0.0 && t_vertex < t_end) {
      const double v = from.v[i] + t_vertex * (cubic.a0_mps2[i] + 0.5 * t_vertex * j);
      if (std::abs(v) > params_.max_velocity_mps + 1e-9) return false;
    }
  }
  const double max_acceleration_mps2 = std::max(cubic.a0_mps2.norm(), (cubic.a0_mps2 + t_end * cubic.jerk_mps3).norm());
  const int chords = chordCount(max_acceleration_mps2, t_end);
  Eigen::Vector3d previous = from.p;
  for (int i = 1; i <= chords; ++i) {
    const double t = t_end * i / chords;
    const Eigen::Vector3d next = positionOf(shot, t);
    if (!inBand(next) || !chordFree(grid, previous, next) ||
        !clearOfPeople(previous, from.t + t_end * (i - 1) / chords, next, from.t + t))
      return false;
    previous = next;
  }
  cost = obvp.cost;
  return true;
}

double KinodynamicSearch::heuristic(const KinematicState& from, const KinematicState& goal) const {
  const ObvpSolution obvp = solveObvp(from.p_W_m, from.v_W_mps, goal.p_W_m, goal.v_W_mps, params_.time_weight);
  return params_.heuristic_weight * obvp.cost + params_.time_penalty_per_s * obvp.duration_s;
}

void KinodynamicSearch::writePath(int end_node, const PathSegment* shot, double shot_cost, SearchPath& path) {
  chain_.clear();
  for (int n = end_node; n >= 0; n = nodes_[static_cast<std::size_t>(n)].parent) chain_.push_back(n);
  path.segments.clear();
  path.occluded_nodes = 0;
  const double tau = params_.primitive_duration_s;
  // chain_ runs end -> start; the start node has no primitive.
  for (auto it = chain_.rbegin(); it != chain_.rend(); ++it) {
    const Node& node = nodes_[static_cast<std::size_t>(*it)];
    if (node.occluded) ++path.occluded_nodes;
    if (node.parent < 0) continue;
    const Node& parent = nodes_[static_cast<std::size_t>(node.parent)];
    path.segments.push_back(PathSegment{parent.p, parent.v, node.u, Eigen::Vector3d::Zero(), tau});
  }
  const Node& end = nodes_[static_cast<std::size_t>(end_node)];
  path.cost = end.g;
  path.duration_s = end.t;
  path.end_heuristic = end.d;
  if (shot != nullptr) {
    path.segments.push_back(*shot);
    path.cost += shot_cost;
    path.duration_s += shot->duration_s;
    path.end_heuristic = 0.0;
  }
}

SearchStatus KinodynamicSearch::search(const mapping::LocalGrid& grid, const KinematicState& start,
                                       const KinematicState& goal_in, double start_time_s,
                                       const PersonPositionFn& person_W_m, SearchPath& path) {
  path.segments.clear();
  path.cost = 0.0;
  path.duration_s = 0.0;
  path.expansions = 0;
  path.occluded_nodes = 0;
  path.end_heuristic = 0.0;
  const auto finish = [&path](SearchStatus status) {
    path.status = status;
    return status;
  };
  if (!finite(start.p_W_m) || !finite(start.v_W_mps) || !finite(goal_in.p_W_m) || !finite(goal_in.v_W_mps) ||
      !std::isfinite(start_time_s)) {
    return finish(SearchStatus::kInvalidInput);
  }
  if (!pointFree(grid, start.p_W_m) || !withinLimits(start.v_W_mps, params_.max_velocity_mps)) {
    return finish(SearchStatus::kStartBlocked);
  }
  for (std::size_t i = 0; i < people_count_; ++i)
    avoided_[i] = (start.p_W_m.head<2>() - people_[i].p_W_m).norm() >= people_clearance_m_;
  search_min_z_m_ = std::min(min_z_m_, start.p_W_m.z());
  search_max_z_m_ = std::max(max_z_m_, start.p_W_m.z());
  // A goal velocity beyond the per-axis limit could never be matched (one-shot or tolerance): scaled into it,
  // direction kept (a runner at 5 m/s along an axis made every search partial, issue 21).
  const double goal_v_inf = goal_in.v_W_mps.cwiseAbs().maxCoeff();
  KinematicState goal = goal_in;
  if (goal_v_inf > params_.max_velocity_mps) goal.v_W_mps *= params_.max_velocity_mps / goal_v_inf;
  const bool check_occlusion = params_.occlusion_aware && params_.occlusion_penalty > 0.0 && person_W_m;
  const auto occluded = [&](const Eigen::Vector3d& p, double t) {
    if (!check_occlusion) return false;
    const Eigen::Vector3d person = person_W_m(start_time_s + t);
    return !grid.lineOfSight(p, person) || peopleOcclude(p, person, t);
  };
  // P_occ is added lazily, when a node is first popped (the paper checks occlusion "in each expanding
  // process"): an occluded node goes back into the open list with the penalty, so the line of sight is
  // traced only for nodes that would otherwise be expanded.
  const auto evaluate = [&](Node& node) {
    const ObvpSolution obvp = solveObvp(node.p, node.v, goal.p_W_m, goal.v_W_mps, params_.time_weight);
    node.d = obvp.cost;
    node.f = node.g + params_.heuristic_weight * obvp.cost + params_.time_penalty_per_s * obvp.duration_s;
  };

  if (++stamp_ == 0) {  // wrapped: invalidate every slot explicitly once
    std::fill(table_stamp_.begin(), table_stamp_.end(), 0u);
    stamp_ = 1;
  }
  open_.clear();
  int used = 0;
  Node& root = nodes_[0];
  root = Node{start.p_W_m, start.v_W_mps, Eigen::Vector3d::Zero(),           0.0, 0.0,
              0.0,         0.0,           keyOf(start.p_W_m, start.v_W_mps), -1,  false,
              false};
  evaluate(root);
  *findSlot(root.key) = 0;
  used = 1;
  open_.push_back({root.f, 0});
  int best_partial = 0;
  bool pool_full = false;
  const double tau = params_.primitive_duration_s;
  const double vmax = params_.max_velocity_mps;
  PathSegment shot;
  double shot_cost = 0.0;

  while (!open_.empty()) {
    std::pop_heap(open_.begin(), open_.end());
    const OpenEntry entry = open_.back();
    open_.pop_back();
    Node& current = nodes_[static_cast<std::size_t>(entry.node)];
    // Stale: the node was closed, improved (pushed again with a lower f) or penalised (pushed again with a
    // higher f); only the entry carrying its current f counts (the same double is stored in both).
    if (current.closed || entry.f != current.f) continue;
    if (check_occlusion && !current.occlusion_checked) {
      current.occlusion_checked = true;
      current.occluded = occluded(current.p, current.t);
      if (current.occluded) {
        current.f += params_.occlusion_penalty;
        open_.push_back({current.f, entry.node});
        std::push_heap(open_.begin(), open_.end());
        continue;
      }
    }
    if (path.expansions >= params_.max_expansions || pool_full) {
      writePath(best_partial, nullptr, 0.0, path);
      return finish(SearchStatus::kPartial);
    }
    current.closed = true;
    ++path.expansions;
    const int current_index = entry.node;
    // A partial path ends at rest where it stops too: only where nobody walks into it.
    if (current.d < nodes_[static_cast<std::size_t>(best_partial)].d && endClearOfPeople(current.p, current.t))
      best_partial = current_index;

    const double distance_m = (current.p - goal.p_W_m).norm();
    // The start is not a lattice node: the one-shot can reach the goal's exact state from it, so it is tried
    // before the tolerances. Otherwise a drone hovering within 0.2 m and 0.5 m/s of a person who sets off
    // counts as arrived, and no plan is made until the goal has left the tolerances (0.58 s after a runner
    // set off in the forest, issue 21); the one-shot's duration says how far from the goal the start is.
    if (current_index == 0 && distance_m <= params_.one_shot_distance_m &&
        oneShot(grid, current, goal, shot, shot_cost) && endClearOfPeople(goal.p_W_m, current.t + shot.duration_s)) {
      writePath(current_index, &shot, shot_cost, path);
      return finish(SearchStatus::kReachedGoal);
    }
    if (distance_m <= params_.goal_tolerance_m &&
        (current.v - goal.v_W_mps).cwiseAbs().maxCoeff() <= params_.goal_velocity_tolerance_mps &&
        endClearOfPeople(current.p, current.t)) {
      writePath(current_index, nullptr, 0.0, path);
      return finish(SearchStatus::kReachedGoal);
    }
    if (distance_m <= params_.one_shot_distance_m && oneShot(grid, current, goal, shot, shot_cost) &&
        endClearOfPeople(goal.p_W_m, current.t + shot.duration_s)) {
      writePath(current_index, &shot, shot_cost, path);
      return finish(SearchStatus::kReachedGoal);
    }

    const Eigen::Vector3d p = current.p;
    const Eigen::Vector3d v = current.v;
    const double g = current.g;
    const double t = current.t;
    for (const Eigen::Vector3d& u : inputs_) {
      const Eigen::Vector3d v_next = v + tau * u;
      if (!withinLimits(v_next, vmax)) continue;
      const Eigen::Vector3d p_next = p + tau * (v + 0.5 * tau * u);
      const std::int64_t key = keyOf(p_next, v_next);
      int* slot = findSlot(key);
      const double g_next = g + (u.squaredNorm() + params_.time_weight) * tau;
      if (*slot >= 0) {
        const Node& existing = nodes_[static_cast<std::size_t>(*slot)];
        if (existing.closed || existing.g <= g_next) continue;
      }
      if (!primitiveFree(grid, p, v, u, tau, t)) continue;
      int index = *slot;
      if (index < 0) {
        if (used >= params_.max_nodes) {
          pool_full = true;
          break;
        }
        index = used++;
        *slot = index;
      }
      Node& child = nodes_[static_cast<std::size_t>(index)];
      child = Node{p_next, v_next, u, g_next, 0.0, 0.0, t + tau, key, current_index, false, false, false};
      evaluate(child);
      open_.push_back({child.f, index});
      std::push_heap(open_.begin(), open_.end());
    }
  }
  if (pool_full) {
    writePath(best_partial, nullptr, 0.0, path);
    return finish(SearchStatus::kPartial);
  }
  path.segments.clear();
  return finish(SearchStatus::kNoPath);
}

}  // namespace aerotrack::planning
