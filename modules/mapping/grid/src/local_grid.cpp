// LocalGrid implementation: parameter validation and stencil construction, the ring-buffer storage
// (slot = (cell - storage_min_cell + storage_min_slot) mod dims per axis, x fastest), incremental
// inflation (add or subtract the sphere stencil when a voxel's occupancy flips), synchronisation with
// OctoMap (changed keys, leaf bounding-box iteration with coarse leaves expanded) and the 3D DDA of
// Amanatides & Woo (1987) on the segment clipped to the window.
#include "aerotrack/mapping/local_grid.hpp"

#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace aerotrack::mapping {
namespace {

constexpr int kKeyOffset = 32768;  // OctoMap's tree_max_val at depth 16: key = cell + 32768
constexpr int kMinCell = -kKeyOffset;
constexpr int kMaxCell = kKeyOffset - 1;
constexpr int kTreeDepth = 16;
constexpr std::int64_t kMaxStorageCells = std::int64_t{1} << 28;
constexpr int kMaxStencilSize = 0xFFFF >> 2;  // the 14-bit count must not overflow
constexpr double kInf = std::numeric_limits<double>::infinity();

std::string num(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%g", value);
  return buffer;
}

rt::Error paramError(const std::string& field, const std::string& what) {
  return rt::Error{"local_grid." + field + ": " + what};
}

int wrapIndex(int index, int size) {
  const int r = index % size;
  return r < 0 ? r + size : r;
}

// The segment's end points and its extent in cell units are finite (else the DDA's arithmetic is not).
bool finiteSegment(const Eigen::Vector3d& a_W_m, const Eigen::Vector3d& b_W_m, double inv_resolution_per_m) {
  return (a_W_m * inv_resolution_per_m).allFinite() && (b_W_m * inv_resolution_per_m).allFinite() &&
         (b_W_m * inv_resolution_per_m - a_W_m * inv_resolution_per_m).allFinite();
}

CellBox intersect(const CellBox& a, const CellBox& b) {
  return {a.lo.cwiseMax(b.lo), a.hi.cwiseMin(b.hi)};
}

// Calls f(box) for disjoint boxes whose union is outer \ inner (inner inside outer, or empty).
template <class F>
void forEachBoxInDifference(const CellBox& outer, const CellBox& inner, const F& f) {
  if (inner.empty()) {
    f(outer);
    return;
  }
  CellBox rest = outer;
  for (int axis = 0; axis < 3; ++axis) {
    if (rest.lo[axis] < inner.lo[axis]) {
      CellBox slab = rest;
      slab.hi[axis] = inner.lo[axis];
      f(slab);
    }
    if (inner.hi[axis] < rest.hi[axis]) {
      CellBox slab = rest;
      slab.lo[axis] = inner.hi[axis];
      f(slab);
    }
    rest.lo[axis] = inner.lo[axis];
    rest.hi[axis] = inner.hi[axis];
  }
}

octomap::OcTreeKey toKey(const CellIndex& cell) {
  return octomap::OcTreeKey(static_cast<octomap::key_type>(cell.x() + kKeyOffset),
                            static_cast<octomap::key_type>(cell.y() + kKeyOffset),
                            static_cast<octomap::key_type>(cell.z() + kKeyOffset));
}

CellIndex fromKey(const octomap::OcTreeKey& key) {
  return {static_cast<int>(key[0]) - kKeyOffset, static_cast<int>(key[1]) - kKeyOffset,
          static_cast<int>(key[2]) - kKeyOffset};
}

bool storageFitsKeys(const CellIndex& storage_min, const CellIndex& dims) {
  return (storage_min.array() >= kMinCell).all() && ((storage_min + dims).array() - 1 <= kMaxCell).all();
}

}  // namespace

// --- Construction. ---

