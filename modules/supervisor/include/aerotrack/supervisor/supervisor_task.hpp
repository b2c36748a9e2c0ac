// Task glue for the supervisor (50 Hz in the task table): reads the health of every stream --
// the newest odometry, depth image and gimbal-camera frame, the person estimate, the planner's failures
// in a row, the real-time executor's missed deadlines, the vehicle link's loss -- updates the mode machine, publishes
// the mode for the planner, and asks the gimbal to sweep while searching, relocating or holding because the person was
// not found (when sweeping is enabled: the baseline mode has a fixed camera). It logs every relocation: when it began,
// when its timeout ran out and the search began (if it did), and how it ended -- found while relocating, found while
// searching, not found (the search timed out), failsafe, landed (issue 21: the summary says how each search went).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>

#include "aerotrack/estimation/target_estimator.hpp"
#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/latest_slot.hpp"
#include "aerotrack/rt/shared_slot.hpp"
#include "aerotrack/rt/task.hpp"
#include "aerotrack/supervisor/supervisor.hpp"

namespace aerotrack::supervisor {

struct SupervisorChannels {
  const rt::LatestSlot<hal::OdometrySample>& odometry;
  const rt::SharedSlot<hal::DepthFrame>& depth;
  const std::atomic<rt::TimeNs>& newest_camera_frame_ns;
  const rt::LatestSlot<hal::GimbalState>& gimbal_state;
  const rt::LatestSlot<estimation::TargetEstimate>& target;
  const std::atomic<int>& planner_failures_in_a_row;
  const std::atomic<std::uint64_t>& deadline_misses;  ///< Periods skipped by the real-time executor (0 in lockstep).
  const std::atomic<bool>& vehicle_link_lost;         ///< Set by the trajectory server from the link's status.
  rt::LatestSlot<SupervisorState>& out;
  std::atomic<bool>& gimbal_search_requested;
};

class SupervisorTask final : public rt::Task {
 public:
  SupervisorTask(const SupervisorParams& params, rt::TimeNs start_ns, const SupervisorChannels& channels,
                 bool sweep_when_searching)
      : supervisor_(params, start_ns), channels_(channels), sweep_(sweep_when_searching) {}

  void step(rt::TimeNs now_ns) override {
    SupervisorInputs in;
    in.now_ns = now_ns;
    if (const auto odometry = channels_.odometry.read()) {
      in.odometry_stamp_ns = odometry->stamp_ns;
      in.altitude_m = odometry->p_WB_m.z();
    }
    if (const auto depth = channels_.depth.read()) in.depth_stamp_ns = depth->stamp_ns;
    in.camera_stamp_ns = channels_.newest_camera_frame_ns.load(std::memory_order_relaxed);
    if (const auto gimbal = channels_.gimbal_state.read()) in.gimbal_stamp_ns = gimbal->stamp_ns;
    if (const auto target = channels_.target.read(); target && target->initialised) {
      in.person_live = !target->lost;
      in.person_accepted_ns = target->last_accepted_ns;
    }
    in.planner_failures_in_a_row = channels_.planner_failures_in_a_row.load(std::memory_order_relaxed);
    in.deadline_overruns = channels_.deadline_misses.load(std::memory_order_relaxed);
    in.vehicle_link_lost = channels_.vehicle_link_lost.load(std::memory_order_relaxed);
    const SupervisorState& state = supervisor_.update(in);
    channels_.out.write(state);
    const bool searching = state.mode == Mode::kSearch || state.mode == Mode::kRelocate ||
                           (state.mode == Mode::kHold && state.reason == Reason::kPersonNotFound);
    channels_.gimbal_search_requested.store(sweep_ && searching, std::memory_order_relaxed);
    if (state.transitions != last_transitions_) {
      last_transitions_ = state.transitions;
      if (log_count_ < log_.size()) log_[log_count_++] = {now_ns, state.mode, state.reason};
      logRelocation(state, now_ns);
    }
    ++mode_steps_[static_cast<std::size_t>(state.mode)];
    last_step_ns_ = now_ns;
  }

