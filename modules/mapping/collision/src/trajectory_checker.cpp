// TrajectoryChecker: samples a trajectory (adaptive time step, chord <= sample_step_m) and
// collides a sphere at each sample with the OctoMap through FCL's shape-octree traversal, which
// descends only into occupied nodes and ends in an exact sphere-box test per occupied leaf. The
// broad phase tests a group of samples as one enclosing sphere and bisects the group in time
// order only when that sphere collides, so the first colliding sample is the per-sample one.
#include "aerotrack/mapping/trajectory_checker.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include <fcl/geometry/octree/octree.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision.h>
#include <octomap/OcTree.h>

namespace aerotrack::mapping {
namespace {

constexpr int kMaxBroadPhaseGroup = 64;
constexpr int kMaxStepShrinks = 200;
// Step shrink factor relative to step / chord, below 1 so that a retry usually fits.
constexpr double kShrinkFactor = 0.95;
// A chord may exceed the step by this much (rounding of p(t + dt) - p(t) when the proposal
// lands exactly on the step, as on a constant-speed line).
constexpr double kChordToleranceM = 1e-12;
// A step that leaves less than this fraction of itself before t_end goes to t_end instead, so
// rounding in t does not add a sliver sample at the end.
constexpr double kEndSnapFraction = 1e-9;
// Added to an enclosing sphere's radius so that it contains its members despite rounding
// (coordinates up to ~1e3 m give rounding near 1e-12 m); it only makes the broad phase more
// conservative.
constexpr double kEnclosingSlackM = 1e-6;

bool isFinitePositive(double x) {
  return std::isfinite(x) && x > 0.0;
}

rt::Error error(const std::string& what) {
  return rt::Error{"mapping::TrajectoryChecker: " + what};
}

/// Produces the samples of sampleTrajectory one at a time, so that check() can stop early and
/// needs no buffer proportional to the trajectory.
class Sampler {
 public:
  Sampler(const trajectory_server::Trajectory& trajectory, double t_begin_s, double t_end_s, double step_m)
      : trajectory_(trajectory), t_end_s_(t_end_s), step_m_(step_m), t_s_(t_begin_s) {}

  bool done() const { return done_; }

  rt::Expected<CheckSample> next() {
    if (first_) {
      first_ = false;
      last_ = trajectory_.sample(t_s_);
      done_ = !(t_s_ < t_end_s_);
      return CheckSample{t_s_, last_.p_W_m};
    }
    const double speed_mps = last_.v_W_mps.norm();
    const double accel_mps2 = last_.a_W_mps2.norm();
    // Largest dt with speed dt + accel dt^2 / 2 <= step, in the form that is stable for
    // accel -> 0 (infinite when the trajectory is at rest: the chord test below decides).
    double dt_s = 2.0 * step_m_ / (speed_mps + std::sqrt(speed_mps * speed_mps + 2.0 * accel_mps2 * step_m_));
    for (int attempt = 0; attempt < kMaxStepShrinks; ++attempt) {
      const double t_next_s = dt_s * (1.0 + kEndSnapFraction) >= t_end_s_ - t_s_ ? t_end_s_ : t_s_ + dt_s;
      if (!(t_next_s > t_s_)) break;
      trajectory_server::TrajectorySample next = trajectory_.sample(t_next_s);
      const double chord_m = (next.p_W_m - last_.p_W_m).norm();
      if (chord_m <= step_m_ + kChordToleranceM) {
        t_s_ = t_next_s;
        last_ = next;
        done_ = !(t_s_ < t_end_s_);
        return CheckSample{t_s_, last_.p_W_m};
      }
      if (!std::isfinite(chord_m)) {
        return error("trajectory sample at t = " + std::to_string(t_next_s) + " s is not finite");
      }
      dt_s = std::min(t_next_s - t_s_, dt_s) * kShrinkFactor * step_m_ / chord_m;
    }
    return error("trajectory jumps after t = " + std::to_string(t_s_) + " s: no time step keeps samples within " +
                 std::to_string(step_m_) + " m");
  }

