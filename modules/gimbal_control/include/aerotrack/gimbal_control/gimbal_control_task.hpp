// Task glue for gimbal control (200 Hz in the task table): reads the newest encoder reading,
// odometry and person estimate, and the supervisor's search request, and commands the gimbal motor.
#pragma once

#include <atomic>
#include <utility>

#include "aerotrack/gimbal_control/gimbal_controller.hpp"
#include "aerotrack/hal/devices.hpp"
#include "aerotrack/rt/latest_slot.hpp"
#include "aerotrack/rt/task.hpp"

namespace aerotrack::gimbal_control {

class GimbalControlTask final : public rt::Task {
 public:
  GimbalControlTask(GimbalController controller, const rt::LatestSlot<hal::GimbalState>& gimbal_state,
                    const rt::LatestSlot<hal::OdometrySample>& odometry,
                    const rt::LatestSlot<estimation::TargetEstimate>& target, const std::atomic<bool>& search_requested,
                    hal::Gimbal& gimbal)
      : controller_(std::move(controller)),
        gimbal_state_(gimbal_state),
        odometry_(odometry),
        target_(target),
        search_requested_(search_requested),
        gimbal_(gimbal) {}

  /// Baseline mode (Fast-Tracker 1.0): the camera is fixed to the body; the gimbal is held at 0.
  void fixCamera(bool fixed) { fixed_ = fixed; }

  void step(rt::TimeNs now_ns) override {
    if (fixed_) {
      hal::GimbalCommand hold;
      hold.stamp_ns = now_ns;
      hold.mode = hal::GimbalCommand::Mode::kAngle;
      hold.angle_rad = 0.0;
      gimbal_.command(hold);
      return;
    }
    const auto state = gimbal_state_.read();
    const auto odometry = odometry_.read();
    const auto target = target_.read();
    GimbalInputs in;
    in.now_ns = now_ns;
    in.gimbal = state ? &*state : nullptr;
    in.odometry = odometry ? &*odometry : nullptr;
    in.target = target ? &*target : nullptr;
    in.search_requested = search_requested_.load(std::memory_order_relaxed);
    const GimbalOutput out = controller_.update(in);
    gimbal_.command(out.command);
    if (out.mode == GimbalMode::kTrack) ++track_steps_;
    if (out.mode == GimbalMode::kSearch) ++search_steps_;
  }

  std::uint64_t trackSteps() const { return track_steps_; }
  std::uint64_t searchSteps() const { return search_steps_; }

 private:
  GimbalController controller_;
  const rt::LatestSlot<hal::GimbalState>& gimbal_state_;
  const rt::LatestSlot<hal::OdometrySample>& odometry_;
  const rt::LatestSlot<estimation::TargetEstimate>& target_;
  const std::atomic<bool>& search_requested_;
  hal::Gimbal& gimbal_;
  bool fixed_ = false;
  std::uint64_t track_steps_ = 0;
  std::uint64_t search_steps_ = 0;
};

}  // namespace aerotrack::gimbal_control