  struct Transition {
    rt::TimeNs at_ns = 0;
    Mode mode = Mode::kTakeOff;
    Reason reason = Reason::kStart;
  };
  /// The first transitions, in order (the log of why the mode changed; at most 64 kept).
  const Transition* transitions() const { return log_.data(); }
  std::size_t transitionCount() const { return log_count_; }
  const SupervisorState& state() const { return supervisor_.state(); }
  /// How a relocation ended (so far).
  enum class RelocationOutcome : std::uint8_t {
    kSearching,        ///< Not over yet (relocating, or searching after the relocation's timeout).
    kFoundRelocating,  ///< Found before the relocation's timeout (along the predicted path).
    kFoundSearching,   ///< Found by the search after it (issue 21 item 3).
    kNotFound,         ///< Timed out: hold "person not found" (the gimbal sweeps on from the hover).
    kFailsafe,         ///< A failsafe (latched hold) ended it.
    kLanded,           ///< Landed (held too long).
  };
  struct Relocation {
    rt::TimeNs start_ns = 0;
    rt::TimeNs timeout_ns = -1;  ///< When relocate_timeout_s ran out (-1: it did not), and any search began.
    rt::TimeNs end_ns = -1;      ///< -1: still relocating or searching.
    bool searched = false;       ///< The search after the timeout ran (search_timeout_s > 0).
    RelocationOutcome outcome = RelocationOutcome::kSearching;
  };
  /// The first relocations, in order (at most 32 kept).
  const Relocation* relocations() const { return relocations_.data(); }
  std::size_t relocationCount() const { return relocation_count_; }
  /// The newest step's time (-1 before the first): where an open relocation's duration ends.
  rt::TimeNs lastStepNs() const { return last_step_ns_; }

  /// Steps spent in each mode (index: Mode).
  std::uint64_t stepsIn(Mode mode) const { return mode_steps_[static_cast<std::size_t>(mode)]; }

 private:
  Supervisor supervisor_;
  SupervisorChannels channels_;
  bool sweep_;
  std::uint64_t last_transitions_ = 0;
  std::array<Transition, 64> log_{};
  std::size_t log_count_ = 0;
  std::array<std::uint64_t, kModeCount> mode_steps_{};
  std::array<Relocation, 32> relocations_{};
  std::size_t relocation_count_ = 0;
  bool relocation_open_ = false;
  rt::TimeNs last_step_ns_ = -1;

  // Called on every transition: opens a relocation on entering relocate, marks its timeout, closes it.
  void logRelocation(const SupervisorState& state, rt::TimeNs now_ns) {
    if (!relocation_open_) {
      if (state.mode != Mode::kRelocate || relocation_count_ >= relocations_.size()) return;
      relocations_[relocation_count_++] = Relocation{now_ns, -1, -1, false, RelocationOutcome::kSearching};
      relocation_open_ = true;
      return;
    }
    Relocation& r = relocations_[relocation_count_ - 1];
    if (state.mode == Mode::kSearch && state.reason == Reason::kPathFlown) {
      r.timeout_ns = now_ns;
      r.searched = true;
      return;
    }
    if (state.mode == Mode::kTrack) {
      r.outcome = r.timeout_ns >= 0 ? RelocationOutcome::kFoundSearching : RelocationOutcome::kFoundRelocating;
    } else if (state.mode == Mode::kHold && state.reason == Reason::kPersonNotFound) {
      if (r.timeout_ns < 0) r.timeout_ns = now_ns;  // search_timeout_s = 0: no search, the hold at once
      r.outcome = RelocationOutcome::kNotFound;
    } else if (state.mode == Mode::kLand) {
      r.outcome = RelocationOutcome::kLanded;
    } else if (state.mode == Mode::kHold) {
      r.outcome = RelocationOutcome::kFailsafe;
    } else {
      return;  // relocate again (cannot happen without leaving it), still searching
    }
    r.end_ns = now_ns;
    relocation_open_ = false;
  }
};

std::string_view toString(SupervisorTask::RelocationOutcome outcome);

}  // namespace aerotrack::supervisor