rt::Expected<LocalGrid> LocalGrid::create(const LocalGridParams& params) {
  const double res = params.resolution_m;
  if (!std::isfinite(res) || res <= 0.0) return paramError("resolution_m", "must be positive, got " + num(res));
  CellIndex size_cells;
  for (int axis = 0; axis < 3; ++axis) {
    const double size = params.size_m[axis];
    const std::string field = std::string("size_m[") + static_cast<char>('0' + axis) + "]";
    if (!std::isfinite(size) || size <= 0.0) return paramError(field, "must be positive, got " + num(size));
    const double cells = size / res;
    const double rounded = std::round(cells);
    if (std::abs(cells - rounded) > 1e-6 || rounded < 1.0 || rounded > 65536.0) {
      return paramError(field, num(size) + " is not a whole number of " + num(res) + " m cells (1 to 65536)");
    }
    size_cells[axis] = static_cast<int>(rounded);
  }
  const double radius = params.inflation_radius_m;
  if (!std::isfinite(radius) || radius < 0.0) {
    return paramError("inflation_radius_m", "must be zero or positive, got " + num(radius));
  }
  if (!std::isfinite(params.recenter_distance_m) || params.recenter_distance_m < 0.0) {
    return paramError("recenter_distance_m", "must be zero or positive, got " + num(params.recenter_distance_m));
  }
  // Stencil: integer offsets d with |d| * res <= radius (a small tolerance keeps exact ties, e.g. 0.2 m
  // at 0.1 m, inside despite rounding of radius / res).
  const double radius_cells = radius / res;
  if (radius_cells > 20.0) return paramError("inflation_radius_m", num(radius) + " is over 20 cells");
  const double r2 = radius_cells * radius_cells + 1e-9;
  const int margin = static_cast<int>(std::floor(radius_cells + 1e-9));
  std::vector<StencilRow> rows;
  int stencil_size = 0;
  for (int dz = -margin; dz <= margin; ++dz) {
    for (int dy = -margin; dy <= margin; ++dy) {
      const int yz2 = dy * dy + dz * dz;
      if (yz2 > r2) continue;
      int half = 0;
      while ((half + 1) * (half + 1) + yz2 <= r2) ++half;
      rows.push_back({dy, dz, half});
      stencil_size += 2 * half + 1;
    }
  }
  if (stencil_size > kMaxStencilSize) {
    return paramError("inflation_radius_m", num(radius) + " gives a stencil over 16383 cells");
  }
  const CellIndex dims = size_cells.array() + 2 * margin;
  const std::int64_t total = std::int64_t{dims.x()} * std::int64_t{dims.y()} * std::int64_t{dims.z()};
  if (total > kMaxStorageCells || (dims.array() > 65536).any()) {
    return paramError("size_m", "window of " + std::to_string(total) + " cells is too large");
  }

  LocalGrid grid;
  grid.params_ = params;
  grid.inv_resolution_per_m_ = 1.0 / res;
  grid.size_cells_ = size_cells;
  grid.margin_cells_ = margin;
  grid.dims_ = dims;
  grid.stencil_rows_ = std::move(rows);
  grid.stencil_size_ = stencil_size;
  const CellIndex window_min = -(size_cells.array() / 2).matrix();
  const CellIndex storage_min = window_min.array() - margin;
  if (!storageFitsKeys(storage_min, dims)) return paramError("size_m", "window exceeds the octree's key range");
  grid.setOrigin(storage_min, CellIndex::Zero());
  grid.cells_.assign(static_cast<std::size_t>(total), Word{0});
  grid.cells_per_row_ = static_cast<std::size_t>(grid.dims_.x());
  grid.row_stamps_.assign(static_cast<std::size_t>(grid.dims_.y()) * static_cast<std::size_t>(grid.dims_.z()), 0);
  return grid;
}

void LocalGrid::setOrigin(const CellIndex& storage_min_cell, const CellIndex& storage_min_slot) {
  storage_min_cell_ = storage_min_cell;
  window_min_cell_ = storage_min_cell.array() + margin_cells_;
  storage_min_slot_ = storage_min_slot;
  for (int axis = 0; axis < 3; ++axis) {
    window_min_slot_[axis] = wrapIndex(storage_min_slot[axis] + margin_cells_, dims_[axis]);
  }
}

void LocalGrid::copyFrom(const LocalGrid& other) {
  if (this == &other) return;
  copyGeometryFrom(other);
  // assign() reuses the existing buffers when they are large enough.
  stencil_rows_.assign(other.stencil_rows_.begin(), other.stencil_rows_.end());
  cells_.assign(other.cells_.begin(), other.cells_.end());
  row_stamps_.assign(other.row_stamps_.begin(), other.row_stamps_.end());
  copyStampsFrom(other);
}

