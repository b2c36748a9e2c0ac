// Occlusion-aware kinodynamic path search (paper Sect. V-B), a hybrid A* in the style of Fast-Planner's
// kinodynamic A* (Zhou et al., RA-L 2019). State x = (p, v) in the world frame W; the input is an
// acceleration u, discretised per axis and held for a primitive duration tau (motion primitives). Node
// cost f_c = g_c + h_c with
//   g_c = sum over primitives of (|u|^2 tau + rho tau)   (the discretised J_t = integral |u|^2 + rho T),
//   h_c = lambda_h D(x_c, x_g) + P_time + P_occ          (paper Eq. for h_c),
// where D is the OBVP cost to the goal (obvp.hpp; it already holds rho T*), P_time = time_penalty_per_s *
// T*(x_c, x_g) an extra push towards short arrival times, and P_occ a constant added when the segment from
// the node to the person's predicted position at the node's time is blocked in the grid
// (LocalGrid::lineOfSight). As in the paper the occlusion check runs "in each expanding process": a node is
// checked when first popped, and an occluded one goes back into the open list with P_occ added. The
// baseline mode (occlusion_aware = false) leaves P_occ out: the paper's comparison. The goal x_g is a
// weighted mix of the person's current and predicted states held at the tracking distance
// (makeTrackingGoal). Primitives are checked against the velocity and acceleration limits (per axis) and
// against the inflated grid as a polyline of chords traced by DDA, short enough that the curve strays less
// than 1 mm from them; near the goal an analytic one-shot OBVP cubic to the goal is tried (collision- and
// limit-checked, as in Fast-Planner). The closed set is a hash on the discretised (p, v). When the
// expansion budget runs out, the path to the expanded node with the smallest D to the goal is returned (a
// partial path).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "aerotrack/mapping/local_grid.hpp"
#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/field_table.hpp"

