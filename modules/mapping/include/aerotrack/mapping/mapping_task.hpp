// Task glue for the mapper: drains the odometry stream into the pose history, inserts new depth
// frames and publishes the snapshots. Odometry arrives later than depth (its latency), so a frame
// whose capture time the history does not cover yet waits (up to max_wait) instead of being
// dropped; frames that cannot get a pose are skipped and counted. Insertion time is measured per
// inserted frame with a stats clock passed in (as the executors measure tasks), apart from the
// time the octree snapshots take, so that map_insert_ms is the cost of a frame, not of a run.
//
// An rt::OverlappedTask: gather() drains the odometry and takes the frames that are ready, work()
// inserts them (the lockstep executor runs it on a second thread when the task has a latency),
// publish() writes the grid and octree snapshots.
//
// The followed person is not an obstacle (ExcludedBody, depth_points.hpp): gather() asks, for each frame it
// takes, where the person was at the frame's capture time (excludeBodyFrom), and their returns clear space.
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <optional>

#include "aerotrack/mapping/mapper.hpp"
#include "aerotrack/rt/clock.hpp"
#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/shared_slot.hpp"
#include "aerotrack/rt/spsc_queue.hpp"
#include "aerotrack/rt/task.hpp"
#include "aerotrack/rt/timing_stats.hpp"

namespace aerotrack::mapping {

/// Reads the `mapping:` config section (throws rt::ConfigError naming the key).
MapperParams parseMapperParams(const rt::ConfigNode& node);

class MappingTask final : public rt::OverlappedTask {
 public:
  MappingTask(Mapper mapper, rt::SpscQueue<hal::OdometrySample>& odometry, const rt::SharedSlot<hal::DepthFrame>& depth,
              rt::SharedSlot<LocalGrid>& grid_out, rt::SharedSlot<octomap::OcTree>& octree_out,
              const rt::Clock& stats_clock, rt::DurationNs max_wait_ns = 200 * rt::kNsPerMillisecond)
      : stats_clock_(stats_clock),
        mapper_(std::move(mapper)),
        odometry_(odometry),
        depth_(depth),
        grid_out_(grid_out),
        octree_out_(octree_out),
        max_wait_ns_(max_wait_ns) {}

  /// Where the followed person's body is at a capture time (nothing: no one to exclude), called from gather()
  /// (the task's thread); the app reads the target estimate (estimation must not be a dependency of mapping).
  using BodySource = std::function<std::optional<ExcludedBody>(rt::TimeNs stamp_ns)>;
  void excludeBodyFrom(BodySource source) { body_source_ = std::move(source); }

  bool gather(rt::TimeNs now_ns) override;
  void work() override;
  void publish(rt::TimeNs publish_ns) override;
  const Mapper& mapper() const { return mapper_; }
  std::uint64_t framesDroppedWaiting() const { return dropped_waiting_; }
  /// Per inserted frame: insertion, grid update and grid snapshot (octree snapshots excluded).
  const rt::TimingStats& insertStats() const { return insert_stats_; }
  /// Per octree snapshot.
  const rt::TimingStats& snapshotStats() const { return snapshot_stats_; }

 private:
  const rt::Clock& stats_clock_;
  rt::TimingStats insert_stats_;
  rt::TimingStats snapshot_stats_;
  Mapper mapper_;
  rt::SpscQueue<hal::OdometrySample>& odometry_;
  const rt::SharedSlot<hal::DepthFrame>& depth_;
  rt::SharedSlot<LocalGrid>& grid_out_;
  rt::SharedSlot<octomap::OcTree>& octree_out_;
  rt::DurationNs max_wait_ns_;
  std::uint64_t depth_version_ = 0;
  std::array<rt::SharedSlot<hal::DepthFrame>::Handle, 8> pending_{};  // waiting for odometry, oldest first
  std::size_t pending_count_ = 0;
  std::uint64_t dropped_waiting_ = 0;
  // Between gather() and work(): the frames to insert, in order.
  std::array<rt::SharedSlot<hal::DepthFrame>::Handle, 8> ready_{};
  std::array<std::optional<ExcludedBody>, 8> ready_excluded_{};
  std::size_t ready_count_ = 0;
  BodySource body_source_;
  // Between work() and publish(): per inserted frame, its grid and (when due) the octree snapshot.
  struct Output {
    std::shared_ptr<const LocalGrid> grid;
    std::shared_ptr<const octomap::OcTree> octree;
  };
  std::array<Output, 8> outbox_{};
  std::size_t outbox_count_ = 0;
};

}  // namespace aerotrack::mapping
