// Task glue for the tracking planner (issue 8 item 4): at a fixed rate (default 20 Hz; the paper
// replans at 13 Hz) it reads the newest odometry, person estimate, local grid and octree snapshot, runs
// one TrackingPlanner cycle and publishes the trajectory for the trajectory server, which switches to
// it at its start time. The cycle's time (prediction + search + corridor + optimisation + check) is
// measured with a stats clock passed in, as the executors measure tasks; it is what summary.json reports
// as the planning time.
//
// No allocation once warm (DESIGN.md rule 4): what a cycle publishes is lent from two rt::LendingPools,
// one of TimedTrajectory wrappers (what the channel carries) and one of PolynomialTrajectory storage
// (what the wrapper's inner handle points at, aliased into its pooled slot). The two are separate
// because readers copy the wrapper by value (the trajectory server keeps current_ and pending_ copies):
// the inner trajectory must stay lent as long as any such copy lives, not just the wrapper. A free
// wrapper keeps its inner handle (the pool does not touch returned objects), so each cycle takes a
// wrapper first and drops that handle before it takes a trajectory. An object goes back to its pool
// when its last handle is dropped, on any thread, with a release/acquire edge (see lending_pool.hpp),
// so the planner never rewrites a trajectory a reader still holds.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include <octomap/OcTree.h>

#include "aerotrack/estimation/target_estimator.hpp"
#include "aerotrack/hal/types.hpp"
#include "aerotrack/mapping/local_grid.hpp"
#include "aerotrack/planning/plan_snapshot.hpp"
#include "aerotrack/planning/tracking_planner.hpp"
#include "aerotrack/rt/clock.hpp"
#include "aerotrack/rt/latest_slot.hpp"
#include "aerotrack/rt/lending_pool.hpp"
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
  /// nothing (the drone hovers while the gimbal sweeps), except in the search after a relocation (reason
  /// kPathFlown, issue 21 item 3), where it flies to the viewpoints of its RelocationSearch (which starts on
  /// entering relocate, from the last live estimate, and marks what the camera sees from then on); in relocate
  /// it plans along the last prediction,
  /// in hold it brakes once and then publishes nothing, in land it descends once, in degraded (issue 21) it
  /// brakes once and then plans as in track, every cycle.
  const rt::LatestSlot<supervisor::SupervisorState>* supervisor = nullptr;
  /// Where it counts its failed cycles in a row, for the supervisor (optional).
  std::atomic<int>* failures_in_a_row = nullptr;
  /// The start time of the newest trajectory the server refused for taking over late (optional; -1: none).
  /// When it is the task's own newest, that one is not flown: the next plan starts from the odometry.
  const std::atomic<rt::TimeNs>* refused_start_ns = nullptr;
  /// Where each cycle that ran the planner publishes what it found, for the flight log (optional).
  rt::LatestSlot<PlanSnapshot>* snapshots = nullptr;
};

class PlanningTask final : public rt::Task {
 public:
  PlanningTask(TrackingPlanner planner, const PlanningChannels& channels, const rt::Clock& stats_clock);

  void step(rt::TimeNs now_ns) override;

  TrackingPlanner& planner() { return planner_; }
  /// Cycles by outcome (index: PlanStatus).
  std::uint64_t count(PlanStatus status) const { return counts_[static_cast<std::size_t>(status)]; }
  std::uint64_t cycles() const { return cycles_; }
  /// Its trajectories the server refused for taking over late (seen by the next cycle).
  std::uint64_t refusedByServer() const { return refused_by_server_; }
  /// Time of the cycles that ran the planner (a target and a map were there), measured by the stats clock.
  const rt::TimingStats& cycleStats() const { return cycle_stats_; }
  std::uint64_t searchPartial() const { return search_partial_; }
  /// Failed searches by how they ended (index: SearchStatus).
  std::uint64_t searchFailures(SearchStatus status) const { return search_failures_[static_cast<std::size_t>(status)]; }
  /// Failed final checks (rejected after any repair) by their final verdict (CheckVerdict).
  std::uint64_t checkFailures(CheckVerdict verdict) const { return check_failures_[static_cast<std::size_t>(verdict)]; }
  /// Final checks run (an optimised trajectory reached stage 6), and those passed without repair.
  std::uint64_t checksRun() const { return checks_run_; }
  std::uint64_t checksPassedFirstTime() const { return checks_passed_first_time_; }
  /// Final checks whose trajectory was thrown away (after any repair; a stop may have been flown instead).
  std::uint64_t checksRejected() const { return checks_rejected_; }
  /// Trajectories repaired (re-timed, then passed) by the verdict of their first check (issue 21).
  std::uint64_t checkRepairs(CheckVerdict first) const { return check_repairs_[static_cast<std::size_t>(first)]; }
  /// Repairs tried and failed (rejected anyway) by the verdict of their first check.
  std::uint64_t checkRepairFailures(CheckVerdict first) const {
    return check_repair_failures_[static_cast<std::size_t>(first)];
  }
  /// The largest time stretch a successful repair applied (1: none yet).
  double maxRepairStretch() const { return max_repair_stretch_; }
  std::uint64_t optimizerMaxIterations() const { return optimizer_max_iterations_; }
  std::uint64_t optimizerLineSearch() const { return optimizer_line_search_; }
  double meanCorridorBoxes() const;
  /// Brakes published on entering hold, and descents on entering land.
  std::uint64_t holds() const { return holds_; }
  /// Brakes to rest on entering the supervisor's degraded mode (issue 21).
  std::uint64_t degradedBrakes() const { return degraded_brakes_; }
  /// The relocation's search pattern (issue 21 item 3; null if it could not be created).
  const RelocationSearch* relocationSearch() const { return relocation_search_ ? &*relocation_search_ : nullptr; }
  /// Cycles of the search after a relocation that planned towards a viewpoint, and those with none to fly to.
  std::uint64_t searchCycles() const { return search_cycles_; }
  std::uint64_t searchIdleCycles() const { return search_idle_cycles_; }
  /// The longest update of the search pattern (belief, look, any viewpoint choice), by the stats clock (ms).
  double searchUpdateMaxMs() const { return rt::nsToSeconds(search_update_max_ns_) * 1e3; }
  std::uint64_t landings() const { return landings_; }
  /// Objects the trajectory pools added after start-up because all of theirs were lent (the only
  /// allocations of the task once warm; they stop once the pools are as large as the readers need).
  std::uint64_t poolGrowths() const { return trajectory_pool_.growths() + timed_pool_.growths(); }
  /// The last trajectory published, empty before the first.
  const trajectory_server::TimedTrajectory& lastPublished() const { return published_; }
  /// The report of the last cycle that ran TrackingPlanner::plan (a default one before the first; hold,
  /// land and search cycles do not plan and leave it as it was).
  const PlanReport& lastReport() const { return last_report_; }

