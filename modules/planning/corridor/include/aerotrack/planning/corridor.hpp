// The flight corridor F = C_1 u ... u C_M of the paper (Sect. V-C): overlapping axis-aligned boxes
// C_i = {x | A_i x <= b_i} grown in the inflated occupancy grid along the kinodynamic search's path, with
// one waypoint q_w_i strictly inside each intersection C_i n C_{i+1} for the back-end optimiser (its
// barrier J_F keeps q_w_i there). The method is the box inflation of Chen, Liu and Shen, "Online
// generation of collision-free trajectories for quadrotor flight in unknown cluttered environments"
// (ICRA 2016), with the redundancy pruning of Gao, Wu, Lin and Shen, "Online safe trajectory generation
// for quadrotors using fast marching method and Bernstein basis polynomial" (ICRA 2018):
//  1. Walk: the polyline is turned into a face-connected sequence of grid cells c_0 .. c_{L-1} by a 3D DDA
//     (Amanatides & Woo 1987) along each chord, so every point of every chord lies in (the closure of)
//     a walk cell. Every walk cell must be unblocked (in the window and not LocalGrid::isOccupied). Where a
//     chord only cuts the corner of a blocked cell (by corner_tolerance_m at most), the walk goes round it
//     through the free neighbour, and those chord points lie within that distance of the walk's cells.
//  2. Boxes: box 0 is seeded with c_0; when the walk leaves the current box at c_j, the next box is seeded
//     with the two face-adjacent cells {c_{j-1}, c_j} (c_{j-1} is in the current box, so consecutive boxes
//     share at least one whole free cell). A seed first follows the walk (the box is stretched, one cell
//     layer at a time, to the bounding box of the next walk cells while that layer is free and the edge
//     cap allows), then is inflated: round-robin over the 6 faces, each face is pushed out while the new
//     cells are free, inside the window and within max_box_size_m; a face that fails stops for good
//     (blocked cells, the cap and the window stay in the way as the box grows).
//     Checking cells is most of the cost, and most cells need not be looked at: a cell is blocked exactly
//     when an occupied voxel lies within the inflation radius (LocalGrid::isOccupied with
//     unknown_is_occupied false), so the blocked cells are a union of balls of rho = inflation_radius_m /
//     resolution_m cells, and every line of cells parallel to an axis meets a ball in a run of at least P
//     cells (P = 3 for the drone's 0.25 m at 0.1 m; P = 1, everything checked, when unknown cells block or
//     rho is too small). Hence (a) in a layer, checking every P-th row and the last row finds any blocked
//     cell of the layer (a ball's run across the rows contains a checked row, or is cut by the layer's edge
//     and contains its first or last row), and (b) beyond a free box, the first blocked cell of the next k
//     <= P layers shows in the k-th (a ball's run along the growth axis starts beyond the free box and is at
//     least P long). A face is therefore pushed out P layers at a time, checking only the farthest layer's
//     every P-th row (about P^2 = 9 times fewer cells), then one layer at a time once that fails. Each row
//     is checked by LocalGrid::segmentFree (an axis-aligned DDA over raw cell words, stopping at the first
//     blocked cell), less its part inside the previous box (known free). The unit tests check every cell of
//     every box.
//  3. Pruning: a new box that can take over from its predecessor (some walk cell lies in the box before
//     the predecessor, with the walk from there to c_j inside the new box) replaces it, repeatedly.
//  4. Waypoints: between boxes i and i+1 the waypoint is the centre of a walk cell lying in both (with
//     the walk before it in box i and after it, up to where box i+1 was seeded, in box i+1); among such
//     cells the one deepest inside the intersection is taken. Being a whole cell of both boxes, it is at
//     least half a cell from every face of the intersection.
// Cost per build: O(walk cells + sum of the box volumes in cells); no allocation once warm.
#pragma once

#include <limits>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "aerotrack/mapping/local_grid.hpp"
#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/field_table.hpp"

