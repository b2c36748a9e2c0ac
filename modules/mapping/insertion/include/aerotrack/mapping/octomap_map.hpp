// OctomapMap: the global occupancy map (issue 4), an octomap::OcTree (Hornung et al., "OctoMap:
// an efficient probabilistic 3D mapping framework based on octrees", Autonomous Robots 2013)
// filled one depth frame at a time. insert() integrates a frame the way
// OcTree::insertPointCloud(scan, origin, maxrange) does -- every ray from the sensor origin
// clears the voxels it crosses (3D DDA, OcTree::computeRayKeys), every hit's voxel is marked
// occupied, each voxel is updated at most once per frame and occupied wins over free -- but it
// batches the frame's voxel keys in a reused open-addressing hash set instead of two
// std::unordered_sets, and skips voxels already clamped in the update's direction with one
// search. Miss points (see depth_points.hpp) clear up to, not including, their end voxel and
// mark nothing occupied. After each insert, changes() lists the leaf voxels that the insert
// created or whose occupied/free state it flipped, with their new state (what OctoMap's change
// detection records, which stays off: it allocates a hash-map node per key); the dense local
// grid is kept in sync from it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <octomap/OcTree.h>
#include <octomap/Pointcloud.h>
#include <Eigen/Core>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::mapping {

/// Sensor model and resolution. Defaults: OctoMap's hit / miss probabilities and threshold; the
/// clamping bounds are the commonly quoted 0.12 / 0.97 (OcTree's own are 0.1192 / 0.971).
struct OctomapMapParams {
  double resolution_m = 0.1;         ///< Leaf voxel edge; > 0.
  double prob_hit = 0.7;             ///< P(occupied | hit); in (0.5, 1).
  double prob_miss = 0.4;            ///< P(occupied | ray passed); in (0, 0.5).
  double clamp_min = 0.12;           ///< Lower clamping probability; in (0, occupancy_threshold).
  double clamp_max = 0.97;           ///< Upper clamping probability; in (occupancy_threshold, 1).
  double occupancy_threshold = 0.5;  ///< Occupied when P > this; in (0, 1).
};

/// Ok if every field is in its documented range.
rt::Status validate(const OctomapMapParams& params);

/// What one insert() did.
struct InsertStats {
  std::size_t hit_points = 0;        ///< Hit points given.
  std::size_t miss_points = 0;       ///< Miss points given.
  std::size_t points_rejected = 0;   ///< Non-finite or outside the octree's extent: ignored.
  std::size_t free_voxels = 0;       ///< Distinct voxels updated as free.
  std::size_t occupied_voxels = 0;   ///< Distinct voxels updated as occupied.
  std::size_t saturated_voxels = 0;  ///< Of those, already clamped in that direction: unchanged.
  /// Distinct voxels this frame updated (at most once each).
  std::size_t updatedVoxels() const { return free_voxels + occupied_voxels; }
};

/// A leaf voxel an insert created (it was unknown) or whose occupied/free state it flipped.
struct VoxelChange {
  octomap::OcTreeKey key;
  bool occupied = false;  ///< The state after the insert (false: free).
};

/// Thread safety: none; one owner thread calls insert() and snapshot(); readers on other threads
/// use snapshots. Allocation: the tree allocates nodes as it grows (inside OctoMap); the key
/// batch, the change list and the ray buffer (~3 MB) are allocated in create(), and the batch
/// grows only if a frame touches more than 65 536 distinct voxels (a 160 x 120 / 4 frame at 6 m
/// touches ~27 000).
class OctomapMap {
 public:
  /// Validates params; builds an empty tree (OctoMap's change detection off: see changes()).
  static rt::Expected<OctomapMap> create(const OctomapMapParams& params = {});

  OctomapMap(OctomapMap&& other) noexcept;
  OctomapMap& operator=(OctomapMap&& other) noexcept;
  OctomapMap(const OctomapMap&) = delete;
  OctomapMap& operator=(const OctomapMap&) = delete;
  ~OctomapMap();