namespace aerotrack::planning {

struct KinodynamicSearchParams {
  double max_velocity_mps = 3.0;             ///< Per-axis speed limit; > 0.
  double max_acceleration_mps2 = 3.0;        ///< Per-axis acceleration limit (inputs and one-shot); > 0.
  int acceleration_steps = 1;                ///< Inputs per axis: k / steps * max_acceleration, k in [-steps, steps].
  double primitive_duration_s = 0.3;         ///< tau, how long each input is held; > 0.
  double time_weight = 10.0;                 ///< rho in J_t (cost per second of flight).
  double heuristic_weight = 5.0;             ///< lambda_h on D (Fast-Planner: 5); 1 keeps the heuristic admissible.
  double time_penalty_per_s = 0.0;           ///< P_time = this * T*(x_c, x_g); >= 0.
  double occlusion_penalty = 200.0;          ///< P_occ for a node that cannot see the person; >= 0.
  bool occlusion_aware = true;               ///< false: the baseline (no P_occ, no line-of-sight checks).
  double position_resolution_m = 0.1;        ///< Closed-set cell size in position; > 0.
  double velocity_resolution_mps = 0.5;      ///< Closed-set cell size in velocity; > 0.
  double goal_tolerance_m = 0.2;             ///< A node this close to the goal position ...
  double goal_velocity_tolerance_mps = 0.5;  ///< ... and velocity counts as reached.
  double one_shot_distance_m = 3.0;          ///< Try the analytic one-shot from nodes this close to the goal.
  int max_expansions = 200;                  ///< Budget: nodes expanded before the best partial path is returned (about
                                             ///< 15-25 us each in the forest: the cycle's p99 under 5 ms, issue 21).
  int max_nodes = 10000;  ///< Node pool (allocated once, ~130 B a node); >= max_expansions * inputs suffices;
                          ///< the search also stops (partial) when it is full.
};

/// The `search:` config section: every field above by its name, all required, with the one range that
/// parsing, validate() and printing share (rt/field_table.hpp; the ranges are in the .cpp).
const rt::FieldTable<KinodynamicSearchParams>& kinodynamicSearchFields();
/// Every field in its range; the error names the key.
rt::Status validate(const KinodynamicSearchParams& params);
/// kinodynamicSearchFields().parse: reads every key of a `search:` section and calls finish(). Throws
/// rt::ConfigError (file:line: key: message) on a missing, unknown or out-of-range key.
KinodynamicSearchParams parseKinodynamicSearchParams(const rt::ConfigNode& node);

/// Position and velocity in W.
struct KinematicState {
  Eigen::Vector3d p_W_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_W_mps = Eigen::Vector3d::Zero();
};

struct TrackingGoalParams {
  double predicted_weight = 0.5;     ///< w in x_g = (1 - w) x_tc + w x_tp; in [0, 1].
  double tracking_distance_m = 2.5;  ///< Horizontal distance held from the mixed person position; >= 0.
  /// Visible goal (makeVisibleTrackingGoal): candidate steps round the person, and the largest turn; both
  /// > 0 (a step larger than the turn tries the plain goal only).
  double visible_step_rad = 0.2618;      // 15 degrees
  double visible_max_turn_rad = 1.5708;  // 90 degrees either way
  /// When x_tp is taken (read by TrackingPlanner::selectGoal): 0, at the prediction horizon after the
  /// hand-over (the paper's reading); > 0, when the drone would get to the goal (the last complete search
  /// path's duration), at most this long after the hand-over. Why (issue 21): a goal taken at a fixed
  /// horizon shorter than the path to it trails the person, and the drone settled 1.5-2 m farther back
  /// than the tracking distance at 2.5 m/s and more at a run.
  double max_lead_s = 0.0;
  /// Which side of the person the goal is held on: 0, towards the drone (the paper's reading); > 0, blended
  /// towards behind the person's (mixed) velocity, fully behind at this speed and faster, unless the person
  /// walks towards the drone. Why (issue 21): held towards the drone, a goal barely moves while the person
  /// walks across the drone-person line (the distance grows only to second order), and a person turning a
  /// corner at a run left the drone behind it, the building between them (sharp_turn 3 m/s seeds 8, 14).
  double trail_speed_mps = 0.0;
};

/// The planner's `goal:` config section (every field above, all required; ranges in the .cpp).
const rt::FieldTable<TrackingGoalParams>& trackingGoalFields();
/// Every field in its range; the error names the key.
rt::Status validate(const TrackingGoalParams& params);

/// The goal state: the mix of the person's current and predicted states, moved horizontally towards the
/// drone by tracking_distance_m (behind the person's velocity when the drone is right above it, -x when the
/// person stands still too), at the drone's altitude p_drone_W_m.z(); velocity: the mixed person velocity
/// with z = 0. Pure, allocation-free, thread-safe.
KinematicState makeTrackingGoal(const KinematicState& person_now, const KinematicState& person_predicted,
                                const Eigen::Vector3d& p_drone_W_m, const TrackingGoalParams& params);

/// The other people, horizontally (W), as makeVisibleTrackingGoal's candidates must see past them: where they stand
/// now, and where they will be at the time of its `p_ahead_W_m`. Why (issue 22 item 2): in the crowd the goal held
/// behind the person saw through bystanders, the map holding them only where the depth camera last saw them; every
/// traced long switch to the look-alike followed a second in which someone standing in front of the person was
/// refused and the person's track starved.
struct SightBlockers {
  std::span<const Eigen::Vector2d> now_W_m;
  std::span<const Eigen::Vector2d> ahead_W_m;
  double radius_m = 0.0;  ///< 0: nobody blocks.
};

/// makeTrackingGoal, kept where it is when it is free in the grid and the person (at the mixed position)
/// is in its line of sight; else the nearest point on the same circle round the person that is both,
/// turning both ways from it in visible_step_rad up to visible_max_turn_rad (the plain goal if none is).
/// Why: the plain goal lies on the line from the person to the drone, so once the person has turned a
/// corner it sits in the corner's shadow, and a drone that reaches it sees nothing (the relocation of
/// issue 9 stopped there). The velocity is the plain goal's. Allocation-free; O(candidates x cells).
/// `p_ahead_W_m` (optional): a point of the person's predicted path that the goal should see as well (the
/// planner passes the prediction at its horizon: the paper checks occlusion against x_tp); candidates that
/// see both come first, then those that see the person now. Why: with x_tp taken close to now, a drone
/// near a corner kept a goal that saw the person at the corner and not where they were walking, backed off
/// along the line to them, and lost them round it (issue 21, sharp_turn seed 8 at 0.85 m/s).
///
/// `others` (optional, SightBlockers): a candidate with one of them standing on its line of sight to the person
/// (peopleBlockSight, others.radius_m) does not see them.
KinematicState makeVisibleTrackingGoal(const mapping::LocalGrid& grid, const KinematicState& person_now,
                                       const KinematicState& person_predicted, const Eigen::Vector3d& p_drone_W_m,
                                       const TrackingGoalParams& params, const Eigen::Vector3d* p_ahead_W_m = nullptr,
                                       const SightBlockers& others = {});

/// Whether one of `people_W_m` stands on the line of sight from `from_W_m` to `to_W_m` (horizontal, W): their
/// centre nearer the segment than radius_m, and nearer `from_W_m` along it than `to_W_m` is (in front of what
/// is looked at; beside or behind it hides nothing). Someone within radius_m of `to_W_m` is not counted: the
/// target task can hold a second track on the person themself (one started on a refused frame of theirs), and
/// every point round the person would be blocked by it. Pure.
bool peopleBlockSight(const Eigen::Vector2d& from_W_m, const Eigen::Vector2d& to_W_m,
                      std::span<const Eigen::Vector2d> people_W_m, double radius_m);

/// A goal the search can reach: the search only expands states inside the grid's window (nothing is known
/// beyond it), so a goal outside the window, or within `margin_m` of its faces, is moved along the straight
/// line from `from_W_m` to the last point at least `margin_m` inside, then back along that line, a cell at a
/// time, to the first unblocked point. The velocity is kept. Returns whether the goal moved.
/// Why: a drone more than ~8 m behind a runner (the window is 20 m wide and recentres every 2 m) searched
/// for a goal it could never reach, spent the whole expansion budget every cycle, and those cycles were the
/// planning tail (issue 21 item 6: forest at 5 m/s, 273 of 426 searches partial). A `from_W_m` outside the
/// shrunk window clamps the goal into it per axis instead.
bool clipGoalToWindow(const mapping::LocalGrid& grid, const Eigen::Vector3d& from_W_m, double margin_m,
                      KinematicState& goal);

/// The person's (predicted) position in W at an absolute time t_s (the clock of start_time_s below).
using PersonPositionFn = std::function<Eigen::Vector3d(double t_s)>;

/// One piece of the path: p(t) = p0 + v0 t + a0 t^2 / 2 + jerk t^3 / 6 for t in [0, duration_s]. Motion
/// primitives have jerk 0; the final one-shot piece is the OBVP cubic.
struct PathSegment {
  Eigen::Vector3d p0_W_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d v0_W_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d a0_W_mps2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d jerk_W_mps3 = Eigen::Vector3d::Zero();
  double duration_s = 0.0;
};

enum class SearchStatus : std::uint8_t {
  kReachedGoal,   ///< The path ends at the goal (one-shot) or within the goal tolerances.
  kPartial,       ///< Budget (expansions or node pool) exhausted: path to the node closest to the goal.
  kNoPath,        ///< Every reachable state was expanded without reaching the goal; the path is empty.
  kStartBlocked,  ///< The start is not free in the grid, outside the window, or beyond the limits.
  kInvalidInput,  ///< Non-finite start, goal or start time.
};
std::string_view toString(SearchStatus status);

struct SearchPath {
  SearchStatus status = SearchStatus::kNoPath;
  std::vector<PathSegment> segments;  ///< Empty unless kReachedGoal or kPartial.
  double cost = 0.0;                  ///< g of the path (J_t of its pieces, P_occ not included).
  double duration_s = 0.0;            ///< Sum of the segment durations.
  int expansions = 0;                 ///< Nodes expanded.
  int occluded_nodes = 0;  ///< Nodes along the path (primitive ends) found unable to see the person (occlusion-aware
                           ///< mode only: nodes are checked when expanded, and the path's end may be unchecked).
  double end_heuristic = 0.0;  ///< D(end, goal): 0 when the goal was reached by the one-shot.