  /// Objects each pool starts with: the channel, the recorder and the trajectory server's current and
  /// pending copies hold a few at a time, and every free wrapper may still pin one trajectory.
  static constexpr std::size_t kTimedPoolSize = 4;
  static constexpr std::size_t kTrajectoryPoolSize = 8;

 private:
  /// A pooled trajectory whose storage is reserved for max_pieces pieces. The pool fills its slots by
  /// copying a prototype, and a copied std::vector keeps no spare capacity: a copy reserves afresh.
  struct TrajectoryStorage {
    explicit TrajectoryStorage(int pieces) : trajectory(pieces), max_pieces(pieces) {}
    TrajectoryStorage(const TrajectoryStorage& other) : trajectory(other.max_pieces), max_pieces(other.max_pieces) {}
    TrajectoryStorage(TrajectoryStorage&&) = delete;
    TrajectoryStorage& operator=(const TrajectoryStorage&) = delete;
    TrajectoryStorage& operator=(TrajectoryStorage&&) = delete;
    ~TrajectoryStorage() = default;
    PolynomialTrajectory trajectory;
    int max_pieces;
  };
  /// What one cycle writes, lent from the pools: the wrapper (its inner handle already dropped) and an
  /// empty trajectory. Whatever is not published goes back when the cycle drops it.
  struct Lent {
    std::shared_ptr<trajectory_server::TimedTrajectory> timed;
    std::shared_ptr<TrajectoryStorage> storage;
  };
  Lent lend();

  TrackingPlanner planner_;
  PlanningChannels channels_;
  const rt::Clock& stats_clock_;
  rt::LendingPool<TrajectoryStorage> trajectory_pool_;
  rt::LendingPool<trajectory_server::TimedTrajectory> timed_pool_;
  const RowMatrixX3d no_coefficients_ = RowMatrixX3d(0, 3);  ///< Empties a lent trajectory (no allocation).
  const Eigen::VectorXd no_durations_ = Eigen::VectorXd(0);
  trajectory_server::TimedTrajectory published_;
  PlanReport last_report_;
  PlanSnapshot snapshot_;  ///< Filled, then published (kept here: 3.5 kB is too much for the stack of every cycle).
  std::array<std::uint64_t, kPlanStatusCount> counts_{};
  std::uint64_t cycles_ = 0;
  std::uint64_t refused_by_server_ = 0;
  std::uint64_t search_partial_ = 0;
  std::array<std::uint64_t, 5> search_failures_{};
  std::array<std::uint64_t, kCheckVerdictCount> check_failures_{};         // by final CheckVerdict
  std::array<std::uint64_t, kCheckVerdictCount> check_repairs_{};          // by first CheckVerdict
  std::array<std::uint64_t, kCheckVerdictCount> check_repair_failures_{};  // by first CheckVerdict
  std::uint64_t checks_run_ = 0;
  std::uint64_t checks_passed_first_time_ = 0;
  std::uint64_t checks_rejected_ = 0;
  double max_repair_stretch_ = 1.0;
  std::uint64_t optimizer_max_iterations_ = 0;
  std::uint64_t optimizer_line_search_ = 0;
  std::uint64_t corridor_boxes_sum_ = 0;
  std::uint64_t holds_ = 0;
  std::uint64_t landings_ = 0;
  int failures_in_a_row_ = 0;
  supervisor::Mode last_mode_ = supervisor::Mode::kTakeOff;
  std::uint64_t degraded_brakes_ = 0;  ///< Brakes to rest on entering degraded (issue 21).
  void publish(Lent& lent, rt::TimeNs start_ns, rt::TimeNs source_capture_ns);
  bool handleMode(const supervisor::SupervisorState& state, const PlanInputs& inputs);
  /// Relocating or searching after it: runs the search pattern; true when a search cycle has no viewpoint.
  bool updateRelocationSearch(const supervisor::SupervisorState& state, PlanInputs& inputs);
  std::optional<RelocationSearch> relocation_search_;
  std::optional<estimation::TargetEstimate> last_live_target_;  ///< Where the search starts from.
  std::optional<Viewpoint> viewpoint_;
  std::uint64_t search_cycles_ = 0;
  std::uint64_t search_idle_cycles_ = 0;
  rt::TimeNs search_update_max_ns_ = 0;
  rt::TimingStats cycle_stats_;
};

}  // namespace aerotrack::planning