  /// Integrates one frame: world-frame (W) hit and miss points seen from sensor origin origin_W
  /// (metres). Non-finite or out-of-extent points are ignored and counted. Error (map unchanged):
  /// origin_W non-finite or outside the tree's extent (+-3276.8 m at 0.1 m). Cost: O(sum of ray
  /// lengths / resolution) for the batch, then one search (+ one update when not clamped) per
  /// distinct voxel, O(tree depth) each.
  rt::Expected<InsertStats> insert(const octomap::Pointcloud& hits_W, const octomap::Pointcloud& misses_W,
                                   const Eigen::Vector3d& origin_W);

  /// Sets free (OctoMap's clamping minimum, as if seen empty many times) every occupied leaf voxel whose centre
  /// lies within radius_m of center_W_m horizontally and between min_z_m and max_z_m, and appends each to
  /// changes(). For the followed person's column (ExcludedBody): what was mapped there before anyone knew
  /// it was the person (before the lock-on, or while lost) is the person, not an obstacle. Returns how many it
  /// cleared; nothing for a column that is not finite or leaves the map's extent. Cost: the existing leaves in
  /// the column's box (free space is pruned, so few) plus one tree update per cleared voxel.
  std::size_t clearColumn(const Eigen::Vector2d& center_W_m, double radius_m, double min_z_m, double max_z_m);

  /// The tree, for queries. Editing it directly makes occupiedVoxelCount() stale until
  /// recountOccupiedVoxels(), and is not reported by changes().
  octomap::OcTree& tree() { return *tree_; }
  const octomap::OcTree& tree() const { return *tree_; }

  /// The voxels the latest insert created or flipped, each once, in the order it applied them, then those
  /// clearColumn cleared since (empty before the first insert and after a failed one). Valid until the next insert.
  const std::vector<VoxelChange>& changes() const;

  /// Occupied voxels at leaf resolution (a pruned inner node counts for every leaf voxel it
  /// covers), kept incrementally by insert(): O(1).
  std::size_t occupiedVoxelCount() const { return static_cast<std::size_t>(occupied_voxels_); }
  /// Recounts from the tree (O(leaves)) and returns the count; for after direct tree() edits.
  std::size_t recountOccupiedVoxels();
  std::uint64_t framesInserted() const { return frames_inserted_; }
  /// Stats of the latest successful insert (all zero before the first).
  const InsertStats& lastInsert() const { return last_insert_; }
  const OctomapMapParams& params() const { return params_; }

  /// A deep copy of the tree for readers on other threads (immutable; change detection off and
  /// its key list empty in the copy). Cost: O(nodes) time and a full copy of the tree's memory
  /// (tree().memoryUsage()), allocated node by node on every call. Measured (bench, 2-core dev
  /// machine): 130 000 nodes (3.6 MB, 10 m of forest flight) 10-16 ms; 1 000 000 nodes (28 MB,
  /// 100 m) ~165 ms. So take snapshots at a low rate or of a bounded map, not after every frame,
  /// and not on the insertion task's deadline. Call on the owner thread (it reads the tree).
  std::shared_ptr<const octomap::OcTree> snapshot() const;

 private:
  struct Workspace;
  OctomapMap(const OctomapMapParams& params, std::unique_ptr<octomap::OcTree> tree,
             std::unique_ptr<Workspace> workspace);

  OctomapMapParams params_;
  std::unique_ptr<octomap::OcTree> tree_;
  std::unique_ptr<Workspace> workspace_;
  std::int64_t occupied_voxels_ = 0;
  std::uint64_t frames_inserted_ = 0;
  InsertStats last_insert_;
};

/// Occupied voxels at leaf resolution in tree, by iterating its leaves: O(leaves). A reference
/// for OctomapMap::occupiedVoxelCount().
std::size_t countOccupiedVoxels(const octomap::OcTree& tree);

}  // namespace aerotrack::mapping
