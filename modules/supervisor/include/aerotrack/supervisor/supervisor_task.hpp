// Task glue for the supervisor (50 Hz in the task table): reads the health of every stream --
// the newest odometry, depth image and gimbal-camera frame, the person estimate, the planner's failures
// in a row, the real-time executor's missed deadlines, the vehicle link's loss -- updates the mode machine, publishes
// the mode for the planner, and asks the gimbal to sweep while searching or relocating (when sweeping is enabled: the
// baseline mode has a fixed camera).
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
    if (const auto target = channels_.target.read(); target && target->initialised) {
      in.person_live = !target->lost;
      in.person_accepted_ns = target->last_accepted_ns;
    }
    in.planner_failures_in_a_row = channels_.planner_failures_in_a_row.load(std::memory_order_relaxed);
    in.deadline_overruns = channels_.deadline_misses.load(std::memory_order_relaxed);
    in.vehicle_link_lost = channels_.vehicle_link_lost.load(std::memory_order_relaxed);
    const SupervisorState& state = supervisor_.update(in);
    channels_.out.write(state);
    const bool searching = state.mode == Mode::kSearch || state.mode == Mode::kRelocate;
    channels_.gimbal_search_requested.store(sweep_ && searching, std::memory_order_relaxed);
    if (state.transitions != last_transitions_) {
      last_transitions_ = state.transitions;
      if (log_count_ < log_.size()) log_[log_count_++] = {now_ns, state.mode, state.reason};
    }
    ++mode_steps_[static_cast<std::size_t>(state.mode)];
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
  /// Steps spent in each mode (index: Mode).
  std::uint64_t stepsIn(Mode mode) const { return mode_steps_[static_cast<std::size_t>(mode)]; }

 private:
  Supervisor supervisor_;
  SupervisorChannels channels_;
  bool sweep_;
  std::uint64_t last_transitions_ = 0;
  std::array<Transition, 64> log_{};
  std::size_t log_count_ = 0;
  std::array<std::uint64_t, 6> mode_steps_{};
};

}  // namespace aerotrack::supervisor