void LocalGrid::copyChangesFrom(const LocalGrid& other) {
  const bool incremental = copied_from_ == &other && other.full_stamp_ <= copied_at_stamp_ &&
                           copied_at_stamp_ <= other.stamp_ && dims_ == other.dims_ &&
                           stencil_size_ == other.stencil_size_ && cells_.size() == other.cells_.size() &&
                           row_stamps_.size() == other.row_stamps_.size();
  if (!incremental) {
    copyFrom(other);
    return;
  }
  copyGeometryFrom(other);
  for (std::size_t row = 0; row < row_stamps_.size(); ++row) {
    if (other.row_stamps_[row] <= copied_at_stamp_) continue;
    const auto first = other.cells_.begin() + static_cast<std::ptrdiff_t>(row * cells_per_row_);
    std::copy(first, first + static_cast<std::ptrdiff_t>(cells_per_row_),
              cells_.begin() + static_cast<std::ptrdiff_t>(row * cells_per_row_));
    row_stamps_[row] = other.row_stamps_[row];
  }
  copyStampsFrom(other);
}

void LocalGrid::copyGeometryFrom(const LocalGrid& other) {
  params_ = other.params_;
  inv_resolution_per_m_ = other.inv_resolution_per_m_;
  size_cells_ = other.size_cells_;
  margin_cells_ = other.margin_cells_;
  dims_ = other.dims_;
  storage_min_cell_ = other.storage_min_cell_;
  window_min_cell_ = other.window_min_cell_;
  storage_min_slot_ = other.storage_min_slot_;
  window_min_slot_ = other.window_min_slot_;
  stencil_size_ = other.stencil_size_;
  cells_per_row_ = other.cells_per_row_;
}

void LocalGrid::copyStampsFrom(const LocalGrid& other) {
  stamp_ = other.stamp_;
  full_stamp_ = other.full_stamp_;
  copied_from_ = &other;
  copied_at_stamp_ = other.stamp_;
}

// --- Storage helpers. ---

bool LocalGrid::inStorage(const CellIndex& cell) const {
  for (int axis = 0; axis < 3; ++axis) {
    const int local = cell[axis] - storage_min_cell_[axis];
    if (local < 0 || local >= dims_[axis]) return false;
  }
  return true;
}

std::size_t LocalGrid::rowBase(int y, int z) const {
  int sy = y - storage_min_cell_.y() + storage_min_slot_.y();
  if (sy >= dims_.y()) sy -= dims_.y();
  int sz = z - storage_min_cell_.z() + storage_min_slot_.z();
  if (sz >= dims_.z()) sz -= dims_.z();
  return (static_cast<std::size_t>(sz) * static_cast<std::size_t>(dims_.y()) + static_cast<std::size_t>(sy)) *
         static_cast<std::size_t>(dims_.x());
}

std::size_t LocalGrid::slotOf(const CellIndex& cell) const {
  std::size_t slot = 0;
  std::size_t stride = 1;
  for (int axis = 0; axis < 3; ++axis) {
    int index = cell[axis] - storage_min_cell_[axis] + storage_min_slot_[axis];
    if (index >= dims_[axis]) index -= dims_[axis];
    slot += static_cast<std::size_t>(index) * stride;
    stride *= static_cast<std::size_t>(dims_[axis]);
  }
  return slot;
}

template <class F>
void LocalGrid::forEachCellIn(const CellBox& box, const F& f) {
  if (box.empty()) return;
  int sx_first = box.lo.x() - storage_min_cell_.x() + storage_min_slot_.x();  // in [0, 2 dims)
  if (sx_first >= dims_.x()) sx_first -= dims_.x();
  CellIndex cell;
  for (cell.z() = box.lo.z(); cell.z() < box.hi.z(); ++cell.z()) {
    for (cell.y() = box.lo.y(); cell.y() < box.hi.y(); ++cell.y()) {
      const std::size_t row = rowBase(cell.y(), cell.z());
      touchRow(row);
      int sx = sx_first;
      for (cell.x() = box.lo.x(); cell.x() < box.hi.x(); ++cell.x()) {
        f(static_cast<const CellIndex&>(cell), cells_[row + static_cast<std::size_t>(sx)]);
        if (++sx == dims_.x()) sx = 0;
      }
    }
  }
}

