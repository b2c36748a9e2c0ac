// Ground-truth metrics of a simulated run, the numbers summary.json reports and the verdict of
// success (issue 3): no collision, the person re-acquired after every loss of sight, and at the
// end the drone within final_distance_factor times the tracking distance of the person.
// Beside it, the paper's stricter verdict (Fast-Tracker 2.0, Sect. V-B, Table I: "a test fails when
// the quadrotor cannot follow the target all the way"), made measurable (issue 20 item 5):
// followed_all_the_way = no collision, no loss of sight longer than success.max_loss_s, and never
// farther than success.max_distance_m for longer than max_loss_s. And the identity metrics: how often
// the followed detection changed from one true person to another, and how long it was a bystander.
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
  /// Where the odometry put the drone (its frame O read as W): drone_m without drift.
  Eigen::Vector3d odometry_m = Eigen::Vector3d::Zero();
};

struct LossEvent {
  double start_s = 0.0;
  double end_s = -1.0;                                ///< -1 while not re-acquired.
  Eigen::Vector3d drone_m = Eigen::Vector3d::Zero();  ///< Where the drone was when sight was lost.
  Sight cause = Sight::kOccluded;                     ///< Why sight was lost (its first sample).
};

/// One metrics sample (the simulation takes one every metrics period). A struct so that later
/// additions do not change record()'s signature.
struct MetricsSample {
  double t_s = 0.0;   ///< Since the start of the run.
  double dt_s = 0.0;  ///< The metrics period: the time this sample stands for.
  Eigen::Vector3d drone_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d person_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d odometry_m = Eigen::Vector3d::Zero();  ///< The drone as the odometry reports it (drift).
  double person_speed_mps = 0.0;                         ///< PersonState::speed_mps.
  /// The person is on the path: from the start delay until they stop at its end (pauses on the way
  /// included); the person's mean speed is taken over these samples.
  bool person_walking = false;
  double clearance_m = std::numeric_limits<double>::infinity();  ///< Drone centre to the nearest obstacle.
  Sight sight = Sight::kVisible;
  bool tracking = false;  ///< The person has started walking: losses and distances count from then on.
  /// The person to the nearest bystander, and to the nearest look-alike (in the person's clothes), horizontally,
  /// metres; infinity without one. The crowd's worlds differ by seed: how close someone came tells them apart.
  double nearest_bystander_m = std::numeric_limits<double>::infinity();
  double nearest_look_alike_m = std::numeric_limits<double>::infinity();
};

/// The person id recordFollowed() takes when there is no followed detection, or it matches nobody.
inline constexpr int kNoPerson = -1;

/// One identity switch of the followed detection (SimMetrics::identitySwitches), with what the world looked like
/// then: which kind of crossing it was, for the docs' tables of what is left (issue 22, item 2).
struct IdentitySwitch {
  double t_s = 0.0;           ///< The detection frame's exposure, seconds since the start.
  int from_id = kNoPerson;    ///< Whom the followed detection was before (0 the target, k >= 1 bystander k)...
  int to_id = kNoPerson;      ///< ... and is now.
  double separation_m = 0.0;  ///< The two persons' horizontal distance apart at that exposure.
  bool look_alike = false;    ///< A bystander of the two wears the target's clothes.
};
/// The switches a run keeps (the count goes on past them: SimMetrics::identitySwitches).
inline constexpr std::size_t kMaxSwitchEvents = 64;

class SimMetrics {
 public:
  explicit SimMetrics(const ScenarioSpec& spec = {}) : drone_radius_m_(spec.drone.radius_m), success_(spec.success) {}

  /// Records one sample, in time order.
  void record(const MetricsSample& sample);

