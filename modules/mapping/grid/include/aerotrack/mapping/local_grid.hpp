// LocalGrid: a dense occupancy grid in a box-shaped window that follows the drone, kept in sync with
// an OctoMap incrementally, for the planner's O(1) voxel queries and its line-of-sight checks to the
// person (paper Sect. V: path search, corridor and visibility all query the voxel grid G).
//
// Cells are the octree's voxels (same resolution and alignment: cell i covers [i, i+1) * resolution,
// i = floor(p / resolution), exactly OctoMap's key - 32768), so one changed octree key is one cell.
// Per cell one 16-bit word holds the state (unknown / free / occupied, 2 bits) and the inflation count
// (14 bits): the number of occupied voxels whose centre lies within inflation_radius_m of the cell's
// centre. Counts are kept incrementally by adding or subtracting a precomputed sphere stencil when a
// voxel starts or stops being occupied. Storage covers the window plus a margin of the stencil radius
// (so that voxels just outside the window still inflate cells inside it) and is a 3D ring buffer: the
// window moves by changing an origin offset, so cells that stay inside are neither copied nor lost and
// only the newly covered cells are read from the octree. Line of sight and segment checks traverse
// cells with the 3D DDA of Amanatides & Woo, "A Fast Voxel Traversal Algorithm for Ray Tracing" (1987).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "aerotrack/rt/expected.hpp"

namespace octomap {
class OcTree;
class OcTreeKey;
}  // namespace octomap

namespace aerotrack::mapping {

/// What is known about one cell (one octree voxel).
enum class CellState : std::uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };

struct LocalGridParams {
  double resolution_m = 0.1;  ///< Cell edge; must equal the octree's resolution (checked on every sync).
  Eigen::Vector3d size_m = Eigen::Vector3d(20.0, 20.0, 5.0);  ///< Window extent (x, y, z); whole cells.
  double inflation_radius_m = 0.25;  ///< The drone's radius: a cell is blocked if an occupied voxel's
                                     ///< centre lies within this distance of the cell's centre.
  bool unknown_is_occupied = false;  ///< Fast-Tracker plans through unknown space as if free.
  double recenter_distance_m = 2.0;  ///< The window moves when its centre is farther than this from the
                                     ///< requested centre.
};

/// Global integer cell coordinates: cell = floor(p_W_m / resolution_m) per axis (OctoMap key - 32768).
using CellIndex = Eigen::Vector3i;

/// Half-open box of global cell indices [lo, hi) per axis.
struct CellBox {
  CellIndex lo = CellIndex::Zero();
  CellIndex hi = CellIndex::Zero();
  bool empty() const { return (hi.array() <= lo.array()).any(); }
  bool contains(const CellIndex& cell) const {
    return (cell.array() >= lo.array()).all() && (cell.array() < hi.array()).all();
  }
};

/// Dense local occupancy grid. Thread safety: the const queries read only and allocate nothing, so any
/// number of threads may query a grid that nobody modifies; the mutating calls (rebuild, applyChanges,
/// recenter, copyFrom) need exclusive access. To serve readers on other threads, keep a small pool of
/// grids and publish immutable copies made with copyFrom (no allocation once the pool is warm).
/// Copyable (a copy allocates its own storage) and movable.
class LocalGrid {
 public:
  /// Validates the parameters and allocates all storage (the only allocation of the grid's cells).
  /// The window starts centred on the origin, all unknown: call rebuild(tree) (or recenter then
  /// rebuild) to fill it from a tree that is not empty.
  static rt::Expected<LocalGrid> create(const LocalGridParams& params);

  const LocalGridParams& params() const { return params_; }

  // --- Synchronisation with the octree (exclusive access; the tree is only read). ---

  /// Refills the whole window from the tree (slow, obvious reference; also used at start): every cell
  /// is reset, the tree's leaves in the window are expanded to cells and all counts are recomputed.
  /// Cost O(cells + leaves + occupied * stencil); allocates only inside OctoMap's leaf iterator.
  /// Error if the tree's resolution differs from resolution_m.
  rt::Status rebuild(const octomap::OcTree& tree);