void LocalGrid::addStencil(const CellIndex& center, Word delta) {
  const int x_min = storage_min_cell_.x();
  const int x_max = x_min + dims_.x() - 1;
  for (const StencilRow& row : stencil_rows_) {
    const int y = center.y() + row.dy;
    const int z = center.z() + row.dz;
    if (y - storage_min_cell_.y() < 0 || y - storage_min_cell_.y() >= dims_.y()) continue;
    if (z - storage_min_cell_.z() < 0 || z - storage_min_cell_.z() >= dims_.z()) continue;
    const int x_begin = std::max(center.x() - row.half_x, x_min);
    const int x_end = std::min(center.x() + row.half_x, x_max);
    const std::size_t base = rowBase(y, z);
    touchRow(base);
    int sx = x_begin - storage_min_cell_.x() + storage_min_slot_.x();  // in [0, 2 dims): no modulo needed
    if (sx >= dims_.x()) sx -= dims_.x();
    for (int x = x_begin; x <= x_end; ++x) {
      Word& word = cells_[base + static_cast<std::size_t>(sx)];
      word = static_cast<Word>(word + delta);
      if (++sx == dims_.x()) sx = 0;
    }
  }
}

template <class Pred>
void LocalGrid::addStencilWhere(const CellIndex& center, Word delta, const Pred& pred) {
  for (const StencilRow& row : stencil_rows_) {
    for (int dx = -row.half_x; dx <= row.half_x; ++dx) {
      const CellIndex cell(center.x() + dx, center.y() + row.dy, center.z() + row.dz);
      if (!inStorage(cell) || !pred(cell)) continue;
      const std::size_t slot = slotOf(cell);
      touchRow(slot);
      Word& word = cells_[slot];
      word = static_cast<Word>(word + delta);
    }
  }
}

// --- Synchronisation with the octree. ---

rt::Status LocalGrid::checkResolution(const octomap::OcTree& tree) const {
  const double tree_res = tree.getResolution();
  if (std::abs(tree_res - params_.resolution_m) > 1e-9 * params_.resolution_m) {
    return rt::Error{"local grid: the octree's resolution " + num(tree_res) + " m differs from the grid's " +
                     num(params_.resolution_m) + " m"};
  }
  return rt::ok();
}

void LocalGrid::fillStatesFromTree(const octomap::OcTree& tree, const CellBox& box) {
  if (box.empty()) return;
  const octomap::OcTreeKey min_key = toKey(box.lo);
  const octomap::OcTreeKey max_key = toKey(box.hi.array() - 1);
  for (auto it = tree.begin_leafs_bbx(min_key, max_key), end = tree.end_leafs_bbx(); it != end; ++it) {
    // A leaf at depth d is a cube of 2^(16 - d) voxels whose lowest corner is its index key.
    const int leaf_cells = 1 << (kTreeDepth - static_cast<int>(it.getDepth()));
    const CellIndex corner = fromKey(it.getIndexKey());
    const CellBox leaf = intersect({corner, corner.array() + leaf_cells}, box);
    const Word state = static_cast<Word>(tree.isNodeOccupied(*it) ? CellState::kOccupied : CellState::kFree);
    forEachCellIn(leaf,
                  [state](const CellIndex&, Word& word) { word = static_cast<Word>((word & ~kStateMask) | state); });
  }
}

void LocalGrid::recountAll() {
  touchAll();
  for (Word& word : cells_) word = static_cast<Word>(word & kStateMask);
  forEachCellIn(storageBox(), [this](const CellIndex& cell, Word& word) {
    if ((word & kStateMask) == static_cast<Word>(CellState::kOccupied)) addStencil(cell, kCountOne);
  });
}

rt::Status LocalGrid::rebuild(const octomap::OcTree& tree) {
  if (auto status = checkResolution(tree); !status) return status;
  touchAll();
  std::fill(cells_.begin(), cells_.end(), Word{0});
  fillStatesFromTree(tree, storageBox());
  recountAll();
  return rt::ok();
}

rt::Status LocalGrid::applyChanges(const octomap::OcTree& tree) {
  if (auto status = checkResolution(tree); !status) return status;
  for (auto it = tree.changedKeysBegin(), end = tree.changedKeysEnd(); it != end; ++it) {
    // search() returns the covering coarse leaf where the tree has pruned 8 equal children.
    const octomap::OcTreeNode* node = tree.search(it->first);
    setVoxel(it->first, node == nullptr             ? CellState::kUnknown
                        : tree.isNodeOccupied(node) ? CellState::kOccupied
                                                    : CellState::kFree);
  }
  return rt::ok();
}

