// Task glue for the tracking planner (issue 8 item 4): at a fixed rate (default 20 Hz; the paper
// replans at 13 Hz) it reads the newest odometry, person estimate, local grid and octree snapshot, runs
// one TrackingPlanner cycle and publishes the trajectory for the trajectory server, which switches to
// it at its start time. Each cycle writes a new trajectory object (one allocation per cycle; see
// freeEntry() for why reuse by use_count is not safe). The cycle's time (prediction
// + search + corridor + optimisation + check) is measured with a stats clock passed in, as the executors
// measure tasks; it is what summary.json reports as the planning time.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include <octomap/OcTree.h>

#include "aerotrack/estimation/target_estimator.hpp"
#include "aerotrack/hal/types.hpp"
#include "aerotrack/mapping/local_grid.hpp"
#include "aerotrack/planning/tracking_planner.hpp"
#include "aerotrack/rt/clock.hpp"
#include "aerotrack/rt/latest_slot.hpp"
#include "aerotrack/rt/shared_slot.hpp"
#include "aerotrack/rt/task.hpp"
#include "aerotrack/rt/timing_stats.hpp"
#include "aerotrack/supervisor/supervisor.hpp"
#include "aerotrack/trajectory_server/trajectory.hpp"

namespace aerotrack::planning {

struct PlanningChannels {
  const rt::LatestSlot<hal::OdometrySample>& odometry;
  const rt::LatestSlot<estimation::TargetEstimate>& target;
  const rt::SharedSlot<mapping::LocalGrid>& grid;
  const rt::SharedSlot<octomap::OcTree>& octree;
  rt::SharedSlot<trajectory_server::TimedTrajectory>& trajectories;
  /// The supervisor's mode (optional: without it the task always tracks). In search it publishes
  /// nothing (the drone hovers while the gimbal sweeps), in relocate it plans along the last prediction,
  /// in hold it brakes once and then publishes nothing, in land it descends once.
  const rt::LatestSlot<supervisor::SupervisorState>* supervisor = nullptr;
  /// Where it counts its failed cycles in a row, for the supervisor (optional).
  std::atomic<int>* failures_in_a_row = nullptr;
};

class PlanningTask final : public rt::Task {
 public:
  PlanningTask(TrackingPlanner planner, const PlanningChannels& channels, const rt::Clock& stats_clock);

  void step(rt::TimeNs now_ns) override;

  TrackingPlanner& planner() { return planner_; }
  /// Cycles by outcome (index: PlanStatus).
  std::uint64_t count(PlanStatus status) const { return counts_[static_cast<std::size_t>(status)]; }
  std::uint64_t cycles() const { return cycles_; }
  /// Time of the cycles that ran the planner (a target and a map were there), measured by the stats clock.
  const rt::TimingStats& cycleStats() const { return cycle_stats_; }
  std::uint64_t searchPartial() const { return search_partial_; }
  /// Failed searches by how they ended (index: SearchStatus).
  std::uint64_t searchFailures(SearchStatus status) const { return search_failures_[static_cast<std::size_t>(status)]; }
  /// Failed final checks by verdict (CheckVerdict).
  std::uint64_t checkFailures(CheckVerdict verdict) const { return check_failures_[static_cast<std::size_t>(verdict)]; }
  std::uint64_t optimizerMaxIterations() const { return optimizer_max_iterations_; }
  std::uint64_t optimizerLineSearch() const { return optimizer_line_search_; }
  double meanCorridorBoxes() const;
  /// Brakes published on entering hold, and descents on entering land.
  std::uint64_t holds() const { return holds_; }
  std::uint64_t landings() const { return landings_; }
  /// Trajectory objects allocated (one per cycle that ran).
  std::uint64_t poolGrowths() const { return pool_growths_; }
  /// The last trajectory published, empty before the first.
  const trajectory_server::TimedTrajectory& lastPublished() const { return published_; }

 private:
  struct PoolEntry {
    std::shared_ptr<PolynomialTrajectory> trajectory;
    std::shared_ptr<trajectory_server::TimedTrajectory> timed;  // always points at `trajectory`
  };
  PoolEntry& freeEntry();
  static PoolEntry makeEntry(int max_pieces);

  TrackingPlanner planner_;
  PlanningChannels channels_;
  const rt::Clock& stats_clock_;
  PoolEntry next_;  ///< The trajectory this cycle writes (new every cycle).
  trajectory_server::TimedTrajectory published_;
  std::array<std::uint64_t, kPlanStatusCount> counts_{};
  std::uint64_t cycles_ = 0;
  std::uint64_t search_partial_ = 0;
  std::array<std::uint64_t, 5> search_failures_{};
  std::array<std::uint64_t, 8> check_failures_{};  // by CheckVerdict
  std::uint64_t optimizer_max_iterations_ = 0;
  std::uint64_t optimizer_line_search_ = 0;
  std::uint64_t corridor_boxes_sum_ = 0;
  std::uint64_t pool_growths_ = 0;
  std::uint64_t holds_ = 0;
  std::uint64_t landings_ = 0;
  int failures_in_a_row_ = 0;
  supervisor::Mode last_mode_ = supervisor::Mode::kTakeOff;
  void publish(PoolEntry& entry, rt::TimeNs start_ns, rt::TimeNs source_capture_ns);
  bool handleMode(supervisor::Mode mode, const PlanInputs& inputs);
  rt::TimingStats cycle_stats_;
};

}  // namespace aerotrack::planning