namespace aerotrack::planning {

/// One box of the corridor, aligned with the grid's cells. Bounds in W, metres: lo_W_m = cells.lo *
/// resolution, hi_W_m = cells.hi * resolution (products, so a point lying exactly on a face can test
/// outside by one rounding step: use a margin of about -1e-9 m to test boundary points).
struct CorridorBox {
  Eigen::Vector3d lo_W_m = Eigen::Vector3d::Zero();  ///< Minimum corner (W, m).
  Eigen::Vector3d hi_W_m = Eigen::Vector3d::Zero();  ///< Maximum corner (W, m).
  mapping::CellBox cells;                            ///< The same box as global cell indices [lo, hi).

  /// Whether lo_W_m + margin_m <= p_W_m <= hi_W_m - margin_m on every axis (margin_m may be negative).
  /// In A x <= b form: A = [I; -I], b = [hi_W_m; -lo_W_m].
  bool contains(const Eigen::Vector3d& p_W_m, double margin_m = 0.0) const {
    return (p_W_m.array() >= lo_W_m.array() + margin_m).all() && (p_W_m.array() <= hi_W_m.array() - margin_m).all();
  }
};

struct CorridorParams {
  /// Cap on each box's edge per axis (whole cells of it are used); > 0, and at least two grid cells per axis
  /// (checked in build).
  Eigen::Vector3d max_box_size_m{3.0, 3.0, 2.0};
  /// More boxes needed: error (path too long or too twisty); >= 1.
  int max_boxes = 24;
  /// Cap on the cells of the polyline's walk through the grid (1 to 1.7 cells per resolution of path length):
  /// more is an error; scratch memory for them is allocated in create(); >= 1.
  int max_path_cells = 4096;
  /// A chord may cut the corner (or edge) of a blocked cell by this much: the walk goes round through the free
  /// neighbour, and the chord's points there lie this close to the boxes (on every axis) instead of in them.
  /// The search's curves stray up to 1 mm from the chords it checked, so polylines sampled from them can cut
  /// corners by that much. 0: every chord point in the boxes. In [0, 0.05].
  double corner_tolerance_m = 0.002;
};

/// The `corridor:` config section (max_box_size_m: [x, y, z], max_boxes, max_path_cells, corner_tolerance_m; all
/// required), with the one range per field that parsing, validate() and printing share (rt/field_table.hpp).
const rt::FieldTable<CorridorParams>& corridorFields();

/// Success when every field is in its range (corridorFields()), else an Error naming the field.
rt::Status validate(const CorridorParams& params);

/// corridorFields().parse: reads every key of a `corridor:` section and calls finish(). Throws rt::ConfigError
/// (file:line: key: message) on a missing, unknown or out-of-range key (use rt::parseConfig at the boundary).
CorridorParams parseCorridorParams(const rt::ConfigNode& node);

/// The corridor of one path: M >= 1 boxes and M - 1 waypoints.
struct Corridor {
  /// M boxes in path order; the path start is in boxes.front(), the end in boxes.back(). Every cell of every
  /// box is unblocked in the grid.
  std::vector<CorridorBox> boxes;
  /// M - 1 points (W, m); waypoint i is the centre of a path cell in boxes[i] n boxes[i+1], so at least half a
  /// cell from every face of that intersection.
  std::vector<Eigen::Vector3d> waypoints_W_m;
  /// M - 1 polyline indices, non-decreasing: waypoint i is the centre of a cell that the chord from point
  /// waypoint_path_index[i] to the next passes through (or that holds the point). The polyline points with
  /// index in (waypoint_path_index[i-1], waypoint_path_index[i]] lie in boxes[i] (from 0 for box 0, to the
  /// end for the last box), and so do the chords between them (up to corner_tolerance_m).
  std::vector<int> waypoint_path_index;
};

/// Builds corridors, with its scratch memory (the path's cell walk, the boxes) allocated once in create()
/// and reused: a build() into a reused Corridor allocates nothing once the Corridor's vectors have grown
/// (except to format an error message). Not thread-safe: one instance per thread. Copyable and movable.
class CorridorBuilder {
 public:
  /// Validates params (validate()) and allocates the scratch memory.
  static rt::Expected<CorridorBuilder> create(const CorridorParams& params);

