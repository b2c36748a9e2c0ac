// The search pattern of a relocation (issue 21 item 3): where can the lost person be, and where should the drone
// look from next. A belief over a horizontal grid of cells (cell_m) centred on the person's last accepted position:
//   - reach: the person walks at most max_person_speed_mps (or 1.2 x their last speed, if faster) since they were
//     lost, round obstacles: a cell counts only if its walking distance from the last position (8-connected
//     Dijkstra through cells with no raw-occupied map cell under them at 0.5 m or 1.1 m) is within that reach;
//   - bias: inside the reach, cells along the last velocity and at the distance it would have carried the person
//     weigh more: w = exp(kappa cos(bearing to the velocity)) exp(-(r - s)^2 / (2 sigma^2)), r the walking
//     distance, s = |v| t, sigma = max(1 m, s / 2), kappa = heading_concentration x min(|v| / 1 m/s, 1);
//   - seen: a cell in the camera's line of sight (LocalGrid DDA through raw-occupied cells, from the camera to the
//     cell's centre at the person's sight height) and range accumulates time in view; full_look_s of it (the
//     gimbal sweep's period: in that time the sweeping camera has turned past it) makes it seen. Its unseen mass is
//     w (1 - seen fraction), normalised so the reachable mass is 1.
// Viewpoints: candidates on rings (viewpoint_radii_m, viewpoint_bearings directions) round the unseen mass's
// centroid and the last position, at the flight altitude, free with clearance_m round them in the inflated grid;
// each scores the unseen mass it sees (in range, in line of sight) per second of getting there and looking
// (distance / travel_speed_mps + full_look_s); the best is kept until it is reached or reselect_s passes (a
// better one must beat it by 20 %). Viewpoints must be known free (the depth camera saw them: not the unknown inside
// of a building); one not reached within twice its travel time plus full_look_s is abandoned for good (the planner
// cannot get there). Pure: the grid, positions and the time come in; no allocation once started
// (storage is sized in create()). Not thread-safe (the planning task's thread).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "aerotrack/mapping/local_grid.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/field_table.hpp"
#include "aerotrack/rt/time.hpp"

namespace aerotrack::planning {

struct RelocationSearchParams {
  double cell_m = 0.5;                 ///< Belief cell edge; > 0.
  double max_radius_m = 12.0;          ///< The belief covers this far from the last position (a square); > cell_m.
  double max_person_speed_mps = 2.0;   ///< The fastest plausible walk (1.2 x the last speed if that is faster).
  double heading_concentration = 1.5;  ///< kappa at 1 m/s and above (0: no heading bias); >= 0.
  double camera_range_m = 8.0;         ///< The detector finds a person this far at most; > 0.
  double full_look_s = 3.0;            ///< In sight this long: seen (about one gimbal sweep); > 0.
  double clearance_m = 0.6;            ///< A viewpoint has this much free space round it (horizontally); >= 0.
  double travel_speed_mps = 1.5;       ///< For the score: the time to reach a viewpoint; > 0.
  double reselect_s = 1.0;             ///< Choose the viewpoint again at least this often; > 0.
  double reached_m = 0.5;              ///< Closer than this to the viewpoint: reached, choose again; > 0.
  int viewpoint_bearings = 12;         ///< Candidate directions per ring; >= 1.
  std::array<double, 3> viewpoint_radii_m = {2.0, 4.0, 6.0};  ///< Candidate rings (three); each > 0.
};

/// The `relocation:` config section of `planning:` (every key required).
const rt::FieldTable<RelocationSearchParams>& relocationSearchFields();
rt::Status validate(const RelocationSearchParams& params);

/// Cells with less unseen mass than this (of 1) are not looked at: the Gaussian's far tail, thousands of cells
/// whose lines of sight cost most of a viewpoint's score and add < 0.3 % of the mass in all.
inline constexpr double kNegligibleMass = 1e-6;

/// Where to fly and what to look at.
struct Viewpoint {
  Eigen::Vector3d p_W_m = Eigen::Vector3d::Zero();     ///< At the flight altitude.
  Eigen::Vector3d look_W_m = Eigen::Vector3d::Zero();  ///< The centroid of the unseen mass it sees (sight height).
  double mass = 0.0;                                   ///< The unseen mass it sees (of 1).
  double score = 0.0;                                  ///< mass per second (see above).
};

class RelocationSearch {
 public:
  /// sight_height_m: the person's torso centre (lines of sight end there); flight_altitude_m: the viewpoints'.
  static rt::Expected<RelocationSearch> create(const RelocationSearchParams& params, double sight_height_m,
                                               double flight_altitude_m);

