// Planning task: see planning_task.hpp.
#include "aerotrack/planning/planning_task.hpp"

#include <algorithm>

namespace aerotrack::planning {
PlanningTask::PlanningTask(TrackingPlanner planner, const PlanningChannels& channels, const rt::Clock& stats_clock)
    : planner_(std::move(planner)),
      channels_(channels),
      stats_clock_(stats_clock),
      // + 1 piece: the brake to rest appended at the end
      trajectory_pool_(kTrajectoryPoolSize, TrajectoryStorage(planner_.params().corridor.max_boxes + 1)),
      timed_pool_(kTimedPoolSize, trajectory_server::TimedTrajectory{}) {
  const TrackingPlannerParams& p = planner_.params();
  if (auto search = RelocationSearch::create(p.relocation, p.person_sight_height_m, p.flight_altitude_m))
    relocation_search_.emplace(std::move(search.value()));
}

PlanningTask::Lent PlanningTask::lend() {
  Lent lent;
  lent.timed = timed_pool_.acquire();
  // A returned wrapper still holds the trajectory it carried last: release it before taking one, or every
  // free wrapper would keep a trajectory lent.
  lent.timed->trajectory.reset();
  lent.storage = trajectory_pool_.acquire();
  // Empty, as a new trajectory was: a cycle that fails before writing must not leave an old one in it.
  lent.storage->trajectory.assign(no_coefficients_, no_durations_);
  return lent;
}

double PlanningTask::meanCorridorBoxes() const {
  const std::uint64_t built = counts_[static_cast<std::size_t>(PlanStatus::kPlanned)] +
                              counts_[static_cast<std::size_t>(PlanStatus::kRelocating)] +
                              counts_[static_cast<std::size_t>(PlanStatus::kOptimizerFailed)] +
                              counts_[static_cast<std::size_t>(PlanStatus::kCheckFailed)];
  return built > 0 ? static_cast<double>(corridor_boxes_sum_) / static_cast<double>(built) : 0.0;
}

void PlanningTask::publish(Lent& lent, rt::TimeNs start_ns, rt::TimeNs source_capture_ns) {
  // The inner handle shares the storage slot's count (aliasing: no allocation), so the trajectory stays
  // lent while any copy of the wrapper's handle lives, wherever the wrapper itself has gone.
  const PolynomialTrajectory* trajectory = &lent.storage->trajectory;
  lent.timed->trajectory = std::shared_ptr<const trajectory_server::Trajectory>(std::move(lent.storage), trajectory);
  lent.timed->start_ns = start_ns;
  lent.timed->source_capture_ns = source_capture_ns;
  published_ = *lent.timed;
  channels_.trajectories.write(std::move(lent.timed));
}

// Hold and land act once, on entering the mode; search publishes nothing. Degraded (issue 21: planning
// failed cycle after cycle while the person is seen) brakes to rest once on entering, like hold, and then
// plans as in track, every cycle, so that the first plan that succeeds flies (and ends the mode). True
// when the cycle is done.
bool PlanningTask::handleMode(const supervisor::SupervisorState& state, const PlanInputs& inputs) {
  using supervisor::Mode;
  const Mode mode = state.mode;
  const bool entered = mode != last_mode_;
  last_mode_ = mode;
  if (mode == Mode::kDegraded && !entered) return false;
  if (mode == Mode::kSearch && state.reason == supervisor::Reason::kPathFlown) return false;  // plans (a search)
  if (mode != Mode::kHold && mode != Mode::kLand && mode != Mode::kSearch && mode != Mode::kDegraded) return false;
  if (!entered || mode == Mode::kSearch || inputs.odometry == nullptr) return true;
  const rt::TimeNs start_ns = inputs.now_ns + rt::secondsToNs(planner_.params().planning_budget_s);
  const StatePva start = planner_.startState(inputs, start_ns);
  Lent lent = lend();
  if (mode == Mode::kDegraded) {
    planner_.makeStopTrajectory(start, lent.storage->trajectory);
    ++degraded_brakes_;
  } else if (mode == Mode::kHold) {
    planner_.makeStopTrajectory(start, lent.storage->trajectory);
    ++holds_;
  } else {
    planner_.makeMoveTrajectory(start, Eigen::Vector3d(start(0, 0), start(1, 0), 0.0), lent.storage->trajectory);
    ++landings_;
  }
  publish(lent, start_ns, -1);
  return true;
}

void PlanningTask::step(rt::TimeNs now_ns) {
  ++cycles_;
  const std::optional<hal::OdometrySample> odometry = channels_.odometry.read();
  const std::optional<estimation::TargetEstimate> target = channels_.target.read();
  const auto grid = channels_.grid.read();
  const auto octree = channels_.octree.read();
  if (target) planner_.observeTarget(*target);
  if (target && target->initialised && !target->lost) last_live_target_ = *target;

  PlanInputs inputs;
  inputs.now_ns = now_ns;
  inputs.odometry = odometry ? &*odometry : nullptr;
  inputs.target = target ? &*target : nullptr;
  inputs.grid = grid.get();
  inputs.octree = octree.get();
  if (channels_.refused_start_ns != nullptr && published_.trajectory &&
      channels_.refused_start_ns->load(std::memory_order_acquire) == published_.start_ns) {
    published_ = {};  // the server refused it (late, issue 23): what is flown is not it, start from the odometry
    ++refused_by_server_;
  }
  inputs.current = published_.trajectory ? &published_ : nullptr;
  if (channels_.supervisor != nullptr) {
    if (const auto state = channels_.supervisor->read()) {
      if (handleMode(*state, inputs)) return;
      inputs.relocate = state->mode == supervisor::Mode::kRelocate;
      if (updateRelocationSearch(*state, inputs)) return;
    }
  }

  Lent lent = lend();
  const rt::TimeNs begin_ns = stats_clock_.now();
  const PlanReport report = planner_.plan(inputs, lent.storage->trajectory);
  last_report_ = report;
  const bool ran = report.status != PlanStatus::kNoOdometry && report.status != PlanStatus::kNoMap &&
                   report.status != PlanStatus::kNoTarget && report.status != PlanStatus::kTakeOff;
  if (ran) {
    const rt::DurationNs cycle_ns = stats_clock_.now() - begin_ns;
    cycle_stats_.recordRun(cycle_ns);
    if (channels_.snapshots != nullptr) {
      takeSnapshot(planner_, report, now_ns, rt::nsToSeconds(cycle_ns) * 1e3, snapshot_);
      channels_.snapshots->write(snapshot_);
    }
  }

  ++counts_[static_cast<std::size_t>(report.status)];
  if (report.search_status == SearchStatus::kPartial) ++search_partial_;
  if (report.status == PlanStatus::kSearchFailed) ++search_failures_[static_cast<std::size_t>(report.search_status)];
  // An evasion after a failed check counts that check's verdict, as a stop does.
  const bool failed_check = report.status == PlanStatus::kCheckFailed ||
                            ((report.status == PlanStatus::kStopped || report.status == PlanStatus::kEvading) &&
                             report.check != CheckVerdict::kOk);
  if (failed_check) ++check_failures_[static_cast<std::size_t>(report.check)];
  const bool checked =
      report.status == PlanStatus::kPlanned || report.status == PlanStatus::kRelocating || failed_check;
  if (checked) {
    ++checks_run_;
    if (report.check != CheckVerdict::kOk) ++checks_rejected_;
    const auto first = static_cast<std::size_t>(report.first_check);
    if (report.first_check == CheckVerdict::kOk) {
      ++checks_passed_first_time_;
    } else if (isDynamicLimit(report.first_check)) {
      if (report.check == CheckVerdict::kOk) {
        ++check_repairs_[first];
        max_repair_stretch_ = std::max(max_repair_stretch_, report.repair_stretch);
      } else {
        ++check_repair_failures_[first];
      }
    }
  }
  if (report.corridor_boxes > 0) corridor_boxes_sum_ += static_cast<std::uint64_t>(report.corridor_boxes);
  if (report.status == PlanStatus::kPlanned || report.status == PlanStatus::kRelocating ||
      report.status == PlanStatus::kCheckFailed) {
    if (report.optimizer_status == OptimizerStatus::kMaxIterations) ++optimizer_max_iterations_;
    if (report.optimizer_status == OptimizerStatus::kLineSearch) ++optimizer_line_search_;
  }
  const bool flies = report.status == PlanStatus::kPlanned || report.status == PlanStatus::kRelocating ||
                     report.status == PlanStatus::kStopped || report.status == PlanStatus::kTakeOff ||
                     report.status == PlanStatus::kEvading || report.status == PlanStatus::kEscaping;
  // The plan used the estimate's newest measurement (tracking) or none (relocation, stop, take-off).
  const bool tracked = report.status == PlanStatus::kPlanned && target && target->initialised && !target->lost;
  if (flies) publish(lent, report.start_ns, tracked ? target->last_accepted_ns : -1);
  const bool failed = report.status == PlanStatus::kStopped || report.status == PlanStatus::kSearchFailed ||
                      report.status == PlanStatus::kCorridorFailed || report.status == PlanStatus::kOptimizerFailed ||
                      report.status == PlanStatus::kCheckFailed;
  failures_in_a_row_ = failed ? failures_in_a_row_ + 1 : 0;
  if (channels_.failures_in_a_row != nullptr)
    channels_.failures_in_a_row->store(failures_in_a_row_, std::memory_order_relaxed);
}

// The search pattern runs while relocating (what the camera sees along the predicted path counts) and in the
// search after it, where its viewpoint is the plan's goal; a search cycle without one publishes nothing (the
// drone holds the end of its last trajectory, the gimbal sweeping). Any other mode ends it.
bool PlanningTask::updateRelocationSearch(const supervisor::SupervisorState& state, PlanInputs& inputs) {
  const bool searching = state.mode == supervisor::Mode::kSearch && state.reason == supervisor::Reason::kPathFlown;
  if (!relocation_search_ || (state.mode != supervisor::Mode::kRelocate && !searching)) {
    if (relocation_search_) relocation_search_->stop();
    viewpoint_.reset();
    return false;
  }
  if (!relocation_search_->active() && last_live_target_)
    relocation_search_->start(last_live_target_->p_WT_m, last_live_target_->v_WT_mps,
                              last_live_target_->last_accepted_ns);
  if (inputs.odometry != nullptr && inputs.grid != nullptr) {
    const rt::TimeNs begin_ns = stats_clock_.now();
    viewpoint_ = relocation_search_->update(*inputs.grid, inputs.odometry->p_WB_m, inputs.now_ns);
    search_update_max_ns_ = std::max(search_update_max_ns_, stats_clock_.now() - begin_ns);
  }
  if (!searching) return false;
  if (!viewpoint_) {
    ++search_idle_cycles_;
    return true;
  }
  ++search_cycles_;
  inputs.look = &*viewpoint_;
  return false;
}

}  // namespace aerotrack::planning