  /// Applies the tree's changed keys (tree.changedKeysBegin()..End(); the owner enables change detection
  /// and resets it after this call). Each key in the window is looked up with tree.search (which returns
  /// the covering coarse leaf where OctoMap has pruned), and the cell's state and the inflation counts of
  /// its stencil are updated when it changed. Cost O(changed keys * tree depth + flips * stencil); no
  /// allocation. Changes OctoMap does not record (deleteNode, clear, readBinary) need rebuild(tree).
  /// Error (grid untouched) if the tree's resolution differs from resolution_m.
  rt::Status applyChanges(const octomap::OcTree& tree);

  /// Sets the state of the voxel with this octree key, as an insertion reported it (the fast path of
  /// applyChanges for an owner that knows what changed: OctomapMap::changes(), no tree search). Outside
  /// the storage: ignored. The inflation counts of its stencil follow when it starts or stops being
  /// occupied. O(1), O(stencil) on such a flip; no allocation. The caller checks the resolutions match.
  void setVoxel(const octomap::OcTreeKey& key, CellState now);

  /// Moves the window, snapped to whole cells, so that it is centred on center_W_m, if its current
  /// centre is farther than recenter_distance_m from it; returns whether it moved. Cells that stay
  /// inside keep their state (ring buffer: only the origin offset changes, nothing is copied), newly
  /// covered cells are filled from the tree's leaves (coarse leaves expanded), and the counts end up
  /// exactly as rebuild(tree) would give, provided the grid was in sync with the tree. Cost
  /// O(new cells + their leaves + occupied voxels near the moving faces * stencil); allocates only
  /// inside OctoMap's leaf iterator. Error (grid untouched) on a resolution mismatch, a non-finite
  /// centre, or a window that would leave the octree's key range (+-3276.8 m at 0.1 m).
  rt::Expected<bool> recenter(const Eigen::Vector3d& center_W_m, const octomap::OcTree& tree);

  /// Copies another grid's contents, parameters and window into this one, reusing this grid's storage:
  /// no allocation when both have the same size and radius. `other` is only read; this grid needs
  /// exclusive access. Cost: one copy of the storage (about 4.5 MB for the default 20 x 20 x 5 m).
  void copyFrom(const LocalGrid& other);

  /// copyFrom that copies only the storage rows (x runs of cells) other wrote since this grid's last
  /// copy of it -- for a pool of published snapshots that each lag the owner's grid by a few frames.
  /// Falls back to copyFrom when this grid's last copy was not of other (by address), when other was
  /// refilled whole since, or when the sizes differ. The caller must not have modified this grid since
  /// its last copy. Cost: O(rows) to compare write stamps plus the changed rows (a frame of forest
  /// flight touches a few hundred of the ~14 000 rows; a window move, the entering slabs).
  void copyChangesFrom(const LocalGrid& other);

  // --- Queries: O(1) or O(cells traversed), const, no allocation. Points in W, metres. ---

  /// Blocked for planning: an occupied voxel within the inflation radius of the cell's centre, or the
  /// cell is unknown and unknown_is_occupied. Outside the window: unknown_is_occupied.
  bool isOccupied(const Eigen::Vector3d& p_W_m) const;
  /// Known free and not within the inflation radius of any occupied voxel. Outside the window: false.
  bool isFree(const Eigen::Vector3d& p_W_m) const;
  /// Whether p lies in the window (the half-open box [windowMinM, windowMaxM)).
  bool inWindow(const Eigen::Vector3d& p_W_m) const;
  /// Raw (not inflated) state of p's cell; kUnknown outside the window.
  CellState state(const Eigen::Vector3d& p_W_m) const;

  /// Same queries by global cell index (named apart from the point overloads so that Eigen expressions
  /// do not make calls ambiguous). Outside the window: false, kUnknown, 0.
  bool cellInWindow(const CellIndex& cell) const;
  CellState cellState(const CellIndex& cell) const;
  /// Number of occupied voxels whose centre is within inflation_radius_m of this cell's centre
  /// (0 outside the window).
  int inflationCount(const CellIndex& cell) const;