  /// Begins a search for a person last seen at p_WT_m (W; z ignored) moving at v_WT_mps at lost_ns. Clears what
  /// was seen.
  void start(const Eigen::Vector3d& p_WT_m, const Eigen::Vector3d& v_WT_mps, rt::TimeNs lost_ns);
  void stop() { active_ = false; }
  bool active() const { return active_; }

  /// One cycle: the belief at now_ns (reach and weights in the newest grid), then the camera at p_WC_m looks for
  /// the time since the last call (at most 0.5 s). Returns the viewpoint to fly to (kept, or chosen again when
  /// reached, stale or beaten), or nothing when nothing unseen is visible from any free candidate.
  std::optional<Viewpoint> update(const mapping::LocalGrid& grid, const Eigen::Vector3d& p_WC_m, rt::TimeNs now_ns);

  // --- The steps of update(), exposed for tests. ---
  /// Reach (walking distance) and the normalised prior weight of every cell at now_ns.
  void updateBelief(const mapping::LocalGrid& grid, rt::TimeNs now_ns);
  /// The camera at p_WC_m looks for dt_s: every cell with weight in range and in sight gains dt_s of view.
  void look(const mapping::LocalGrid& grid, const Eigen::Vector3d& p_WC_m, double dt_s);
  /// The unseen mass a camera at p_WC_m would see, and its centroid (sight height) in look_W_m.
  double visibleMass(const mapping::LocalGrid& grid, const Eigen::Vector3d& p_WC_m, Eigen::Vector3d& look_W_m) const;
  /// The candidate viewpoints round `centre_W_m` (flight altitude), free ones only, into candidates(). Free: known
  /// free, or unknown in plain sight of the drone at p_WB_m (no mapped surface between them), and clear all round.
  void makeCandidates(const mapping::LocalGrid& grid, const Eigen::Vector3d& centre_W_m, const Eigen::Vector3d& p_WB_m);
  /// The best candidate for a drone at p_WB_m (nothing if none sees unseen mass).
  std::optional<Viewpoint> bestViewpoint(const mapping::LocalGrid& grid, const Eigen::Vector3d& p_WB_m) const;

  const std::vector<Eigen::Vector3d>& candidates() const { return candidates_; }
  int cellsPerSide() const { return side_; }
  std::size_t cellCount() const { return weight_.size(); }
  Eigen::Vector3d cellCenterM(std::size_t cell) const;             ///< At the sight height.
  double weight(std::size_t cell) const { return weight_[cell]; }  ///< Normalised prior (sums to 1, or all 0).
  double seenFraction(std::size_t cell) const;
  double unseenMass(std::size_t cell) const { return weight_[cell] * (1.0 - seenFraction(cell)); }
  double totalUnseenMass() const;
  double walkingDistanceM(std::size_t cell) const { return distance_m_[cell]; }  ///< Infinity: unreachable.
  double reachM() const { return reach_m_; }
  const Eigen::Vector3d& lastPositionM() const { return p_last_W_m_; }
  const RelocationSearchParams& params() const { return params_; }

 private:
  RelocationSearch(const RelocationSearchParams& params, double sight_height_m, double flight_altitude_m);
  bool cellBlocked(const mapping::LocalGrid& grid, const Eigen::Vector3d& centre_W_m) const;
  bool viewpointFree(const mapping::LocalGrid& grid, const Eigen::Vector3d& p_W_m, const Eigen::Vector3d& p_WB_m) const;
  Eigen::Vector3d unseenCentroid() const;

  RelocationSearchParams params_;
  double sight_height_m_;
  double flight_altitude_m_;
  int side_ = 0;
  /// The index of cell (x, y) in the row-major arrays (x, y in [0, side_)).
  std::size_t cellAt(int x, int y) const {
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(side_) + static_cast<std::size_t>(x);
  }
  bool active_ = false;
  Eigen::Vector3d p_last_W_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_last_W_mps_ = Eigen::Vector3d::Zero();
  rt::TimeNs lost_ns_ = 0;
  rt::TimeNs last_update_ns_ = -1;
  double reach_m_ = 0.0;
  std::vector<double> weight_;
  std::vector<double> seen_s_;
  std::vector<double> distance_m_;
  std::vector<std::uint8_t> blocked_;
  std::vector<std::pair<double, int>> heap_;  ///< Dijkstra's queue (reserved).
  std::vector<Eigen::Vector3d> candidates_;
  std::optional<Viewpoint> current_;
  rt::TimeNs chosen_ns_ = 0;
  rt::TimeNs heading_since_ns_ = 0;  ///< When the current viewpoint was first chosen.
  double give_up_s_ = 0.0;           ///< Not reached by then: abandoned.
  /// The last viewpoints abandoned (NaN: none); candidates within reached_m of them are not chosen again.
  std::array<Eigen::Vector3d, 8> abandoned_W_m_{};
  std::size_t abandoned_next_ = 0;
};

}  // namespace aerotrack::planning
