// The flight corridor: box inflation along the search path's cell walk (see corridor.hpp; paper Sect. V-C).
#include "aerotrack/planning/corridor.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <limits>
#include <string>

namespace aerotrack::planning {
namespace {

using mapping::CellBox;
using mapping::CellIndex;
using mapping::LocalGrid;

constexpr double kInf = std::numeric_limits<double>::infinity();
// Crossings of two cell planes this close (metres along the chord's first axis) count as one corner
// crossing even with corner_tolerance_m 0: the walk may step either axis first.
constexpr double kTieM = 1e-9;

// The same expression as LocalGrid::cellCenterM (inlined: it runs for every row of every layer).
Eigen::Vector3d cellCenter(const CellIndex& cell, double resolution_m) {
  return (cell.cast<double>().array() + 0.5) * resolution_m;
}

bool cellBlocked(const LocalGrid& grid, const CellIndex& cell, double resolution_m) {
  return !grid.cellInWindow(cell) || grid.isOccupied(cellCenter(cell, resolution_m));
}

std::string formatPoint(const Eigen::Vector3d& p) {
  char text[96];
  std::snprintf(text, sizeof(text), "(%.2f, %.2f, %.2f)", p.x(), p.y(), p.z());
  return text;
}

// The row period P of the sparse layer check (see corridor.hpp): the shortest run, along any axis, of the
// cells within the inflation radius of an occupied voxel (a ball of radius rho = inflation_radius_m /
// resolution_m cells, rho^2 >= a^2 + b^2 + c^2 for offsets (a, b, c)): P = min over columns (a, b) of
// 2 floor(sqrt(rho^2 - a^2 - b^2)) + 1. The columns are taken from a slightly larger ball and the runs from a
// slightly smaller one, so rounding of the grid's own stencil can only make P smaller (safe). 1 (every row)
// when unknown cells block, since one unknown cell is blocked on its own.
int sparsePeriod(const mapping::LocalGridParams& params) {
  if (params.unknown_is_occupied) return 1;
  const double rho = params.inflation_radius_m / params.resolution_m;
  const double outer2 = rho * rho + 1e-6;
  const double inner2 = rho * rho - 1e-6;
  const int reach = static_cast<int>(std::floor(std::sqrt(outer2)));
  int period = std::numeric_limits<int>::max();
  for (int a = 0; a <= reach; ++a) {
    for (int b = 0; b <= reach; ++b) {
      if (a * a + b * b > outer2) continue;
      const double rest = inner2 - a * a - b * b;
      const int run = rest < 0.0 ? 0 : 2 * static_cast<int>(std::floor(std::sqrt(rest))) + 1;
      period = std::min(period, run);
    }
  }
  return std::max(1, period);
}

// Whether cells [lo, hi) along row_axis, through `first` (its row_axis coordinate is ignored), are all
// unblocked: LocalGrid::segmentFree from the centre of the first cell to the centre of the last (an
// axis-aligned DDA over exactly these cells, stopping at the first blocked one).
bool rowFree(const LocalGrid& grid, CellIndex first, int row_axis, int lo, int hi, double resolution_m) {
  first[row_axis] = lo;
  const Eigen::Vector3d a = cellCenter(first, resolution_m);
  if (hi - lo == 1) return !grid.isOccupied(a);
  first[row_axis] = hi - 1;
  return grid.segmentFree(a, cellCenter(first, resolution_m));
}

// Whether the layer `layer` (a box one cell thick across thin_axis, inside the window) has no blocked cell,
// given that the box it was grown from is free (see corridor.hpp): rows along the layer's longer in-plane
// axis, every period-th row across the shorter one and the last row, each less its part inside known_free
// (a box whose cells are all free; may be null).
bool layerCellsFree(const LocalGrid& grid, const CellBox& layer, int thin_axis, int period, const CellBox* known_free,
                    double resolution_m) {
  const CellIndex extent = layer.hi - layer.lo;
  int row_axis = (thin_axis + 1) % 3;
  int across_axis = (thin_axis + 2) % 3;
  if (extent[across_axis] > extent[row_axis]) std::swap(row_axis, across_axis);
  const int row_lo = layer.lo[row_axis];
  const int row_hi = layer.hi[row_axis];
  // Rows of the layer that cross `known_free` need only their parts outside it.
  const bool overlaps = known_free != nullptr && layer.lo[thin_axis] >= known_free->lo[thin_axis] &&
                        layer.lo[thin_axis] < known_free->hi[thin_axis] && known_free->lo[row_axis] < row_hi &&
                        known_free->hi[row_axis] > row_lo;
  CellIndex first = layer.lo;
  const int end = layer.hi[across_axis];
  for (int i = layer.lo[across_axis]; i < end; i = (i + period < end || i == end - 1) ? i + period : end - 1) {
    first[across_axis] = i;
    if (overlaps && i >= known_free->lo[across_axis] && i < known_free->hi[across_axis]) {
      const int skip_lo = std::max(row_lo, known_free->lo[row_axis]);
      const int skip_hi = std::min(row_hi, known_free->hi[row_axis]);
      if (skip_lo > row_lo && !rowFree(grid, first, row_axis, row_lo, skip_lo, resolution_m)) return false;
      if (skip_hi < row_hi && !rowFree(grid, first, row_axis, skip_hi, row_hi, resolution_m)) return false;
      continue;
    }
    if (!rowFree(grid, first, row_axis, row_lo, row_hi, resolution_m)) return false;
  }
  return true;
}

}  // namespace

const rt::FieldTable<CorridorParams>& corridorFields() {
  using P = CorridorParams;
  using rt::Range;
  static const rt::FieldTable<P> kTable({
      rt::numberList("max_box_size_m", &P::max_box_size_m, 3, Range::closed(0.01, 100.0)),
      rt::integer("max_boxes", &P::max_boxes, 1, 10'000),
      rt::integer("max_path_cells", &P::max_path_cells, 1, 10'000'000),
      rt::number("corner_tolerance_m", &P::corner_tolerance_m, Range::closed(0.0, 0.05)),
  });
  return kTable;
}

rt::Status validate(const CorridorParams& params) {
  return corridorFields().validate(params);
}

CorridorParams parseCorridorParams(const rt::ConfigNode& node) {
  return corridorFields().parse(node);
}

rt::Expected<CorridorBuilder> CorridorBuilder::create(const CorridorParams& params) {
  if (rt::Status status = validate(params); !status) return rt::Error{"corridor: " + status.error().message};
  return CorridorBuilder(params);
}

CorridorBuilder::CorridorBuilder(const CorridorParams& params) : params_(params) {
  walk_.reserve(static_cast<std::size_t>(params.max_path_cells));
  walk_point_.reserve(static_cast<std::size_t>(params.max_path_cells));
  boxes_.reserve(static_cast<std::size_t>(params.max_boxes));
  box_first_.reserve(static_cast<std::size_t>(params.max_boxes));
}

rt::Status CorridorBuilder::walkPath(const LocalGrid& grid, std::span<const Eigen::Vector3d> path_W_m) {
  walk_.clear();
  walk_point_.clear();
  const double resolution_m = grid.params().resolution_m;
  const double inv_resolution_per_m = 1.0 / resolution_m;
  for (std::size_t k = 0; k < path_W_m.size(); ++k) {
    if (!path_W_m[k].allFinite()) return rt::Error{"corridor: path point " + std::to_string(k) + " is not finite"};
  }
  CellIndex cell = grid.cellIndex(path_W_m[0]);
  if (!grid.cellInWindow(cell)) {
    return rt::Error{"corridor: the path start " + formatPoint(path_W_m[0]) + " is outside the grid window"};
  }
  if (grid.isOccupied(cellCenter(cell, resolution_m))) {
    return rt::Error{"corridor: the path start " + formatPoint(path_W_m[0]) + " is in a blocked cell"};
  }
  walk_.push_back(cell);
  walk_point_.push_back(0);
  for (std::size_t k = 1; k < path_W_m.size(); ++k) {
    const CellIndex end = grid.cellIndex(path_W_m[k]);
    // The window is a box: a chord between two cells inside it only visits cells inside it.
    if (!grid.cellInWindow(end)) {
      return rt::Error{"corridor: path point " + std::to_string(k) + " " + formatPoint(path_W_m[k]) +
                       " is outside the grid window"};
    }
    // 3D DDA in cell units: each axis takes exactly |end - start| unit steps, in the order in which the
    // chord crosses the cell planes, so the walk stays face-connected and ends in the end point's cell.
    const Eigen::Vector3d a = path_W_m[k - 1] * inv_resolution_per_m;
    const Eigen::Vector3d d = path_W_m[k] * inv_resolution_per_m - a;
    const double max_rate_cells = d.cwiseAbs().maxCoeff();  // cells per unit of t, on the fastest axis
    int remaining[3];
    int step[3];
    double t_max[3];
    double t_delta[3];
    int total = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const int delta = end[axis] - cell[axis];
      step[axis] = delta > 0 ? 1 : -1;
      remaining[axis] = std::abs(delta);
      total += remaining[axis];
      if (remaining[axis] == 0) {
        t_max[axis] = kInf;
        t_delta[axis] = kInf;
      } else if (d[axis] == 0.0) {  // not reachable (floor is monotonic); step at once rather than never
        t_max[axis] = 0.0;
        t_delta[axis] = 0.0;
      } else {
        const double boundary = cell[axis] + (step[axis] > 0 ? 1 : 0);
        t_max[axis] = (boundary - a[axis]) / d[axis];
        t_delta[axis] = 1.0 / std::abs(d[axis]);
      }
    }
    for (; total > 0; --total) {
      int axis = 0;
      if (t_max[1] < t_max[axis]) axis = 1;
      if (t_max[2] < t_max[axis]) axis = 2;
      CellIndex next = cell;
      next[axis] += step[axis];
      bool blocked = cellBlocked(grid, next, resolution_m);
      // Round a blocked cell whose corner the chord only cuts: step first along an axis whose plane the chord
      // crosses at most slack_t later, if that cell is free. A chord point then lies outside the walk's cells
      // only while some plane it has crossed is not yet stepped, which is less than slack_t after that plane
      // (an early step comes at most slack_t after the earliest plane not yet stepped), so by less than
      // slack_t * max |d| cells on each axis: corner_tolerance_m.
      const double slack_t = (params_.corner_tolerance_m + kTieM) / (max_rate_cells * resolution_m);
      for (int other = 0; blocked && other < 3; ++other) {
        if (other == axis || remaining[other] == 0 || t_max[other] > t_max[axis] + slack_t) continue;
        CellIndex alternative = cell;
        alternative[other] += step[other];
        if (!cellBlocked(grid, alternative, resolution_m)) {
          axis = other;
          next = alternative;
          blocked = false;
        }
      }
      t_max[axis] = --remaining[axis] == 0 ? kInf : t_max[axis] + t_delta[axis];
      cell = next;
      if (blocked) {
        return rt::Error{"corridor: the path between points " + std::to_string(k - 1) + " and " + std::to_string(k) +
                         " crosses the blocked cell at " + formatPoint(cellCenter(cell, resolution_m))};
      }
      if (walk_.size() >= static_cast<std::size_t>(params_.max_path_cells)) {
        return rt::Error{"corridor: the path crosses more than " + std::to_string(params_.max_path_cells) +
                         " grid cells (max_path_cells)"};
      }
      walk_.push_back(cell);
      walk_point_.push_back(static_cast<int>(k) - 1);
    }
    walk_point_.back() = static_cast<int>(k);  // the end cell holds point k (also when the chord stays in a cell)
  }
  return rt::ok();
}

int CorridorBuilder::room(const LocalGrid& grid, const CellBox& box, int axis, bool upper) const {
  const int cap = max_box_cells_[axis] - (box.hi[axis] - box.lo[axis]);
  const int window = upper ? grid.windowMinCell()[axis] + grid.windowSizeCells()[axis] - box.hi[axis]
                           : box.lo[axis] - grid.windowMinCell()[axis];
  const int band = axis != 2 ? window : upper ? band_hi_cell_ - box.hi[axis] : box.lo[axis] - band_lo_cell_;
  return std::min({cap, window, band});
}

bool CorridorBuilder::slabFree(const LocalGrid& grid, const CellBox& box, int axis, bool upper, int depth) const {
  CellBox layer = box;
  if (upper) {
    layer.lo[axis] = box.hi[axis] + depth - 1;
    layer.hi[axis] = layer.lo[axis] + 1;
  } else {
    layer.hi[axis] = box.lo[axis] - depth + 1;
    layer.lo[axis] = layer.hi[axis] - 1;
  }
  const CellBox* known_free = boxes_.empty() ? nullptr : &boxes_.back();
  return layerCellsFree(grid, layer, axis, period_, known_free, grid.params().resolution_m);
}

CellBox CorridorBuilder::growBox(const LocalGrid& grid, int first, int seed_cells) const {
  const auto first_index = static_cast<std::size_t>(first);
  CellBox box{walk_[first_index], walk_[first_index] + CellIndex::Ones()};
  if (seed_cells == 2) {
    box.lo = box.lo.cwiseMin(walk_[first_index + 1]);
    box.hi = box.hi.cwiseMax(walk_[first_index + 1] + CellIndex::Ones());
  }
  // Follow the walk: each next cell outside the box is face-adjacent to the previous one, which is inside,
  // so it lies one layer beyond exactly one face.
  for (std::size_t n = first_index + static_cast<std::size_t>(seed_cells); n < walk_.size(); ++n) {
    const CellIndex& cell = walk_[n];
    if (box.contains(cell)) continue;
    int axis = 0;
    while (cell[axis] >= box.lo[axis] && cell[axis] < box.hi[axis]) ++axis;
    const bool upper = cell[axis] >= box.hi[axis];
    if (room(grid, box, axis, upper) < 1 || !slabFree(grid, box, axis, upper, 1)) break;
    if (upper) {
      ++box.hi[axis];
    } else {
      --box.lo[axis];
    }
  }
  // Inflate: round-robin over the faces -x, +x, -y, +y, -z, +z. A face moves out by up to `period` layers at
  // once (only the farthest is checked: see corridor.hpp); after a failed multi-layer step it moves one layer
  // at a time, and after a failed single layer it is done (a blocked layer stays blocked as the box grows,
  // and so do the cap and the window).
  int step[6];
  std::fill(std::begin(step), std::end(step), period_);
  for (bool any = true; any;) {
    any = false;
    for (int face = 0; face < 6; ++face) {
      if (step[face] == 0) continue;
      const int axis = face / 2;
      const bool upper = face % 2 == 1;
      const int depth = std::min(step[face], room(grid, box, axis, upper));
      if (depth < 1) {
        step[face] = 0;
        continue;
      }
      any = true;
      if (!slabFree(grid, box, axis, upper, depth)) {
        step[face] = depth > 1 ? 1 : 0;
        continue;
      }
      if (upper) {
        box.hi[axis] += depth;
      } else {
        box.lo[axis] -= depth;
      }
    }
  }
  return box;
}

int CorridorBuilder::runStartIn(const CellBox& box, int last) const {
  int n = last;
  while (n > 0 && box.contains(walk_[static_cast<std::size_t>(n - 1)])) --n;
  return n;
}

int CorridorBuilder::runEndIn(const CellBox& box, int first, int cap) const {
  int n = first;
  while (n < cap && box.contains(walk_[static_cast<std::size_t>(n) + 1])) ++n;
  return n;
}

rt::Status CorridorBuilder::build(const LocalGrid& grid, std::span<const Eigen::Vector3d> path_W_m, Corridor& out) {
  out.boxes.clear();
  out.waypoints_W_m.clear();
  out.waypoint_path_index.clear();
  // Capacity for the most boxes a build can return: a reused Corridor allocates only in its first build.
  out.boxes.reserve(static_cast<std::size_t>(params_.max_boxes));
  out.waypoints_W_m.reserve(static_cast<std::size_t>(params_.max_boxes));
  out.waypoint_path_index.reserve(static_cast<std::size_t>(params_.max_boxes));
  if (path_W_m.empty()) return rt::Error{"corridor: empty path"};
  const double resolution_m = grid.params().resolution_m;
  for (int axis = 0; axis < 3; ++axis) {
    const double cells = std::floor(params_.max_box_size_m[axis] / resolution_m + 1e-9);
    max_box_cells_[axis] = static_cast<int>(std::min(cells, 1e6));  // wider than any window
  }
  period_ = sparsePeriod(grid.params());
  if ((max_box_cells_.array() < 2).any()) {
    char text[128];
    std::snprintf(text, sizeof(text), "corridor: max_box_size_m must be at least two grid cells (%g m) on every axis",
                  2.0 * resolution_m);
    return rt::Error{text};
  }
  if (rt::Status walked = walkPath(grid, path_W_m); !walked) return walked;

  const int cells = static_cast<int>(walk_.size());
  // The altitude band in cells (a cell belongs when it holds a height in the band), widened to the walk.
  constexpr int kUnbounded = 1 << 29;
  const auto bandCell = [resolution_m](double z_m, int unbounded) {
    return std::isfinite(z_m) ? static_cast<int>(std::clamp(std::floor(z_m / resolution_m), -1e9, 1e9)) : unbounded;
  };
  band_lo_cell_ = bandCell(min_z_m_, -kUnbounded);
  band_hi_cell_ = bandCell(max_z_m_, kUnbounded - 1) + 1;
  for (const mapping::CellIndex& cell : walk_) {
    band_lo_cell_ = std::min(band_lo_cell_, cell.z());
    band_hi_cell_ = std::max(band_hi_cell_, cell.z() + 1);
  }
  boxes_.clear();
  box_first_.clear();
  boxes_.push_back(growBox(grid, 0, 1));
  box_first_.push_back(0);
  for (int j = 1; j < cells; ++j) {
    if (boxes_.back().contains(walk_[static_cast<std::size_t>(j)])) continue;
    // The walk leaves the current box at c_j: seed the next box with {c_{j-1}, c_j}.
    const CellBox next = growBox(grid, j - 1, 2);
    const int next_start = runStartIn(next, j);  // the walk [next_start, j] lies in `next`
    // Pruning: the current box is redundant when the one before it can hand over to `next` directly (the
    // walk from where that box took over up to some cell lies in it, and from that cell to c_j in `next`).
    while (true) {
      if (boxes_.size() == 1) {
        if (next_start == 0) {  // `next` holds the whole walk so far: it becomes box 0
          boxes_.pop_back();
          box_first_.pop_back();
        }
        break;
      }
      const std::size_t before = boxes_.size() - 2;
      if (next_start > runEndIn(boxes_[before], box_first_[before], j)) break;
      boxes_.pop_back();
      box_first_.pop_back();
    }
    if (boxes_.empty()) {
      boxes_.push_back(next);
      box_first_.push_back(0);
      continue;
    }
    // The hand-over cell: the walk up to it lies in the current box, and from it to c_j in `next`. Of the
    // candidates (there is one: c_{j-1}, or the cell found by the pruning), take the deepest inside the
    // intersection, the later one on ties. It comes after the current box's own hand-over cell, since
    // otherwise the pruning would have removed the current box.
    const CellBox& current = boxes_.back();
    const int lo = std::max(box_first_.back(), next_start);
    const int hi = std::min(runEndIn(current, box_first_.back(), j), j);
    const CellIndex overlap_lo = current.lo.cwiseMax(next.lo);
    const CellIndex overlap_hi = current.hi.cwiseMin(next.hi);
    int hand_over = hi;
    int best_depth = -1;
    for (int n = hi; n >= lo; --n) {
      const CellIndex& cell = walk_[static_cast<std::size_t>(n)];
      const int depth = std::min((cell - overlap_lo).minCoeff(), (overlap_hi - CellIndex::Ones() - cell).minCoeff());
      if (depth > best_depth) {
        best_depth = depth;
        hand_over = n;
      }
    }
    if (boxes_.size() >= static_cast<std::size_t>(params_.max_boxes)) {
      return rt::Error{"corridor: the path needs more than " + std::to_string(params_.max_boxes) +
                       " boxes (max_boxes): too long or too twisty"};
    }
    boxes_.push_back(next);
    box_first_.push_back(hand_over);
  }

  for (std::size_t i = 0; i < boxes_.size(); ++i) {
    const CellBox& box = boxes_[i];
    out.boxes.push_back(CorridorBox{box.lo.cast<double>() * resolution_m, box.hi.cast<double>() * resolution_m, box});
    if (i == 0) continue;
    const auto cell = static_cast<std::size_t>(box_first_[i]);
    out.waypoints_W_m.push_back(cellCenter(walk_[cell], resolution_m));
    out.waypoint_path_index.push_back(walk_point_[cell]);
  }
  return rt::ok();
}

}  // namespace aerotrack::planning
