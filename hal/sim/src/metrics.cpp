// Ground-truth metrics: see metrics.hpp.
#include "aerotrack/hal/sim/metrics.hpp"

#include <algorithm>
#include <cstdio>

namespace aerotrack::hal::sim {

const char* sightName(Sight sight) {
  switch (sight) {
    case Sight::kVisible:
      return "visible";
    case Sight::kOutOfImage:
      return "out_of_image";
    case Sight::kOccluded:
      return "occluded";
  }
  return "unknown";
}

void SimMetrics::record(double t_s, const Eigen::Vector3d& drone_m, const Eigen::Vector3d& person_m, double clearance_m,
                        Sight sight, bool tracking, double dt_s) {
  const bool visible = sight == Sight::kVisible;
  const double surface_clearance_m = clearance_m - drone_radius_m_;
  min_clearance_m_ = std::min(min_clearance_m_, surface_clearance_m);
  const bool colliding = surface_clearance_m < 0.0;
  if (colliding && !in_collision_) ++collisions_;
  in_collision_ = colliding;
  track_.push_back({t_s, drone_m, person_m, visible});
  last_t_s_ = t_s;
  if (!tracking) return;

  tracked_s_ += dt_s;
  if (visible) visible_s_ += dt_s;
  if (sight == Sight::kOutOfImage) out_of_image_s_ += dt_s;
  if (sight == Sight::kOccluded) occluded_s_ += dt_s;
  final_distance_m_ = (drone_m - person_m).head<2>().norm();
  distance_sum_m_ += final_distance_m_;
  distance_max_m_ = std::max(distance_max_m_, final_distance_m_);
  ++samples_tracked_;
  if (was_visible_ && !visible) losses_.push_back({t_s, -1.0, drone_m, sight});
  if (!was_visible_ && visible && !losses_.empty()) losses_.back().end_s = t_s;
  was_visible_ = visible;
}

double SimMetrics::longestLossS() const {
  double longest = 0.0;
  for (const LossEvent& l : losses_) longest = std::max(longest, (l.end_s < 0.0 ? last_t_s_ : l.end_s) - l.start_s);
  return longest;
}

std::string SimMetrics::failureReason() const {
  char text[160];
  if (collisions_ > 0) {
    std::snprintf(text, sizeof(text), "%d collision(s); minimum clearance %.2f m", collisions_, min_clearance_m_);
    return text;
  }
  if (!losses_.empty() && losses_.back().end_s < 0.0) {
    std::snprintf(text, sizeof(text), "the person was lost at t = %.1f s and never re-acquired",
                  losses_.back().start_s);
    return text;
  }
  const double limit_m = success_.final_distance_factor * success_.tracking_distance_m;
  if (final_distance_m_ > limit_m) {
    std::snprintf(text, sizeof(text), "final distance %.1f m exceeds %.1f m", final_distance_m_, limit_m);
    return text;
  }
  return "";
}

bool SimMetrics::success() const {
  return failureReason().empty();
}

}  // namespace aerotrack::hal::sim
