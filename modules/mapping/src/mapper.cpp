// The mapper: see mapper.hpp.
#include "aerotrack/mapping/mapper.hpp"

#include <algorithm>
#include <cmath>

namespace aerotrack::mapping {

rt::Expected<Mapper> Mapper::create(const MapperParams& params) {
  if (params.grid_pool_size < 1) return rt::Error{"mapping: grid_pool_size must be >= 1"};
  if (params.octree_snapshot_every_n_frames < 1)
    return rt::Error{"mapping: octree_snapshot_every_n_frames must be >= 1"};
  if (std::abs(params.grid.resolution_m - params.octomap.resolution_m) > 1e-9)
    return rt::Error{"mapping: the local grid's resolution must equal the octree's"};
  auto poses = PoseHistory::create(params.poses);
  if (!poses) return rt::Error{"mapping: " + poses.error().message};
  auto inserter = FrameInserter::create(params.points);
  if (!inserter) return rt::Error{"mapping: " + inserter.error().message};
  auto map = OctomapMap::create(params.octomap);
  if (!map) return rt::Error{"mapping: " + map.error().message};
  auto grid = LocalGrid::create(params.grid);
  if (!grid) return rt::Error{"mapping: " + grid.error().message};
  Mapper m(params);
  m.poses_ = std::make_unique<PoseHistory>(std::move(poses.value()));
  m.inserter_ = std::make_unique<FrameInserter>(std::move(inserter.value()));
  m.map_ = std::make_unique<OctomapMap>(std::move(map.value()));
  m.grid_ = std::make_unique<LocalGrid>(std::move(grid.value()));
  m.pool_ = std::make_unique<rt::LendingPool<LocalGrid>>(params.grid_pool_size, *m.grid_);
  return m;
}

void Mapper::addOdometry(const hal::OdometrySample& sample) {
  if (poses_->push(sample) != PushResult::kAccepted) ++stats_.odometry_rejected;
}

std::shared_ptr<const LocalGrid> Mapper::publishGrid() {
  // A grid no reader holds any more is rewritten in place; readers keep theirs as long as they like.
  std::shared_ptr<LocalGrid> g = pool_->acquire();
  g->copyChangesFrom(*grid_);  // only the rows written since this pool grid was last published
  stats_.grid_snapshots_allocated = pool_->growths();
  return g;
}

std::optional<ExcludedBody> bodyAround(const Eigen::Vector3d& p_W_m, const Eigen::Matrix2d& cov_xy_m2,
                                       const TargetExclusionParams& params) {
  if (!params.enabled || !p_W_m.allFinite() || !cov_xy_m2.allFinite()) return std::nullopt;
  // The larger eigenvalue of the symmetric 2 x 2 covariance: its major axis's variance.
  const double mean = 0.5 * (cov_xy_m2(0, 0) + cov_xy_m2(1, 1));
  const double half_diff = 0.5 * (cov_xy_m2(0, 0) - cov_xy_m2(1, 1));
  const double major_var = mean + std::sqrt(half_diff * half_diff + cov_xy_m2(0, 1) * cov_xy_m2(1, 0));
  ExcludedBody body;
  body.center_W_m = p_W_m.head<2>();
  body.radius_m = params.body_radius_m + params.sigmas * std::sqrt(std::max(0.0, major_var));
  if (!(body.radius_m <= params.max_radius_m)) return std::nullopt;
  body.min_z_m = p_W_m.z() + params.floor_above_estimate_m;
  body.max_z_m = p_W_m.z() + params.height_above_estimate_m;
  return body;
}

rt::Expected<MapUpdate> Mapper::insert(const hal::DepthFrame& frame, std::span<const ExcludedBody> excluded) {
  const auto report = inserter_->insert(frame, *poses_, *map_, excluded);
  if (!report) {
    ++stats_.frames_skipped_bad;
    return report.error();
  }
  if (report->status == FrameInsertStatus::kSkippedNoPose) {
    ++stats_.frames_skipped_no_pose;
    return rt::Error{toString(report->status)};
  }
  ++stats_.frames_inserted;
  stats_.returns_excluded += report->points.excluded;
  for (const ExcludedBody& body : excluded)
    stats_.voxels_cleared += map_->clearColumn(body.center_W_m, body.radius_m, body.min_z_m, body.max_z_m);
  const octomap::OcTree& tree = map_->tree();
  // Keep the window on the drone: the pose at the frame's time is known (the insert used it).
  const Eigen::Vector3d drone_W_m = poses_->valueAt(frame.stamp_ns)->translation();
  if (!grid_initialised_) {
    if (auto moved = grid_->recenter(drone_W_m, tree); !moved) return moved.error();
    if (rt::Status s = grid_->rebuild(tree); !s) return s.error();
    grid_initialised_ = true;
  } else {
    // Only what this insert changed (the window already holds the rest): no tree searches.
    for (const VoxelChange& change : map_->changes())
      grid_->setVoxel(change.key, change.occupied ? CellState::kOccupied : CellState::kFree);
    if (auto moved = grid_->recenter(drone_W_m, tree); !moved) return moved.error();
  }
  stats_.occupied_voxels = map_->occupiedVoxelCount();

  MapUpdate update;
  update.grid = publishGrid();
  return update;
}

bool Mapper::octreeDue() const {
  const auto n = static_cast<std::uint64_t>(params_.octree_snapshot_every_n_frames);
  return stats_.frames_inserted > 0 && (stats_.frames_inserted - 1) % n == 0;
}

std::shared_ptr<const octomap::OcTree> Mapper::octreeSnapshot() const {
  const CellBox box = grid_->windowBox();
  const double res = params_.grid.resolution_m;
  return occupiedSnapshot(map_->tree(), box.lo.cast<double>() * res, box.hi.cast<double>() * res);
}

}  // namespace aerotrack::mapping