  const CorridorParams& params() const { return params_; }
  /// Boxes grow in W z only across the cells that hold heights in [min_z_m, max_z_m], widened to the path's
  /// own cells (default: unbounded). The search's altitude band (KinodynamicSearch::setAltitudeBand): a box
  /// reaching below it would let the optimiser take the path back down where the search may not go.
  void setAltitudeBand(double min_z_m, double max_z_m) {
    min_z_m_ = min_z_m;
    max_z_m_ = max_z_m;
  }

  /// Builds the corridor of the polyline path_W_m (points in W, metres: the search's path sampled densely,
  /// consecutive points joined by straight chords) in `grid` (a cell is blocked when outside the window or
  /// LocalGrid::isOccupied at its centre: inflation and the unknown policy apply). Guarantees (see
  /// Corridor): every point of the polyline lies in the boxes, and every point of its chords too (or within
  /// corner_tolerance_m of them where a chord cuts a blocked cell's corner), in order; consecutive
  /// boxes share at least one whole free cell, where their waypoint lies; no box has a blocked cell; no
  /// edge exceeds max_box_size_m. Writes `out` (cleared first; its vectors keep their capacity) on success;
  /// on error `out` is left empty. Errors (one line): empty path, non-finite point, start cell blocked or
  /// outside the window, a path cell blocked or outside the window, max_box_size_m under two cells per
  /// axis, more than max_path_cells walk cells, more than max_boxes boxes. No clock is read. Cost
  /// O(walk cells * boxes + box volumes in cells).
  rt::Status build(const mapping::LocalGrid& grid, std::span<const Eigen::Vector3d> path_W_m, Corridor& out);

 private:
  explicit CorridorBuilder(const CorridorParams& params);

  rt::Status walkPath(const mapping::LocalGrid& grid, std::span<const Eigen::Vector3d> path_W_m);
  /// Grows a box seeded with walk cells [first, first + seed_cells) (1 or 2 cells): follows the walk from
  /// first + seed_cells, then inflates. Returns the box.
  mapping::CellBox growBox(const mapping::LocalGrid& grid, int first, int seed_cells) const;
  /// Layers the box may still grow by beyond one face: the smaller of the cap and the window.
  int room(const mapping::LocalGrid& grid, const mapping::CellBox& box, int axis, bool upper) const;
  /// Whether the `depth` (1 .. period_) layers beyond one face of the free `box` are free: checks the last
  /// (sparsely), skipping cells inside boxes_.back() (free).
  bool slabFree(const mapping::LocalGrid& grid, const mapping::CellBox& box, int axis, bool upper, int depth) const;
  /// First walk index n <= last with walk cells [n, last] all in box.
  int runStartIn(const mapping::CellBox& box, int last) const;
  /// Last walk index n >= first (at most cap) with walk cells [first, n] all in box.
  int runEndIn(const mapping::CellBox& box, int first, int cap) const;

  CorridorParams params_;
  double min_z_m_ = -std::numeric_limits<double>::infinity();  // setAltitudeBand
  double max_z_m_ = std::numeric_limits<double>::infinity();
  int band_lo_cell_ = 0;  // per build: the band's lowest z cell and one past its highest, widened to the walk
  int band_hi_cell_ = 0;
  mapping::CellIndex max_box_cells_ = mapping::CellIndex::Zero();  // per build, from the grid's resolution
  int period_ = 1;                                                 // per build: the sparse check's row period
  std::vector<mapping::CellIndex> walk_;                           // c_0 .. c_{L-1}
  std::vector<int> walk_point_;  // per walk cell: the last polyline index whose point is at or before it
  std::vector<mapping::CellBox> boxes_;
  std::vector<int> box_first_;  // walk index of the cell where each box takes over (0 for box 0)
};

}  // namespace aerotrack::planning
