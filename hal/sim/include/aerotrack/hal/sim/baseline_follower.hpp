// baseline_follow: a TRUTH-FED STAND-IN for the tracking system, used by `aerotrack sim` until
// the planner (issues 7-8) and the gimbal controller (issue 9) land. It reads the simulator's
// ground truth of the person -- something the real system never has -- and flies along the
// person's own trail (breadcrumbs), a fixed arc length behind them, at a fixed height; the
// gimbal is pointed at the person's true position. Following the trail rather than the straight
// line keeps the drone on ground the person has just walked, which the scenario generators keep
// clear of obstacles, so the stand-in can fly the built-in scenarios; it does nothing about
// occlusion, which is what the real planner is for.
#pragma once

#include <array>
#include <cstddef>

#include "aerotrack/hal/sim/simulation.hpp"
#include "aerotrack/hal/types.hpp"

namespace aerotrack::hal::sim {

struct BaselineFollowerParams {
  double distance_m = 2.5;  ///< Arc length along the trail behind the person.
  double altitude_m = 1.5;
  double trail_spacing_m = 0.1;  ///< A breadcrumb every this many metres the person walks.
  double yaw_min_speed_mps = 0.3;
  double gimbal_max_rate_radps = 4.0;
};

struct FollowCommand {
  Setpoint setpoint;
  GimbalCommand gimbal;
};

class BaselineFollower {
 public:
  /// start_W_m: the drone's start; the trail begins there, so the first target is the start.
  BaselineFollower(const BaselineFollowerParams& params, const Eigen::Vector3d& start_W_m, double start_yaw_rad);

  /// The setpoint and gimbal command for the truth at now_ns. No allocation.
  FollowCommand update(const TruthSnapshot& truth, TimeNs now_ns);

 private:
  void addBreadcrumb(const Eigen::Vector2d& p_m);
  const Eigen::Vector2d& crumb(std::size_t age) const;  // age 0: newest

  static constexpr std::size_t kCapacity = 8192;  // 819 m of trail at 0.1 m; older crumbs are dropped
  BaselineFollowerParams params_;
  std::array<Eigen::Vector2d, kCapacity> trail_{};
  std::size_t trail_head_ = 0, trail_count_ = 0;
  double yaw_rad_;
};

}  // namespace aerotrack::hal::sim