  /// True if no raw-occupied cell lies along the segment a->b (3D DDA over every window cell the segment
  /// passes through, both end cells included; cells are half-open, so an end exactly on a face belongs to
  /// the cell above it). Inflation does not block sight, and neither do unknown cells nor the outside of
  /// the window, whatever unknown_is_occupied says. Non-finite input counts as blocked (false).
  /// O(cells traversed), no allocation.
  bool lineOfSight(const Eigen::Vector3d& a_W_m, const Eigen::Vector3d& b_W_m) const;
  /// The point where the segment a->b first enters a raw-occupied cell (a itself if a's cell is
  /// occupied), or nothing exactly when lineOfSight(a, b). Non-finite input: a. O(cells traversed), no
  /// allocation.
  std::optional<Eigen::Vector3d> firstHit(const Eigen::Vector3d& a_W_m, const Eigen::Vector3d& b_W_m) const;
  /// True if no cell the segment a->b passes through is blocked in the sense of isOccupied (inflation and
  /// the unknown policy apply, also outside the window). For path checks. Non-finite input: false.
  /// O(cells traversed), no allocation.
  bool segmentFree(const Eigen::Vector3d& a_W_m, const Eigen::Vector3d& b_W_m) const;

  // --- Geometry. ---

  /// Global cell index of a point (floor(p / resolution_m), as OctoMap's coordToKey - 32768). Saturated
  /// just outside the octree's key range [-32768, 32767] (NaN: -32769), so never inside a window.
  CellIndex cellIndex(const Eigen::Vector3d& p_W_m) const;
  /// Centre of a cell (W, metres).
  Eigen::Vector3d cellCenterM(const CellIndex& cell) const;
  /// Window: cells [windowMinCell, windowMinCell + windowSizeCells) per axis.
  CellIndex windowMinCell() const { return window_min_cell_; }
  CellIndex windowSizeCells() const { return size_cells_; }
  CellBox windowBox() const { return {window_min_cell_, window_min_cell_ + size_cells_}; }
  /// Window corners and centre (W, metres); all points are in W, so the frame is left out of these names.
  Eigen::Vector3d windowMinM() const;
  Eigen::Vector3d windowMaxM() const;
  Eigen::Vector3d windowCenterM() const;
  /// Inflation margin around the window (cells) that storage also covers.
  int marginCells() const { return margin_cells_; }
  /// Number of cells in the inflation stencil (81 for 0.25 m at 0.1 m).
  int stencilSize() const { return stencil_size_; }
  /// Bytes of cell storage.
  std::size_t storageBytes() const { return cells_.size() * sizeof(Word); }

 private:
  using Word = std::uint16_t;  // bits 0-1: CellState, bits 2-15: inflation count
  static constexpr Word kStateMask = 3;
  static constexpr int kCountShift = 2;
  static constexpr Word kCountOne = Word{1} << kCountShift;

  struct StencilRow {  // offsets (dx in [-half_x, half_x], dy, dz) of the cells within the radius
    int dy;
    int dz;
    int half_x;
  };

  LocalGrid() = default;

  /// Storage index of p's cell, or false if p is outside the window (NaN included). Inline: hot path.
  bool windowSlot(const Eigen::Vector3d& p_W_m, std::size_t& slot) const;
  rt::Status checkResolution(const octomap::OcTree& tree) const;
  CellBox storageBox() const { return {storage_min_cell_, storage_min_cell_ + dims_}; }
  bool inStorage(const CellIndex& cell) const;
  std::size_t slotOf(const CellIndex& cell) const;  // storage index; the cell must be inStorage
  std::size_t rowBase(int y, int z) const;          // storage index of slot x = 0 in row (y, z), in storage
  void setOrigin(const CellIndex& storage_min_cell, const CellIndex& storage_min_slot);
  void copyGeometryFrom(const LocalGrid& other);  // everything but the cells, stencil rows and stamps
  void copyStampsFrom(const LocalGrid& other);
  void fillStatesFromTree(const octomap::OcTree& tree, const CellBox& box);  // states only, box in storage
  void recountAll();                                                         // counts from states, whole storage
  void addStencil(const CellIndex& center, Word delta);                      // every storage cell within the radius
  template <class Pred>
  void addStencilWhere(const CellIndex& center, Word delta, const Pred& pred);  // ... and pred(cell)
  template <class F>
  void forEachCellIn(const CellBox& box, const F& f);  // f(cell, word&), box inside storage
  void touchRow(std::size_t storage_index) { row_stamps_[storage_index / cells_per_row_] = ++stamp_; }
  void touchAll() { full_stamp_ = ++stamp_; }
  template <class Visit>
  bool traverse(const Eigen::Vector3d& a_W_m, const Eigen::Vector3d& b_W_m, const Visit& visit) const;

