// Bystanders give way to the followed person (issue 22): two bodies never overlap.
//
// Every simulated person is a solid 0.25 m cylinder (kPersonBodyRadiusM) to the depth camera, the renderer and the
// drone, but the walkers' paths are generated without regard to the person, and in 9 of 20 crowd trials one walked
// through them (centres 0.09-0.47 m apart; the look-alike straight through their middle). No real pedestrian does:
// walkers who meet adapt their paths seconds ahead and pass with about 0.8 m between their centres (Olivier,
// Marin, Cretual, Pettre 2012, "Minimal predicted distance: a common metric for collision avoidance during
// pairwise interactions between walkers", Gait & Posture 36:399). Here a bystander only keeps out of the person's
// body -- their centres at least two body radii apart, the physical minimum, not the comfortable 0.8 m -- so that
// crossings and overtakings stay as close as physics allows.
//
// The bystander side-steps: at each encounter (a stretch of time in which their generated path would bring
// them within the minimum distance) they move sideways along one direction, away from the person at the
// closest approach, by the least distance that keeps them out (exactly: |d + a n| = D solved for a >= 0), and
// start and end that step at a bounded sideways speed (the least envelope above the required offsets whose slope
// stays within it), so they drift aside ahead of the meeting and back after it instead of jumping. Their gait,
// heading and timing are unchanged. The offsets are sampled once, when the trial is built; lookups interpolate.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "aerotrack/hal/sim/obstacle_world.hpp"
#include "aerotrack/hal/sim/walking_person.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::sim {

struct GiveWayParams {
  double min_distance_m = 0.5;  ///< Between the two centres: two body radii (kPersonBodyRadiusM).
  double step_speed_mps = 0.5;  ///< The side-step's sideways speed (a walker's lateral drift, not a jump).
  double sample_s = 0.02;       ///< The offsets' sampling (the two move < 0.06 m relative to each other in one).
  double horizon_s = 120.0;     ///< Sampled from the simulation's start to here; held after.
};

/// One walker's timed sideways offset, relative to the followed person. Immutable; lookups are O(1).
class GiveWay {
 public:
  /// No offset at any time.
  GiveWay() = default;
  /// The offsets of `walker` (whose walk starts walker_delay_s after the simulation's) around `person` (theirs
  /// starts person_delay_s after it). A side-step that would put the walker's body into an obstacle of `world` at
  /// the closest approach is taken to the other side; if both are blocked, the side away from the person.
  /// Error on invalid params.
  static rt::Expected<GiveWay> compute(const WalkingPerson& person, double person_delay_s, const WalkingPerson& walker,
                                       double walker_delay_s, const ObstacleWorld& world, const GiveWayParams& params);

  /// The offset to add to the walker's position at t_s seconds since the simulation's start, metres in W (xy).
  Eigen::Vector2d offsetM(double t_s) const;
  /// Its rate of change, to add to the walker's velocity, m/s.
  Eigen::Vector2d rateMps(double t_s) const;
  /// How many encounters needed a step (0: the walker never came too near).
  int encounters() const { return encounters_; }

 private:
  double sample_s_ = 0.02;
  std::vector<Eigen::Vector2d> offsets_m_;  // at t = k sample_s_
  int encounters_ = 0;
};

/// The walker's state with the offset applied: position, every keypoint and velocity moved; heading and gait kept.
PersonState withOffset(PersonState state, const GiveWay& give_way, double t_s);

}  // namespace aerotrack::hal::sim
