// Truth-fed trail follower: see baseline_follower.hpp.
#include "aerotrack/hal/sim/baseline_follower.hpp"

#include <cmath>

namespace aerotrack::hal::sim {

BaselineFollower::BaselineFollower(const BaselineFollowerParams& params, const Eigen::Vector3d& start_W_m,
                                   double start_yaw_rad)
    : params_(params), yaw_rad_(start_yaw_rad) {
  addBreadcrumb(start_W_m.head<2>());
}

void BaselineFollower::addBreadcrumb(const Eigen::Vector2d& p_m) {
  trail_[(trail_head_ + trail_count_) % kCapacity] = p_m;
  if (trail_count_ < kCapacity)
    ++trail_count_;
  else
    trail_head_ = (trail_head_ + 1) % kCapacity;
}

const Eigen::Vector2d& BaselineFollower::crumb(std::size_t age) const {
  return trail_[(trail_head_ + trail_count_ - 1 - age) % kCapacity];
}

FollowCommand BaselineFollower::update(const TruthSnapshot& truth, TimeNs now_ns) {
  const Eigen::Vector2d person = truth.person_p_W_m.head<2>();
  if (truth.person_walking && (person - crumb(0)).norm() >= params_.trail_spacing_m) addBreadcrumb(person);

  // Walk back from the person along the trail until `distance_m` of arc length is used up.
  Eigen::Vector2d target = crumb(trail_count_ - 1);     // the oldest crumb if the trail is short
  Eigen::Vector2d trail_dir = Eigen::Vector2d::Zero();  // direction of travel along the trail at the target
  double remaining_m = params_.distance_m;
  Eigen::Vector2d from = truth.person_walking ? person : crumb(0);
  for (std::size_t age = 0; age < trail_count_; ++age) {
    const Eigen::Vector2d to = crumb(age);
    const double seg_m = (from - to).norm();
    if (seg_m >= remaining_m && seg_m > 0.0) {
      target = from + (to - from) * (remaining_m / seg_m);
      trail_dir = (from - to) / seg_m;
      break;
    }
    remaining_m -= seg_m;
    from = to;
  }

  FollowCommand out;
  Setpoint& sp = out.setpoint;
  sp.stamp_ns = now_ns;
  sp.p_W_m = Eigen::Vector3d(target.x(), target.y(), params_.altitude_m);
  // Feed forward the person's speed along the trail where the target is (not the person's own
  // direction, which after a corner points across it).
  const double person_speed = truth.person_v_W_mps.head<2>().norm();
  if (truth.person_walking) sp.v_W_mps.head<2>() = person_speed * trail_dir;
  const double speed = sp.v_W_mps.head<2>().norm();
  if (speed >= params_.yaw_min_speed_mps) yaw_rad_ = std::atan2(sp.v_W_mps.y(), sp.v_W_mps.x());
  sp.yaw_rad = yaw_rad_;

  // Gimbal: the bearing to the person relative to the body, unwrapped near the current angle.
  const Eigen::Vector3d to_person = truth.person_p_W_m - truth.camera_p_W_m;
  const double bearing_B = std::atan2(to_person.y(), to_person.x()) - truth.drone_yaw_rad;
  GimbalCommand& g = out.gimbal;
  g.stamp_ns = now_ns;
  g.mode = GimbalCommand::Mode::kAngle;
  g.angle_rad = truth.gimbal_angle_rad + std::remainder(bearing_B - truth.gimbal_angle_rad, 2.0 * M_PI);
  g.max_rate_radps = params_.gimbal_max_rate_radps;
  return out;
}

}  // namespace aerotrack::hal::sim
