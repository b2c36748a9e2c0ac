// Ground-truth metrics of a simulated run, the numbers summary.json reports and the verdict of
// success (issue 3): no collision, the person re-acquired after every loss of sight, and at the
// end the drone within final_distance_factor times the tracking distance of the person.
// "Visible" means the person's torso (mid-shoulders and mid-hips) is inside the gimbal camera's
// image and in its line of sight -- what a detector needs, independent of what it then found.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "aerotrack/hal/sim/scenario.hpp"

namespace aerotrack::hal::sim {

/// Whether the person could be seen, and if not, why: outside the gimbal camera's image (the
/// camera points elsewhere, or the drone is so close that the torso leaves the frame), or
/// behind an obstacle. Kept apart because they blame different parts: gimbal control and
/// distance keeping for the first, the occlusion-aware planner (Sect. III) for the second.
enum class Sight { kVisible, kOutOfImage, kOccluded };

const char* sightName(Sight sight);

/// A sample of the run for pictures: positions every metrics period.
struct TrackSample {
  double t_s = 0.0;
  Eigen::Vector3d drone_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d person_m = Eigen::Vector3d::Zero();
  bool visible = false;
};

struct LossEvent {
  double start_s = 0.0;
  double end_s = -1.0;                                ///< -1 while not re-acquired.
  Eigen::Vector3d drone_m = Eigen::Vector3d::Zero();  ///< Where the drone was when sight was lost.
  Sight cause = Sight::kOccluded;                     ///< Why sight was lost (its first sample).
};

class SimMetrics {
 public:
  explicit SimMetrics(const ScenarioSpec& spec = {}) : drone_radius_m_(spec.drone.radius_m), success_(spec.success) {}

  /// Records one sample. tracking: the person has started walking (losses and distances count
  /// from then on). clearance_m: distance from the drone's centre to the nearest obstacle.
  void record(double t_s, const Eigen::Vector3d& drone_m, const Eigen::Vector3d& person_m, double clearance_m,
              Sight sight, bool tracking, double dt_s);

  /// The verdict at the end of the run; final distance is the last sample's.
  bool success() const;
  /// Null-like empty string when successful, else the first reason.
  std::string failureReason() const;

  int collisions() const { return collisions_; }
  /// Infinity when there is no obstacle in the world.
  double minClearanceM() const { return min_clearance_m_; }
  double visibleRatio() const { return tracked_s_ > 0.0 ? visible_s_ / tracked_s_ : 0.0; }
  double longestLossS() const;
  /// Seconds (from the person's start) the person was hidden out of the image / behind obstacles.
  double outOfImageS() const { return out_of_image_s_; }
  double occludedS() const { return occluded_s_; }
  double distanceMeanM() const { return samples_tracked_ > 0 ? distance_sum_m_ / samples_tracked_ : 0.0; }
  double distanceMaxM() const { return distance_max_m_; }
  double finalDistanceM() const { return final_distance_m_; }
  const std::vector<LossEvent>& losses() const { return losses_; }
  const std::vector<TrackSample>& track() const { return track_; }

 private:
  double drone_radius_m_;
  SuccessSpec success_;
  int collisions_ = 0;
  bool in_collision_ = false;
  double min_clearance_m_ = std::numeric_limits<double>::infinity();  // stays infinite without obstacles
  double tracked_s_ = 0.0, visible_s_ = 0.0, out_of_image_s_ = 0.0, occluded_s_ = 0.0;
  double distance_sum_m_ = 0.0, distance_max_m_ = 0.0, final_distance_m_ = 0.0;
  double last_t_s_ = 0.0;
  int samples_tracked_ = 0;
  bool was_visible_ = true;
  std::vector<LossEvent> losses_;
  std::vector<TrackSample> track_;
};

}  // namespace aerotrack::hal::sim