void LocalGrid::setVoxel(const octomap::OcTreeKey& key, CellState now) {
  constexpr Word kMinusOne = static_cast<Word>(-static_cast<int>(kCountOne));
  const CellIndex cell = fromKey(key);
  if (!inStorage(cell)) return;
  const std::size_t slot = slotOf(cell);
  Word& word = cells_[slot];
  const auto before = static_cast<CellState>(word & kStateMask);
  if (before == now) return;
  touchRow(slot);
  word = static_cast<Word>((word & ~kStateMask) | static_cast<Word>(now));
  if (before == CellState::kOccupied) addStencil(cell, kMinusOne);
  if (now == CellState::kOccupied) addStencil(cell, kCountOne);
}

rt::Expected<bool> LocalGrid::recenter(const Eigen::Vector3d& center_W_m, const octomap::OcTree& tree) {
  if (auto status = checkResolution(tree); !status) return status.error();
  if (!center_W_m.allFinite()) return rt::Error{"local grid: recenter: the centre is not finite"};
  CellIndex new_window_min;
  for (int axis = 0; axis < 3; ++axis) {
    const double cell = std::floor(center_W_m[axis] * inv_resolution_per_m_);
    if (!(cell >= kMinCell && cell <= kMaxCell)) {
      return rt::Error{"local grid: recenter: centre " + num(center_W_m[axis]) + " m is outside the octree"};
    }
    new_window_min[axis] = static_cast<int>(cell) - size_cells_[axis] / 2;
  }
  const CellIndex new_storage_min = new_window_min.array() - margin_cells_;
  if (!storageFitsKeys(new_storage_min, dims_)) {
    return rt::Error{"local grid: recenter: the window would leave the octree's key range"};
  }
  if ((center_W_m - windowCenterM()).norm() <= params_.recenter_distance_m) return false;
  if (new_window_min == window_min_cell_) return false;

  const CellBox old_box = storageBox();
  const CellBox new_box{new_storage_min, new_storage_min + dims_};
  const CellBox kept = intersect(old_box, new_box);
  if (kept.empty()) {  // nothing to keep: a full refill
    setOrigin(new_storage_min, storage_min_slot_);
    touchAll();
    std::fill(cells_.begin(), cells_.end(), Word{0});
    fillStatesFromTree(tree, new_box);
    recountAll();
    return true;
  }
  constexpr Word kMinusOne = static_cast<Word>(-static_cast<int>(kCountOne));
  const auto is_occupied = [](Word word) { return (word & kStateMask) == static_cast<Word>(CellState::kOccupied); };
  const auto in_kept = [&kept](const CellIndex& cell) { return kept.contains(cell); };
  const auto not_in_kept = [&kept](const CellIndex& cell) { return !kept.contains(cell); };

  // 1. Occupied voxels that leave no longer inflate the cells that stay.
  forEachBoxInDifference(old_box, kept, [&](const CellBox& box) {
    forEachCellIn(box, [&](const CellIndex& cell, Word& word) {
      if (is_occupied(word)) addStencilWhere(cell, kMinusOne, in_kept);
    });
  });
  // 2. Re-index: kept cells keep their slots; the leaving cells' slots now hold the entering cells.
  CellIndex new_slot;
  for (int axis = 0; axis < 3; ++axis) {
    new_slot[axis] = wrapIndex(storage_min_slot_[axis] + new_storage_min[axis] - storage_min_cell_[axis], dims_[axis]);
  }
  setOrigin(new_storage_min, new_slot);
  // 3. Entering cells: cleared, then filled from the tree's leaves.
  forEachBoxInDifference(new_box, kept, [&](const CellBox& box) {
    forEachCellIn(box, [](const CellIndex&, Word& word) { word = Word{0}; });
    fillStatesFromTree(tree, box);
  });
  // 4. Occupied entering voxels inflate every cell around them.
  forEachBoxInDifference(new_box, kept, [&](const CellBox& box) {
    forEachCellIn(box, [&](const CellIndex& cell, Word& word) {
      if (is_occupied(word)) addStencil(cell, kCountOne);
    });
  });
  // 5. Occupied kept voxels near the entering faces inflate the entering cells around them.
  CellBox core = kept;  // kept cells farther than the stencil radius from every entering cell
  for (int axis = 0; axis < 3; ++axis) {
    if (new_box.lo[axis] < kept.lo[axis]) core.lo[axis] += margin_cells_;
    if (kept.hi[axis] < new_box.hi[axis]) core.hi[axis] -= margin_cells_;
  }
  forEachBoxInDifference(kept, core, [&](const CellBox& box) {
    forEachCellIn(box, [&](const CellIndex& cell, Word& word) {
      if (is_occupied(word)) addStencilWhere(cell, kCountOne, not_in_kept);
    });
  });
  return true;
}

