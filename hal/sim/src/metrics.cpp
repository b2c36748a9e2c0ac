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

void SimMetrics::record(const MetricsSample& sample) {
  const double t_s = sample.t_s, dt_s = sample.dt_s;
  const bool visible = sample.sight == Sight::kVisible;
  const double surface_clearance_m = sample.clearance_m - drone_radius_m_;
  min_clearance_m_ = std::min(min_clearance_m_, surface_clearance_m);
  const bool colliding = surface_clearance_m < 0.0;
  if (colliding && !in_collision_) ++collisions_;
  in_collision_ = colliding;
  track_.push_back({t_s, sample.drone_m, sample.person_m, visible, sample.odometry_m});
  last_t_s_ = t_s;
  person_top_speed_mps_ = std::max(person_top_speed_mps_, sample.person_speed_mps);
  if (sample.person_walking) {  // a rectangle rule, like every other time integral here
    walking_s_ += dt_s;
    walking_distance_m_ += sample.person_speed_mps * dt_s;
  }
  if (!sample.tracking) return;

  tracked_s_ += dt_s;
  closest_bystander_m_ = std::min(closest_bystander_m_, sample.nearest_bystander_m);
  closest_look_alike_m_ = std::min(closest_look_alike_m_, sample.nearest_look_alike_m);
  if (visible) visible_s_ += dt_s;
  if (sample.sight == Sight::kOutOfImage) out_of_image_s_ += dt_s;
  if (sample.sight == Sight::kOccluded) occluded_s_ += dt_s;
  if (last_person_id_ >= 1) time_on_wrong_person_s_ += dt_s;
  final_distance_m_ = (sample.drone_m - sample.person_m).head<2>().norm();
  distance_sum_m_ += final_distance_m_;
  distance_max_m_ = std::max(distance_max_m_, final_distance_m_);
  ++samples_tracked_;
  if (was_visible_ && !visible) losses_.push_back({t_s, -1.0, sample.drone_m, sample.sight});
  if (!was_visible_ && visible && !losses_.empty()) losses_.back().end_s = t_s;
  was_visible_ = visible;

  // Excursions beyond max_distance_m, timed like losses: from the first sample beyond to the first
  // sample back within (or the last sample).
  const bool beyond = final_distance_m_ > maxDistanceM();
  if (beyond && excursion_start_s_ < 0.0) excursion_start_s_ = t_s;
  if (excursion_start_s_ >= 0.0) {
    const double length_s = t_s - excursion_start_s_;
    if (length_s > longest_excursion_s_) {
      longest_excursion_s_ = length_s;
      longest_excursion_start_s_ = excursion_start_s_;
    }
    if (!beyond) excursion_start_s_ = -1.0;
  }
}

void SimMetrics::recordFollowed(double t_s, int person_id, int nearest_id) {
  (void)t_s;  // the id holds until the next call; record() integrates it at the metrics samples
  ++followed_frames_;
  last_person_id_ = person_id;
  if (nearest_id >= 0) {
    if (last_nearest_id_ >= 0 && nearest_id != last_nearest_id_) ++identity_switches_nearest_;
    last_nearest_id_ = nearest_id;
  }
  if (person_id < 0) return;
  if (last_real_person_id_ >= 0 && person_id != last_real_person_id_) ++identity_switches_;
  last_real_person_id_ = person_id;
}

void SimMetrics::noteSwitch(const IdentitySwitch& event) {
  if (switch_events_.size() < kMaxSwitchEvents) switch_events_.push_back(event);
}

double SimMetrics::maxDistanceM() const {
  return success_.max_distance_m > 0.0 ? success_.max_distance_m
                                       : success_.final_distance_factor * success_.tracking_distance_m;
}

double SimMetrics::longestExcursionS() const {
  return longest_excursion_s_;
}

std::string SimMetrics::followFailureReason() const {
  char text[200];
  if (collisions_ > 0) {
    std::snprintf(text, sizeof(text), "%d collision(s); minimum clearance %.2f m", collisions_, min_clearance_m_);
    return text;
  }
  for (const LossEvent& l : losses_) {
    const double length_s = (l.end_s < 0.0 ? last_t_s_ : l.end_s) - l.start_s;
    if (length_s > success_.max_loss_s) {
      std::snprintf(text, sizeof(text), "sight lost for %.2f s from t = %.1f s (%s), longer than %.1f s", length_s,
                    l.start_s, sightName(l.cause), success_.max_loss_s);
      return text;
    }
  }
  if (longest_excursion_s_ > success_.max_loss_s) {
    std::snprintf(text, sizeof(text), "farther than %.1f m for %.2f s from t = %.1f s, longer than %.1f s",
                  maxDistanceM(), longest_excursion_s_, longest_excursion_start_s_, success_.max_loss_s);
    return text;
  }
  return "";
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
