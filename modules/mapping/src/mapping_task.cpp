// Mapping task and its config section: see mapping_task.hpp.
#include "aerotrack/mapping/mapping_task.hpp"

namespace aerotrack::mapping {

MapperParams parseMapperParams(const rt::ConfigNode& node) {
  MapperParams p;
  p.octomap.resolution_m = node.getDouble("resolution_m", 0.02, 1.0);
  p.grid.resolution_m = p.octomap.resolution_m;
  p.octomap.prob_hit = node.getDouble("prob_hit", 0.51, 0.99);
  p.octomap.prob_miss = node.getDouble("prob_miss", 0.01, 0.49);
  p.points.decimation = node.getInt("decimation", 1, 64);
  p.points.min_range_m = node.getDouble("min_range_m", 0.0, 5.0);
  p.points.max_range_m = node.getDouble("max_range_m", 0.5, 50.0);
  if (p.points.max_range_m <= p.points.min_range_m) node.fail("max_range_m", "must exceed min_range_m");
  const auto size = node.getDoubleList("grid_size_m", 3, 1.0, 200.0);
  p.grid.size_m = Eigen::Vector3d(size[0], size[1], size[2]);
  p.grid.inflation_radius_m = node.getDouble("inflation_radius_m", 0.0, 2.0);
  p.grid.unknown_is_occupied = node.getBool("unknown_is_occupied");
  p.grid.recenter_distance_m = node.getDouble("recenter_distance_m", 0.1, 50.0);
  p.octree_snapshot_every_n_frames = node.getInt("octree_snapshot_every_n_frames", 1, 1000);
  if (node.has("exclude_target")) {
    const rt::ConfigNode e = node.child("exclude_target");
    TargetExclusionParams& x = p.exclude_target;
    x.enabled = e.getBool("enabled");
    x.body_radius_m = e.getDouble("body_radius_m", 0.0, 5.0);
    x.sigmas = e.getDouble("sigmas", 0.0, 10.0);
    x.max_radius_m = e.getDouble("max_radius_m", 0.0, 10.0);
    if (x.max_radius_m < x.body_radius_m) e.fail("max_radius_m", "must be at least body_radius_m");
    x.floor_above_estimate_m = e.getDouble("floor_above_estimate_m", -5.0, 20.0);
    x.height_above_estimate_m = e.getDouble("height_above_estimate_m", -5.0, 20.0);
    if (x.height_above_estimate_m <= x.floor_above_estimate_m)
      e.fail("height_above_estimate_m", "must exceed floor_above_estimate_m");
    e.finish();
  }
  node.finish();
  return p;
}

bool MappingTask::gather(rt::TimeNs now_ns) {
  while (const auto sample = odometry_.try_pop()) mapper_.addOdometry(*sample);

  if (depth_.version() != depth_version_) {
    depth_version_ = depth_.version();
    if (auto frame = depth_.read()) {
      if (pending_count_ == pending_.size()) {  // far behind: drop the oldest waiting frame
        for (std::size_t i = 1; i < pending_count_; ++i) pending_[i - 1] = std::move(pending_[i]);
        --pending_count_;
        ++dropped_waiting_;
      }
      pending_[pending_count_++] = std::move(frame);
    }
  }

  // The frames that go in now: in order, those the pose history covers or that waited long enough.
  std::size_t ready = 0;
  for (; ready < pending_count_; ++ready) {
    const hal::DepthFrame& frame = *pending_[ready];
    const bool covered = mapper_.poses().size() > 0 && mapper_.poses().newest().stamp_ns >= frame.stamp_ns;
    if (!covered && now_ns - frame.stamp_ns < max_wait_ns_) break;  // odometry still on its way
  }
  for (std::size_t i = 0; i < ready; ++i) {
    ready_[i] = std::move(pending_[i]);
    ready_excluded_[i] = body_source_ ? body_source_(ready_[i]->stamp_ns) : std::nullopt;
  }
  ready_count_ = ready;
  for (std::size_t i = ready; i < pending_count_; ++i) pending_[i - ready] = std::move(pending_[i]);
  for (std::size_t i = pending_count_ - ready; i < pending_count_; ++i) pending_[i].reset();
  pending_count_ -= ready;
  return ready_count_ > 0;
}

void MappingTask::work() {
  outbox_count_ = 0;
  for (std::size_t i = 0; i < ready_count_; ++i) {
    const rt::TimeNs begin_ns = stats_clock_.now();
    std::span<const ExcludedBody> excluded;
    if (ready_excluded_[i]) excluded = std::span<const ExcludedBody>(&*ready_excluded_[i], 1);
    const auto update = mapper_.insert(*ready_[i], excluded);  // a frame that cannot be placed is counted there
    ready_[i].reset();
    if (!update) continue;
    const rt::TimeNs inserted_ns = stats_clock_.now();
    insert_stats_.recordRun(inserted_ns - begin_ns);
    Output& out = outbox_[outbox_count_++];
    out.grid = update->grid;
    if (mapper_.octreeDue()) {
      out.octree = mapper_.octreeSnapshot();
      snapshot_stats_.recordRun(stats_clock_.now() - inserted_ns);
    }
  }
  ready_count_ = 0;
}

void MappingTask::publish(rt::TimeNs /*publish_ns*/) {
  for (std::size_t i = 0; i < outbox_count_; ++i) {
    Output& out = outbox_[i];
    if (out.grid) grid_out_.write(std::move(out.grid));
    if (out.octree) octree_out_.write(std::move(out.octree));
    out = Output{};
  }
  outbox_count_ = 0;
}

}  // namespace aerotrack::mapping