  /// Records which true person the followed detection of one detection frame belongs to: 0 the
  /// target, k >= 1 bystander k, kNoPerson (-1) no followed detection or one that matches nobody.
  /// Called once per detection frame, in time order, interleaved with record() by time; the id holds
  /// until the next call (time_on_wrong_person_s integrates it over the metrics samples).
  /// `nearest_id`: the person the detection fits best whoever was followed before; person_id may keep the person
  /// followed before where the detection still fits them (CLEAR MOT's correspondences, Simulation::matchDetection).
  /// Both count switches: identitySwitches person_id's, identitySwitchesNearest nearest_id's.
  void recordFollowed(double t_s, int person_id, int nearest_id);
  void recordFollowed(double t_s, int person_id) { recordFollowed(t_s, person_id, person_id); }
  /// Describes the switch the next recordFollowed() counts (called just before it, with the same ids); the first
  /// kMaxSwitchEvents are kept.
  void noteSwitch(const IdentitySwitch& event);
  /// The switches described so far, in time order.
  const std::vector<IdentitySwitch>& switchEvents() const { return switch_events_; }

  /// The verdict at the end of the run; final distance is the last sample's.
  bool success() const;
  /// Null-like empty string when successful, else the first reason.
  std::string failureReason() const;

  /// The paper's verdict (see the top of this file).
  bool followedAllTheWay() const { return followFailureReason().empty(); }
  /// Empty when followed all the way, else the first reason (collision, long loss, long excursion).
  std::string followFailureReason() const;
  /// The longest time the drone was continuously farther than success.max_distance_m, seconds.
  double longestExcursionS() const;
  /// The excursion limit in metres: success.max_distance_m, or its default (see SuccessSpec).
  double maxDistanceM() const;

  /// Times the followed id changed from one person (>= 0) to a different person (>= 0); frames
  /// without a followed detection (-1) between them are ignored (0, -1, 0 is no switch; 0, -1, 2 is one).
  int identitySwitches() const { return identity_switches_; }
  /// The same count over the nearest ids: a detection of two overlapping people that fits both switches to
  /// whichever it fits a little better, frame by frame (the stricter count, before CLEAR MOT's rule).
  int identitySwitchesNearest() const { return identity_switches_nearest_; }
  /// The latest person id >= 0 recordFollowed() took (kNoPerson before any).
  int lastFollowedPersonId() const { return last_real_person_id_; }
  /// Tracked time during which the latest recordFollowed() id was a bystander (>= 1), seconds.
  double timeOnWrongPersonS() const { return time_on_wrong_person_s_; }
  /// recordFollowed() calls so far (0: the run reported no identities; the metrics mean nothing).
  long long followedFrames() const { return followed_frames_; }

  /// The closest any bystander, and any look-alike, came to the person while tracking (MetricsSample), metres;
  /// infinity without one.
  double closestBystanderM() const { return closest_bystander_m_; }
  double closestLookAlikeM() const { return closest_look_alike_m_; }
  /// The person's fastest speed over the run, m/s.
  double personTopSpeedMps() const { return person_top_speed_mps_; }
  /// The person's mean speed while on the path (start delay to the end of the path, pauses
  /// included), m/s; 0 if they never walked.
  double personMeanSpeedMps() const { return walking_s_ > 0.0 ? walking_distance_m_ / walking_s_ : 0.0; }

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
  double excursion_start_s_ = -1.0;  // -1 while within max_distance_m
  double longest_excursion_s_ = 0.0, longest_excursion_start_s_ = 0.0;
  int last_person_id_ = kNoPerson;       // the latest recordFollowed() id
  int last_real_person_id_ = kNoPerson;  // the latest id >= 0 (switches skip -1 gaps)
  int identity_switches_ = 0;
  int last_nearest_id_ = kNoPerson;  // the latest nearest id >= 0
  int identity_switches_nearest_ = 0;
  long long followed_frames_ = 0;
  double time_on_wrong_person_s_ = 0.0;
  double person_top_speed_mps_ = 0.0, walking_s_ = 0.0, walking_distance_m_ = 0.0;
  std::vector<LossEvent> losses_;
  std::vector<TrackSample> track_;
  std::vector<IdentitySwitch> switch_events_;
  double closest_bystander_m_ = std::numeric_limits<double>::infinity();
  double closest_look_alike_m_ = std::numeric_limits<double>::infinity();
};

}  // namespace aerotrack::hal::sim
