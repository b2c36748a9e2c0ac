// The mapper (issue 4; paper Sect. III: voxel occupancy grids built from the depth camera): each
// depth frame is placed in the world with the drone's pose at the frame's capture time
// (interpolated from the odometry history, not the latest pose), inserted into the OctoMap with
// free-space clearing, and the dense local grid around the drone is brought up to date with only
// the voxels that changed. Readers on other threads get immutable snapshots: the local grid after
// every frame (from a small pool, so publishing does not allocate once warm) and, less often, a
// copy of the octree for the final FCL check of trajectories.
//
// Pure: time comes in, nothing is printed; one thread calls it (the mapping task).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/mapping/depth_points.hpp"
#include "aerotrack/mapping/frame_inserter.hpp"
#include "aerotrack/mapping/local_grid.hpp"
#include "aerotrack/mapping/octomap_map.hpp"
#include "aerotrack/mapping/pose_history.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/lending_pool.hpp"

namespace aerotrack::mapping {

/// How wide a column the followed person's returns are left out of (`mapping.exclude_target`).
struct TargetExclusionParams {
  bool enabled = true;
  double body_radius_m = 0.35;           ///< The body's half width with swinging arms (a person is ~0.5 m wide)...
  double sigmas = 2.0;                   ///< ... plus this many standard deviations of the estimate's position;
  double max_radius_m = 0.7;             ///< wider than this: too uncertain, nothing is excluded.
  double floor_above_estimate_m = 0.5;   ///< The column's foot above the estimate's z (below: the ground, kept)...
  double height_above_estimate_m = 2.5;  ///< ... and its top.
};

/// The column of `params` around a person estimated at p_W_m (xy covariance cov_xy_m2): radius body_radius_m
/// plus `sigmas` standard deviations along the covariance's major axis; from floor_above_estimate_m to
/// height_above_estimate_m above p_W_m's z. Nothing if disabled, the estimate is not finite, or the radius
/// would exceed max_radius_m: an uncertain estimate (the person hidden round a corner) must not erase the wall
/// beside them -- better the person mapped for a moment than a wall unmapped. Pure.
std::optional<ExcludedBody> bodyAround(const Eigen::Vector3d& p_W_m, const Eigen::Matrix2d& cov_xy_m2,
                                       const TargetExclusionParams& params);

struct MapperParams {
  OctomapMapParams octomap;
  DepthPointsParams points;
  LocalGridParams grid;
  PoseHistoryParams poses;
  std::size_t grid_pool_size = 3;           ///< Grid snapshots in flight before one is allocated.
  int octree_snapshot_every_n_frames = 15;  ///< Publish an octree snapshot every n-th frame.
  TargetExclusionParams exclude_target;     ///< Used by the app's wiring of the mapping task.
};

struct MapperStats {
  std::uint64_t frames_inserted = 0;
  std::uint64_t frames_skipped_no_pose = 0;
  std::uint64_t frames_skipped_bad = 0;  ///< Malformed depth images, or a camera outside the map.
  std::uint64_t returns_excluded = 0;    ///< Depth returns on an excluded body (the followed person).
  std::uint64_t voxels_cleared = 0;      ///< Occupied voxels found inside an excluded body's column, set free.
  std::uint64_t odometry_rejected = 0;   ///< Out of order or not finite.
  std::uint64_t grid_snapshots_allocated = 0;
  std::size_t occupied_voxels = 0;
};

/// The occupied voxels of tree inside the box [min_W_m, max_W_m) (the voxels of the cells
/// floor(min / res) .. floor(max / res) - 1), as a new octree with the same resolution and
/// thresholds: occupied leaves keep their log-odds, coarse (pruned) ones stay coarse unless they
/// cross the box's faces, inner nodes hold their children's maximum. This is what the FCL check of
/// a trajectory needs; a deep copy of the whole tree would also copy every free voxel ever seen
/// (~120 ms for a 40 x 40 m forest). Cost: the nodes on the paths to the copied leaves; free
/// subtrees are skipped whole. Allocates the new tree. Requires inner nodes at their children's
/// maximum (OctoMap's invariant, kept by OctomapMap::insert).
std::shared_ptr<const octomap::OcTree> occupiedSnapshot(const octomap::OcTree& tree, const Eigen::Vector3d& min_W_m,
                                                        const Eigen::Vector3d& max_W_m);

/// What one frame produced for readers: handles to immutable snapshots (null if not refreshed).
struct MapUpdate {
  std::shared_ptr<const LocalGrid> grid;
};

class Mapper {
 public:
  static rt::Expected<Mapper> create(const MapperParams& params);

  /// Adds an odometry sample to the pose history (time order; others are rejected and counted).
  void addOdometry(const hal::OdometrySample& sample);

  /// Inserts one depth frame. Error (and nothing changes) if the pose at its capture time is
  /// unknown or the image is unusable; the stats count why. The update carries the new grid
  /// snapshot; octreeDue() says whether an octree snapshot should follow. Returns inside `excluded` (the
  /// followed person) are not obstacles (depthToPoints), and what the map holds inside them is cleared
  /// (OctomapMap::clearColumn).
  rt::Expected<MapUpdate> insert(const hal::DepthFrame& frame, std::span<const ExcludedBody> excluded = {});
  bool octreeDue() const;
  /// The occupied voxels of the local window as a new octree (occupiedSnapshot()).
  std::shared_ptr<const octomap::OcTree> octreeSnapshot() const;

  const MapperStats& stats() const { return stats_; }
  const OctomapMap& octomap() const { return *map_; }
  const LocalGrid& grid() const { return *grid_; }
  const PoseHistory& poses() const { return *poses_; }

 private:
  explicit Mapper(const MapperParams& params) : params_(params) {}
  std::shared_ptr<const LocalGrid> publishGrid();

  MapperParams params_;
  std::unique_ptr<PoseHistory> poses_;
  std::unique_ptr<FrameInserter> inserter_;
  std::unique_ptr<OctomapMap> map_;
  std::unique_ptr<LocalGrid> grid_;
  std::unique_ptr<rt::LendingPool<LocalGrid>> pool_;
  MapperStats stats_;
  bool grid_initialised_ = false;
};

}  // namespace aerotrack::mapping