// --- Queries. ---

bool LocalGrid::cellInWindow(const CellIndex& cell) const {
  return windowBox().contains(cell);
}

CellState LocalGrid::cellState(const CellIndex& cell) const {
  if (!cellInWindow(cell)) return CellState::kUnknown;
  return static_cast<CellState>(cells_[slotOf(cell)] & kStateMask);
}

int LocalGrid::inflationCount(const CellIndex& cell) const {
  if (!cellInWindow(cell)) return 0;
  return cells_[slotOf(cell)] >> kCountShift;
}

CellIndex LocalGrid::cellIndex(const Eigen::Vector3d& p_W_m) const {
  CellIndex cell;
  for (int axis = 0; axis < 3; ++axis) {
    const double s = std::floor(p_W_m[axis] * inv_resolution_per_m_);
    // Saturated just outside the octree's key range (NaN: below it), so the cast is always defined.
    cell[axis] = s >= kMinCell ? (s <= kMaxCell ? static_cast<int>(s) : kMaxCell + 1) : kMinCell - 1;
  }
  return cell;
}

Eigen::Vector3d LocalGrid::cellCenterM(const CellIndex& cell) const {
  return (cell.cast<double>().array() + 0.5) * params_.resolution_m;
}

Eigen::Vector3d LocalGrid::windowMinM() const {
  return window_min_cell_.cast<double>() * params_.resolution_m;
}

Eigen::Vector3d LocalGrid::windowMaxM() const {
  return (window_min_cell_ + size_cells_).cast<double>() * params_.resolution_m;
}

Eigen::Vector3d LocalGrid::windowCenterM() const {
  return (window_min_cell_.cast<double>() + 0.5 * size_cells_.cast<double>()) * params_.resolution_m;
}