  /// The path at time t_s from its start (clamped to [0, duration_s]). Empty path: zero state.
  KinematicState stateAt(double t_s) const;
  Eigen::Vector3d accelerationAt(double t_s) const;
};

/// Someone other than the followed person, as the search keeps clear of them (issue 21 item 5): at p_W_m when the
/// search starts, walking at v_W_mps for moving_s seconds, then standing (horizontal, W).
struct MovingPerson {
  Eigen::Vector2d p_W_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d v_W_mps = Eigen::Vector2d::Zero();
  double moving_s = 0.0;
  Eigen::Vector2d at(double t_s) const { return p_W_m + std::clamp(t_s, 0.0, moving_s) * v_W_mps; }
};
/// The most people a search keeps clear of (the target task tracks 12 others).
inline constexpr std::size_t kMaxSearchPeople = 16;

/// The search, with its scratch memory (node pool, hash table, open list) allocated once in create() and
/// reused by every search(). Not thread-safe: one instance per thread. Copyable and movable.
class KinodynamicSearch {
 public:
  /// Validates params (every field in its documented range) and allocates the scratch memory.
  static rt::Expected<KinodynamicSearch> create(const KinodynamicSearchParams& params);

  const KinodynamicSearchParams& params() const { return params_; }
  /// Switches the occlusion penalty on or off (the baseline mode) without reallocating.
  void setOcclusionAware(bool occlusion_aware) { params_.occlusion_aware = occlusion_aware; }
  bool occlusionAware() const { return params_.occlusion_aware; }
  /// Keeps every path inside the heights [min_z_m, max_z_m] (W z; default: unbounded). A start outside the band
  /// widens it to the start's height for that search: the path may climb (or sink) back into the band, never
  /// away from it. Why (issue 21): unknown space counts as free, and the space under a person or a wall's
  /// edge that the depth camera never saw drew the path down to the floor's margin, where it stopped.
  void setAltitudeBand(double min_z_m, double max_z_m) {
    min_z_m_ = min_z_m;
    max_z_m_ = max_z_m;
  }
  /// Keeps every path horizontally clearance_m from each of `people` (the first kMaxSearchPeople) at the time it
  /// passes there, as the final check will; someone already that close to the start is left to the check
  /// (which forbids coming closer). Why (issue 21 item 5): the final check alone refused every plan that
  /// passed near a walker, and the drone fell behind the person in the crowd; searched around, it follows
  /// on. Holds until set again (an empty span, or a clearance not above 0, clears it); no allocation.
  /// sight_radius_m > 0 (occlusion-aware mode): a node from which one of them, where they walk by then, stands on
  /// the line of sight to the person (peopleBlockSight) is occluded, as one the map's line of sight fails
  /// (issue 22 item 2: see SightBlockers).
  void setPeople(std::span<const MovingPerson> people, double clearance_m, double sight_radius_m = 0.0) {
    people_count_ = std::min(people.size(), people_.size());
    std::copy_n(people.begin(), people_count_, people_.begin());
    people_clearance_m_ = clearance_m;
    people_sight_radius_m_ = sight_radius_m;
  }