 private:
  const trajectory_server::Trajectory& trajectory_;
  double t_end_s_;
  double step_m_;
  double t_s_;
  trajectory_server::TrajectorySample last_;
  bool first_ = true;
  bool done_ = false;
};

/// Validates and clamps the interval to [0, durationS()].
rt::Expected<std::array<double, 2>> clampedInterval(const trajectory_server::Trajectory& trajectory, double t_begin_s,
                                                    double t_end_s) {
  if (!std::isfinite(t_begin_s) || !std::isfinite(t_end_s)) return error("time interval is not finite");
  if (t_end_s < t_begin_s) {
    return error("t_end_s " + std::to_string(t_end_s) + " is before t_begin_s " + std::to_string(t_begin_s));
  }
  const double duration_s = trajectory.durationS();
  if (!std::isfinite(duration_s) || duration_s < 0.0) return error("trajectory duration is not finite");
  return std::array<double, 2>{std::clamp(t_begin_s, 0.0, duration_s), std::clamp(t_end_s, 0.0, duration_s)};
}

/// One FCL sphere against one octree, both for the duration of a check() call.
class OctreeQuery {
 public:
  explicit OctreeQuery(const std::shared_ptr<const octomap::OcTree>& tree)
      : fcl_tree_(tree), sphere_(1.0), request_(1, false) {
    // FCL prunes inner nodes it deems free (log-odds <= its free threshold, default 0 = p 0.5)
    // before looking at their children. With a tree whose occupancy threshold is <= 0.5 an inner
    // node can be both, and occupied leaves under it would be missed. A free threshold of p = 0
    // (log-odds -inf) marks no node free; inner nodes below the occupancy threshold are still
    // skipped as "uncertain", which is exact since an inner node holds its children's maximum.
    fcl_tree_.setFreeThres(0.0);
  }

  /// True if the sphere (centre, radius, world frame, m) touches or overlaps an occupied leaf.
  bool collides(const Eigen::Vector3d& centre_W_m, double radius_m) {
    sphere_.radius = radius_m;
    fcl::Transform3d X_W_sphere = fcl::Transform3d::Identity();
    X_W_sphere.translation() = centre_W_m;
    fcl::CollisionResult<double> result;
    fcl::collide<double>(&sphere_, X_W_sphere, &fcl_tree_, fcl::Transform3d::Identity(), request_, result);
    return result.isCollision();
  }