  LocalGridParams params_;
  double inv_resolution_per_m_ = 10.0;
  CellIndex size_cells_ = CellIndex::Zero();        // window size
  int margin_cells_ = 0;                            // stencil radius in cells
  CellIndex dims_ = CellIndex::Zero();              // storage size = window + 2 margin
  CellIndex storage_min_cell_ = CellIndex::Zero();  // global index of storage box's min corner
  CellIndex window_min_cell_ = CellIndex::Zero();   // = storage_min_cell_ + margin
  CellIndex storage_min_slot_ = CellIndex::Zero();  // ring slot (per axis) holding storage_min_cell_
  CellIndex window_min_slot_ = CellIndex::Zero();   // ring slot (per axis) holding window_min_cell_
  std::vector<StencilRow> stencil_rows_;
  int stencil_size_ = 0;
  std::vector<Word> cells_;  // x fastest: slot = sx + dims.x * (sy + dims.y * sz)
  // Write stamps for copyChangesFrom: every write to a storage row (dims.x cells) stamps it with
  // ++stamp_; a whole refill sets full_stamp_. A copy remembers its source and the source's stamp_.
  std::size_t cells_per_row_ = 1;
  std::vector<std::uint64_t> row_stamps_;
  std::uint64_t stamp_ = 0;
  std::uint64_t full_stamp_ = 0;
  const LocalGrid* copied_from_ = nullptr;
  std::uint64_t copied_at_stamp_ = 0;
};

// --- Inline hot-path queries. ---

inline bool LocalGrid::windowSlot(const Eigen::Vector3d& p_W_m, std::size_t& slot) const {
  std::size_t stride = 1;
  slot = 0;
  for (int axis = 0; axis < 3; ++axis) {
    // Same floor(p / resolution) as OctoMap's coordToKey. With integer bounds, s >= lo and s < hi is
    // exactly floor(s) in [lo, hi); NaN fails both, so the cast below is always defined.
    const double s = p_W_m[axis] * inv_resolution_per_m_;
    const int lo = window_min_cell_[axis];
    if (!(s >= lo && s < lo + size_cells_[axis])) return false;
    int cell = static_cast<int>(s);  // truncation toward zero, then floor:
    if (cell > s) --cell;
    int index = cell - lo + window_min_slot_[axis];
    if (index >= dims_[axis]) index -= dims_[axis];
    slot += static_cast<std::size_t>(index) * stride;
    stride *= static_cast<std::size_t>(dims_[axis]);
  }
  return true;
}

inline bool LocalGrid::isOccupied(const Eigen::Vector3d& p_W_m) const {
  std::size_t slot = 0;
  if (!windowSlot(p_W_m, slot)) return params_.unknown_is_occupied;
  const Word word = cells_[slot];
  return word >= kCountOne || (params_.unknown_is_occupied && (word & kStateMask) == 0);
}

inline bool LocalGrid::isFree(const Eigen::Vector3d& p_W_m) const {
  std::size_t slot = 0;
  return windowSlot(p_W_m, slot) && cells_[slot] == static_cast<Word>(CellState::kFree);
}

inline bool LocalGrid::inWindow(const Eigen::Vector3d& p_W_m) const {
  std::size_t slot = 0;
  return windowSlot(p_W_m, slot);
}

inline CellState LocalGrid::state(const Eigen::Vector3d& p_W_m) const {
  std::size_t slot = 0;
  if (!windowSlot(p_W_m, slot)) return CellState::kUnknown;
  return static_cast<CellState>(cells_[slot] & kStateMask);
}

}  // namespace aerotrack::mapping