  /// Searches from start to goal in `grid` (blocked = LocalGrid::isOccupied, which applies the inflation
  /// and the grid's unknown policy; the path must also stay in the window). start_time_s is the absolute
  /// time of the start state: a node reached after t seconds asks person_W_m(start_time_s + t) for the
  /// line-of-sight check (not called in the baseline mode; may be empty then). Writes `path` (its vectors
  /// keep their capacity, so a reused path allocates nothing once warm) and returns path.status. No clock is
  /// read: the budget is max_expansions. Cost O(expansions * primitives * (chord cells + OBVP) + expanded
  /// nodes * line of sight). A goal velocity over the per-axis limit is searched for scaled into it
  /// (direction kept): no path could end with it. A goal outside the window is unreachable (see
  /// clipGoalToWindow).
  SearchStatus search(const mapping::LocalGrid& grid, const KinematicState& start, const KinematicState& goal,
                      double start_time_s, const PersonPositionFn& person_W_m, SearchPath& path);

  /// h_c without P_occ: heuristic_weight * D + P_time (exposed for tests).
  double heuristic(const KinematicState& from, const KinematicState& goal) const;

 private:
  struct Node {
    Eigen::Vector3d p;
    Eigen::Vector3d v;
    Eigen::Vector3d u;  // input of the primitive that reached this node
    double g = 0.0;
    double f = 0.0;
    double d = 0.0;  // unweighted D to the goal
    double t = 0.0;  // seconds since the start
    std::int64_t key = 0;
    int parent = -1;
    bool closed = false;
    bool occluded = false;
    bool occlusion_checked = false;
  };
  struct OpenEntry {
    double f;
    int node;
    bool operator<(const OpenEntry& other) const { return f > other.f; }  // min-heap via std::push_heap
  };

