// The final check before a planned trajectory is used (issue 8 item 3; paper Sect. V-C: the
// optimiser's penalties are soft, so its output is verified, not trusted). Sampled velocity,
// acceleration and jerk within the limits (norms, with a tolerance), every sample clear in the inflated
// local grid, and the FCL sphere check against the newest octree snapshot (mapping/collision). A
// trajectory that starts inside the inflation margin (the drone was pushed close to something, or a
// surface was just seen beside it) is allowed to leave it, but only quickly (MarginWalk).
#pragma once

#include <cstdint>
#include <string_view>

#include <octomap/OcTree.h>

#include "aerotrack/mapping/local_grid.hpp"
#include "aerotrack/mapping/trajectory_checker.hpp"
#include "aerotrack/planning/polynomial_trajectory.hpp"
#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/field_table.hpp"

namespace aerotrack::planning {

/// The vehicle's dynamic limits live here and only here (issue 21): the optimiser's soft-penalty targets are
/// derived from them (TrackingPlannerParams::optimizer_limit_fraction), so the two cannot drift apart.
struct TrajectoryCheckParams {
  double max_velocity_mps = 3.0;       ///< Norm limit (the vehicle's); > 0.
  double max_acceleration_mps2 = 4.0;  ///< Norm limit (the vehicle's); > 0.
  double max_jerk_mps3 = 40.0;         ///< Norm limit (the vehicle's); > 0.
  double tolerance = 0.05;             ///< Relative excess allowed over each limit; in [0, 1].
  double sample_step_s = 0.02;         ///< Time between limit and grid samples; > 0.
  double horizon_s = 3.0;              ///< Only this much of the trajectory is checked (the rest is replanned); > 0.
  double margin_escape_s = 0.3;        ///< A start inside the inflation margin must be left within this; > 0.
  /// A trajectory over the dynamic limits is repaired by stretching its time (repairs beyond this total
  /// factor are refused: a plan that slow no longer keeps up with the person); >= 1 (1: no repair).
  double max_repair_stretch = 2.0;
};

/// Judges a trajectory's samples against the inflated grid, in time order. A sample in the margin after
/// a clear one is a collision ahead. A start in the margin is tolerated only while the trajectory leaves
/// it within escape_s: one that stays in (flying along a surface first seen at close range, e.g. the
/// far face of a corner rounded in unknown space) is blocked too -- the drone must brake, not go on.
class MarginWalk {
 public:
  explicit MarginWalk(double escape_s) : escape_s_(escape_s) {}
  /// t_s: time since the first sample; occupied: the sample lies in the inflated grid's occupied cells.
  bool blocked(double t_s, bool occupied) {
    if (!occupied) {
      left_margin_ = true;
      return false;
    }
    return left_margin_ || t_s > escape_s_;
  }

 private:
  double escape_s_;
  bool left_margin_ = false;
};

/// The `check:` config section: every field of TrajectoryCheckParams by its name, all required, with the one
/// range per field that parsing, validate() and printing share (rt/field_table.hpp; ranges in the .cpp).
const rt::FieldTable<TrajectoryCheckParams>& trajectoryCheckFields();
/// Every field in its range; the error names the key.
rt::Status validate(const TrajectoryCheckParams& params);
/// trajectoryCheckFields().parse; throws rt::ConfigError naming the key.
TrajectoryCheckParams parseTrajectoryCheckParams(const rt::ConfigNode& node);

enum class CheckVerdict : std::uint8_t {
  kOk,
  kVelocity,
  kAcceleration,
  kJerk,
  kGridBlocked,
  kCollision,
  kCheckerError,
  kTooCloseToPerson,     ///< Checked by the planner (it knows the person's predicted path).
  kTooCloseToBystander,  ///< Checked by the planner: another person's constant-velocity path.
};
std::string_view toString(CheckVerdict verdict);
inline constexpr int kCheckVerdictCount = 9;
/// Velocity, acceleration or jerk: a verdict a slower timing of the same path can cure (the others cannot).
constexpr bool isDynamicLimit(CheckVerdict verdict) {
  return verdict == CheckVerdict::kVelocity || verdict == CheckVerdict::kAcceleration || verdict == CheckVerdict::kJerk;
}

struct CheckResult {
  CheckVerdict verdict = CheckVerdict::kOk;
  double t_s = 0.0;  ///< Time of the first failing sample (0 when ok).
};

/// Checks `trajectory` over [0, min(duration, horizon_s)]. `octree` may be null (no snapshot yet): the
/// FCL check is then skipped and the grid check stands alone. Allocation-free except inside FCL.
CheckResult checkTrajectory(const PolynomialTrajectory& trajectory, const TrajectoryCheckParams& params,
                            const mapping::LocalGrid& grid, const mapping::TrajectoryChecker& checker,
                            const octomap::OcTree* octree);

/// The time stretch k >= 1 that brings the trajectory within the dynamic limits (without the tolerance) over
/// the checked window [0, min(duration, horizon_s)], sampled every sample_step_s: the largest of |v| / v_max,
/// sqrt(|a| / a_max) and cbrt(|j| / j_max) (a pure stretch by k divides v by k, a by k^2, j by k^3), or 1.
double dynamicStretchFactor(const PolynomialTrajectory& trajectory, const TrajectoryCheckParams& params);

}  // namespace aerotrack::planning
