// The mapper: see mapper.hpp.
#include "aerotrack/mapping/mapper.hpp"

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

rt::Expected<MapUpdate> Mapper::insert(const hal::DepthFrame& frame) {
  const auto report = inserter_->insert(frame, *poses_, *map_);
  if (!report) {
    ++stats_.frames_skipped_bad;
    return report.error();
  }
  if (report->status == FrameInsertStatus::kSkippedNoPose) {
    ++stats_.frames_skipped_no_pose;
    return rt::Error{toString(report->status)};
  }
  ++stats_.frames_inserted;
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