  explicit KinodynamicSearch(const KinodynamicSearchParams& params);
  std::int64_t keyOf(const Eigen::Vector3d& p, const Eigen::Vector3d& v) const;
  int* findSlot(std::int64_t key);  // the slot holding key's node, or the empty slot where it goes
  bool primitiveFree(const mapping::LocalGrid& grid, const Eigen::Vector3d& p, const Eigen::Vector3d& v,
                     const Eigen::Vector3d& u, double duration_s, double t0_s) const;
  /// The chord from a (reached ta_s after the start) to b (tb_s) keeps clear of the people this search avoids.
  bool clearOfPeople(const Eigen::Vector3d& a, double ta_s, const Eigen::Vector3d& b, double tb_s) const;
  /// A path ending at `end` at t_s, held there, keeps clear of them until they all stand still.
  bool endClearOfPeople(const Eigen::Vector3d& end, double t_s) const;
  bool oneShot(const mapping::LocalGrid& grid, const Node& from, const KinematicState& goal, PathSegment& shot,
               double& cost) const;
  void writePath(int end_node, const PathSegment* shot, double shot_cost, SearchPath& path);

  KinodynamicSearchParams params_;
  double min_z_m_ = -std::numeric_limits<double>::infinity();  // setAltitudeBand
  double max_z_m_ = std::numeric_limits<double>::infinity();
  double search_min_z_m_ = 0.0;  // per search: the band widened to the start's height
  double search_max_z_m_ = 0.0;
  bool inBand(const Eigen::Vector3d& p) const { return p.z() >= search_min_z_m_ && p.z() <= search_max_z_m_; }
  std::array<MovingPerson, kMaxSearchPeople> people_{};  // setPeople
  std::size_t people_count_ = 0;
  double people_clearance_m_ = 0.0;
  double people_sight_radius_m_ = 0.0;
  /// Someone this search was given stands on the line of sight from p to the person at t seconds after the start.
  bool peopleOcclude(const Eigen::Vector3d& p, const Eigen::Vector3d& person_W_m, double t_s) const;
  std::array<bool, kMaxSearchPeople> avoided_{};  // per search: not already within the clearance of the start
  std::vector<Eigen::Vector3d> inputs_;
  std::vector<Node> nodes_;
  std::vector<int> table_;                  // node index per slot
  std::vector<std::uint32_t> table_stamp_;  // slot valid when equal to stamp_
  std::uint32_t stamp_ = 0;
  std::vector<OpenEntry> open_;
  std::vector<int> chain_;  // scratch for writePath
};

}  // namespace aerotrack::planning
