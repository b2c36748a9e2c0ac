// The last safety gate before a planned trajectory is flown (issue 4; paper Sect. V-C, safe
// tracking trajectory generation: the flown path must stay clear of mapped obstacles). The
// trajectory is sampled so that consecutive centres are at most `sample_step_m` apart; at each
// sample a sphere of radius `radius_m + margin_m` is collided with FCL (fcl::Sphere against
// fcl::OcTree wrapping the OctoMap, exact sphere-box test on occupied leaves; Pan et al., "FCL",
// ICRA 2012). Only occupied leaves are obstacles: free and unknown space are not. A broad phase
// keeps the answer exact: a group of consecutive samples is first tested as one FCL sphere that
// contains all of their spheres; only when that sphere touches an occupied leaf is the group
// bisected, in time order, down to single samples. The first colliding sample is therefore the
// same one that a per-sample check would find.
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/field_table.hpp"
#include "aerotrack/trajectory_server/trajectory.hpp"

namespace octomap {
class OcTree;
}  // namespace octomap

namespace aerotrack::mapping {

struct TrajectoryCheckerParams {
  /// Radius of the sphere that encloses the drone, m. > 0.
  double radius_m = 0.25;
  /// Largest straight-line distance between consecutive sample centres, m. > 0 and
  /// <= radius_m (see TrajectoryChecker for what this bounds).
  double sample_step_m = 0.05;
  /// Extra clearance added to radius_m, m. >= 0.
  double margin_m = 0.0;
  /// Consecutive samples tested as one enclosing sphere before falling back to single samples
  /// (broad phase). 1 disables the broad phase (one FCL query per sample). In [1, 64].
  int broad_phase_group = 16;
};

/// The planner's `collision:` config section: every field above by its name, all required, with the one
/// range per field (and the rule sample_step_m <= radius_m) that parsing, validate() and printing share
/// (rt/field_table.hpp; the ranges are in the .cpp).
const rt::FieldTable<TrajectoryCheckerParams>& trajectoryCheckerFields();
/// Every field in its range and the rule; the error names the field.
rt::Status validate(const TrajectoryCheckerParams& params);

struct CollisionReport {
  bool collision_free = true;
  /// Time of the first colliding sample, s since the trajectory's start; empty when free.
  std::optional<double> first_collision_t_s;
  /// Centre of the drone's sphere at that sample, world frame, m; zero when free.
  Eigen::Vector3d first_collision_p_W_m = Eigen::Vector3d::Zero();
  /// Samples taken in time order up to and including the first colliding one (all of them when
  /// free). Does not depend on broad_phase_group.
  int samples_checked = 0;
};

/// One sample of the trajectory as the checker sees it.
struct CheckSample {
  double t_s = 0.0;
  Eigen::Vector3d p_W_m = Eigen::Vector3d::Zero();
};

/// Samples `trajectory` on [t_begin_s, t_end_s] exactly as TrajectoryChecker::check does and
/// appends the samples to `out` (time order, both ends included, consecutive centres at most
/// `sample_step_m` (+1e-12 m for rounding) apart in straight-line distance). The time step is taken from the local
/// speed and acceleration (largest dt with |v| dt + |a| dt^2 / 2 <= step), then shrunk until the chord fits. Error if
/// the interval is not finite, t_end_s < t_begin_s, the step is not positive, or the trajectory jumps (no time step
/// short enough makes the chord fit). Times are clamped to [0, durationS()]. Thread-safe; allocates only by growing
/// `out`.
rt::Status sampleTrajectory(const trajectory_server::Trajectory& trajectory, double t_begin_s, double t_end_s,
                            double sample_step_m, std::vector<CheckSample>& out);

/// Checks trajectories against an OctoMap with FCL.
///
/// What a "collision free" verdict means: every sample sphere of radius r = radius_m +
/// margin_m is clear of every occupied leaf (touching counts as a collision). Between two
/// samples at most s = sample_step_m apart, the union of the two spheres contains the capsule of
/// radius sqrt(r^2 - s^2 / 4) around their chord (r = 0.25, s = 0.05: 0.24875 m), so the
/// continuous path's clearance is guaranteed to that radius, less the path's deviation from
/// its chords (small for smooth trajectories; bounded by |a| dt^2 / 8).
///
/// The OcTree's occupancy threshold decides what is occupied (node log-odds >= the tree's
/// threshold, as octomap::OcTree::isNodeOccupied). Precondition: inner nodes hold the maximum
/// of their children (OctoMap's default; after lazy updates call updateInnerOccupancy()).
class TrajectoryChecker {
 public:
  /// Validates `params` (validate()). Error naming the first bad field.
  static rt::Expected<TrajectoryChecker> create(const TrajectoryCheckerParams& params);

  /// Checks `trajectory` between t_begin_s and t_end_s (s since its start, clamped to
  /// [0, durationS()]) against `tree` (world frame W, the octree's own coordinates). Stops at
  /// the first colliding sample. Error as sampleTrajectory. The tree is only read and is not
  /// copied: a caller that holds a std::shared_ptr<const octomap::OcTree> snapshot passes
  /// *snapshot. Thread-safe (const, no shared mutable state; concurrent checks on one tree are
  /// fine as long as nobody writes the tree). No heap allocation when the trajectory is free
  /// (measured); FCL allocates its small contact list when it finds the collision. Error
  /// messages allocate.
  rt::Expected<CollisionReport> check(const trajectory_server::Trajectory& trajectory, double t_begin_s, double t_end_s,
                                      const octomap::OcTree& tree) const;

  /// Same, for a shared snapshot. Error if `tree` is null.
  rt::Expected<CollisionReport> check(const trajectory_server::Trajectory& trajectory, double t_begin_s, double t_end_s,
                                      const std::shared_ptr<const octomap::OcTree>& tree) const;

  const TrajectoryCheckerParams& params() const { return params_; }

 private:
  explicit TrajectoryChecker(const TrajectoryCheckerParams& params) : params_(params) {}
  TrajectoryCheckerParams params_;
};

}  // namespace aerotrack::mapping