// 3D DDA (Amanatides & Woo 1987) in cell units: the segment a + t (b - a), t in [0, 1], is clipped to the
// window, then cells are visited in order from the cell of the clipped start to the cell of the clipped
// end, stepping each time along the axis whose next cell boundary is nearest. Each axis takes exactly
// |end - start| steps, so rounding can never make the walk overshoot. visit(word, t_enter) returns true
// to stop; traverse returns whether it stopped.
template <class Visit>
bool LocalGrid::traverse(const Eigen::Vector3d& a_W_m, const Eigen::Vector3d& b_W_m, const Visit& visit) const {
  const Eigen::Vector3d a = a_W_m * inv_resolution_per_m_;
  const Eigen::Vector3d d = b_W_m * inv_resolution_per_m_ - a;
  double t0 = 0.0;
  double t1 = 1.0;
  for (int axis = 0; axis < 3; ++axis) {
    const double lo = window_min_cell_[axis];
    const double hi = lo + size_cells_[axis];
    if (d[axis] == 0.0) {
      if (!(a[axis] >= lo && a[axis] < hi)) return false;
      continue;
    }
    double t_lo = (lo - a[axis]) / d[axis];
    double t_hi = (hi - a[axis]) / d[axis];
    if (t_lo > t_hi) std::swap(t_lo, t_hi);
    t0 = std::max(t0, t_lo);
    t1 = std::min(t1, t_hi);
  }
  if (!(t0 <= t1)) return false;

  // Per-axis walk state; kept in named locals (not indexed arrays) so that it lives in registers.
  struct AxisWalk {
    double t_max;  // t at which the next boundary along this axis is crossed (inf: no more steps)
    double t_delta;
    int remaining;
    int step;
    int slot;  // ring slot of the current cell along this axis
    int size;
    std::size_t stride;
  };
  AxisWalk walk[3];
  const std::size_t strides[3] = {1, static_cast<std::size_t>(dims_.x()),
                                  static_cast<std::size_t>(dims_.x()) * static_cast<std::size_t>(dims_.y())};
  int total = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const int lo = window_min_cell_[axis];
    const int hi = lo + size_cells_[axis] - 1;
    const auto clamp_cell = [lo, hi](double s) {
      return static_cast<int>(std::clamp(std::floor(s), static_cast<double>(lo), static_cast<double>(hi)));
    };
    const int start = clamp_cell(a[axis] + t0 * d[axis]);
    const int end = clamp_cell(a[axis] + t1 * d[axis]);
    int delta = end - start;
    if ((delta > 0 && !(d[axis] > 0.0)) || (delta < 0 && !(d[axis] < 0.0))) delta = 0;
    AxisWalk& w = walk[axis];
    w.step = delta > 0 ? 1 : -1;
    w.remaining = std::abs(delta);
    total += w.remaining;
    if (w.remaining > 0) {
      const double boundary = start + (w.step > 0 ? 1 : 0);
      w.t_max = (boundary - a[axis]) / d[axis];
      w.t_delta = 1.0 / std::abs(d[axis]);
    } else {
      w.t_max = kInf;
      w.t_delta = kInf;
    }
    w.size = dims_[axis];
    w.stride = strides[axis];
    w.slot = start - window_min_cell_[axis] + window_min_slot_[axis];
    if (w.slot >= w.size) w.slot -= w.size;
  }
  AxisWalk wx = walk[0];
  AxisWalk wy = walk[1];
  AxisWalk wz = walk[2];
  std::size_t offset_y = static_cast<std::size_t>(wy.slot) * wy.stride;
  std::size_t offset_z = static_cast<std::size_t>(wz.slot) * wz.stride;
  double t_enter = t0;
  const auto advance = [&t_enter](AxisWalk& w) {
    t_enter = std::max(t_enter, w.t_max);
    w.t_max = --w.remaining == 0 ? kInf : w.t_max + w.t_delta;
    w.slot += w.step;
    if (w.slot == w.size) {
      w.slot = 0;
    } else if (w.slot < 0) {
      w.slot = w.size - 1;
    }
  };
  for (;;) {
    if (visit(cells_[static_cast<std::size_t>(wx.slot) + offset_y + offset_z], t_enter)) return true;
    if (total-- == 0) return false;
    // Step along the axis whose next boundary is nearest (ties: y before x, z before both).
    if (wx.t_max < wy.t_max && wx.t_max < wz.t_max) {
      advance(wx);
    } else if (wy.t_max < wz.t_max) {
      advance(wy);
      offset_y = static_cast<std::size_t>(wy.slot) * wy.stride;
    } else {
      advance(wz);
      offset_z = static_cast<std::size_t>(wz.slot) * wz.stride;
    }
  }
}

bool LocalGrid::lineOfSight(const Eigen::Vector3d& a_W_m, const Eigen::Vector3d& b_W_m) const {
  if (!finiteSegment(a_W_m, b_W_m, inv_resolution_per_m_)) return false;
  return !traverse(a_W_m, b_W_m,
                   [](Word word, double) { return (word & kStateMask) == static_cast<Word>(CellState::kOccupied); });
}

std::optional<Eigen::Vector3d> LocalGrid::firstHit(const Eigen::Vector3d& a_W_m, const Eigen::Vector3d& b_W_m) const {
  if (!finiteSegment(a_W_m, b_W_m, inv_resolution_per_m_)) return a_W_m;
  double t_hit = 0.0;
  const bool hit = traverse(a_W_m, b_W_m, [&t_hit](Word word, double t_enter) {
    t_hit = t_enter;
    return (word & kStateMask) == static_cast<Word>(CellState::kOccupied);
  });
  if (!hit) return std::nullopt;
  return Eigen::Vector3d(a_W_m + t_hit * (b_W_m - a_W_m));
}

bool LocalGrid::segmentFree(const Eigen::Vector3d& a_W_m, const Eigen::Vector3d& b_W_m) const {
  if (!finiteSegment(a_W_m, b_W_m, inv_resolution_per_m_)) return false;
  const bool unknown_blocks = params_.unknown_is_occupied;
  // The window is convex: the segment stays inside exactly when both ends do.
  if (unknown_blocks && (!inWindow(a_W_m) || !inWindow(b_W_m))) return false;
  return !traverse(a_W_m, b_W_m, [unknown_blocks](Word word, double) {
    return word >= kCountOne || (unknown_blocks && (word & kStateMask) == 0);
  });
}

}  // namespace aerotrack::mapping