 private:
  fcl::OcTree<double> fcl_tree_;
  fcl::Sphere<double> sphere_;
  fcl::CollisionRequest<double> request_;
};

/// Index of the first colliding sample in [lo, hi), or -1. Tests the enclosing sphere of the
/// range first and bisects, earlier half first, when it collides.
int firstCollision(OctreeQuery& query, const std::array<CheckSample, kMaxBroadPhaseGroup>& samples, int lo, int hi,
                   double radius_m) {
  if (hi - lo == 1) return query.collides(samples[lo].p_W_m, radius_m) ? lo : -1;
  Eigen::Vector3d min_W_m = samples[lo].p_W_m;
  Eigen::Vector3d max_W_m = samples[lo].p_W_m;
  for (int i = lo + 1; i < hi; ++i) {
    min_W_m = min_W_m.cwiseMin(samples[i].p_W_m);
    max_W_m = max_W_m.cwiseMax(samples[i].p_W_m);
  }
  const Eigen::Vector3d centre_W_m = 0.5 * (min_W_m + max_W_m);
  double spread_m = 0.0;
  for (int i = lo; i < hi; ++i) spread_m = std::max(spread_m, (samples[i].p_W_m - centre_W_m).norm());
  if (!query.collides(centre_W_m, spread_m + radius_m + kEnclosingSlackM)) return -1;
  const int mid = lo + (hi - lo) / 2;
  const int first = firstCollision(query, samples, lo, mid, radius_m);
  return first >= 0 ? first : firstCollision(query, samples, mid, hi, radius_m);
}

}  // namespace

rt::Status sampleTrajectory(const trajectory_server::Trajectory& trajectory, double t_begin_s, double t_end_s,
                            double sample_step_m, std::vector<CheckSample>& out) {
  if (!isFinitePositive(sample_step_m)) return error("sample_step_m must be positive");
  auto interval = clampedInterval(trajectory, t_begin_s, t_end_s);
  if (!interval) return interval.error();
  Sampler sampler(trajectory, (*interval)[0], (*interval)[1], sample_step_m);
  while (!sampler.done()) {
    auto sample = sampler.next();
    if (!sample) return sample.error();
    out.push_back(*sample);
  }
  return rt::ok();
}

const rt::FieldTable<TrajectoryCheckerParams>& trajectoryCheckerFields() {
  using P = TrajectoryCheckerParams;
  using rt::Range;
  static const rt::FieldTable<P> kTable(
      {
          rt::number("radius_m", &P::radius_m, Range::closed(0.01, 5.0)),
          rt::number("sample_step_m", &P::sample_step_m, Range::closed(0.005, 5.0)),
          rt::number("margin_m", &P::margin_m, Range::closed(0.0, 5.0)),
          rt::integer("broad_phase_group", &P::broad_phase_group, 1, kMaxBroadPhaseGroup),
      },
      {{"sample_step_m", "must be <= radius_m", [](const P& p) { return p.sample_step_m <= p.radius_m; }}});
  return kTable;
}

rt::Status validate(const TrajectoryCheckerParams& params) {
  return trajectoryCheckerFields().validate(params);
}

rt::Expected<TrajectoryChecker> TrajectoryChecker::create(const TrajectoryCheckerParams& params) {
  if (const rt::Status valid = validate(params); !valid) return error(valid.error().message);
  return TrajectoryChecker(params);
}

rt::Expected<CollisionReport> TrajectoryChecker::check(const trajectory_server::Trajectory& trajectory,
                                                       double t_begin_s, double t_end_s,
                                                       const octomap::OcTree& tree) const {
  // Non-owning handle (aliasing constructor, no allocation): the tree outlives this call.
  return check(trajectory, t_begin_s, t_end_s, std::shared_ptr<const octomap::OcTree>(std::shared_ptr<void>(), &tree));
}

rt::Expected<CollisionReport> TrajectoryChecker::check(const trajectory_server::Trajectory& trajectory,
                                                       double t_begin_s, double t_end_s,
                                                       const std::shared_ptr<const octomap::OcTree>& tree) const {
  if (tree == nullptr) return error("octree is null");
  auto interval = clampedInterval(trajectory, t_begin_s, t_end_s);
  if (!interval) return interval.error();

  const double radius_m = params_.radius_m + params_.margin_m;
  OctreeQuery query(tree);
  Sampler sampler(trajectory, (*interval)[0], (*interval)[1], params_.sample_step_m);
  std::array<CheckSample, kMaxBroadPhaseGroup> group;
  int group_size = 0;
  CollisionReport report;
  while (!sampler.done()) {
    auto sample = sampler.next();
    if (!sample) return sample.error();
    group[group_size++] = *sample;
    if (group_size < params_.broad_phase_group && !sampler.done()) continue;
    const int first = firstCollision(query, group, 0, group_size, radius_m);
    if (first >= 0) {
      report.collision_free = false;
      report.first_collision_t_s = group[first].t_s;
      report.first_collision_p_W_m = group[first].p_W_m;
      report.samples_checked += first + 1;
      return report;
    }
    report.samples_checked += group_size;
    group_size = 0;
  }
  return report;
}

}  // namespace aerotrack::mapping
