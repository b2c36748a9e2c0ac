// TrajectoryChecker: analytic first-collision times against a tree trunk and a wall, clearance
// and margin, unknown space, the tree's occupancy threshold, and agreement with a slow obvious
// reference (every sample against every occupied leaf by exact sphere-box distance) on random
// trajectories through a random octree, with and without the broad phase.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <utility>
#include <vector>

#include <octomap/OcTree.h>

#include "../../../support/require.hpp"
#include "aerotrack/mapping/trajectory_checker.hpp"
#include "aerotrack/trajectory_server/min_jerk_tour.hpp"

namespace aerotrack::mapping {
namespace {

using trajectory_server::MinJerkTour;
using trajectory_server::Trajectory;
using trajectory_server::TrajectorySample;

constexpr double kResolutionM = 0.1;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// p(t) = p0 + v t on [0, duration]: first contacts can be computed by hand.
class LineTrajectory final : public Trajectory {
 public:
  LineTrajectory(Eigen::Vector3d p0_W_m, Eigen::Vector3d v_W_mps, double duration_s)
      : p0_W_m_(std::move(p0_W_m)), v_W_mps_(std::move(v_W_mps)), duration_s_(duration_s) {}
  double durationS() const override { return duration_s_; }
  TrajectorySample sample(double t_s) const override {
    TrajectorySample s;
    s.p_W_m = p0_W_m_ + v_W_mps_ * std::clamp(t_s, 0.0, duration_s_);
    s.v_W_mps = v_W_mps_;
    return s;
  }

 private:
  Eigen::Vector3d p0_W_m_;
  Eigen::Vector3d v_W_mps_;
  double duration_s_;
};

/// Jumps by 1 m at t = 1 s.
class JumpingTrajectory final : public Trajectory {
 public:
  double durationS() const override { return 2.0; }
  TrajectorySample sample(double t_s) const override {
    TrajectorySample s;
    s.p_W_m = Eigen::Vector3d(0.1 * t_s + (t_s > 1.0 ? 1.0 : 0.0), 0, 1);
    s.v_W_mps = Eigen::Vector3d(0.1, 0, 0);
    return s;
  }
};

/// Marks the voxel that contains p (world frame, m) occupied (or free).
void markVoxel(octomap::OcTree& tree, const Eigen::Vector3d& p_W_m, bool occupied = true) {
  tree.updateNode(
      octomap::point3d(static_cast<float>(p_W_m.x()), static_cast<float>(p_W_m.y()), static_cast<float>(p_W_m.z())),
      occupied);
}

/// Marks every voxel whose centre lies in [lo, hi] (world frame, m) occupied (or free).
void fillBox(octomap::OcTree& tree, const Eigen::Vector3d& lo_W_m, const Eigen::Vector3d& hi_W_m,
             bool occupied = true) {
  // Voxel i spans [i, i + 1) * resolution; its centre is inside [lo, hi] for these i.
  const auto first = [](double lo) { return static_cast<int>(std::ceil(lo / kResolutionM - 0.5 - 1e-9)); };
  const auto last = [](double hi) { return static_cast<int>(std::floor(hi / kResolutionM - 0.5 + 1e-9)); };
  for (int i = first(lo_W_m.x()); i <= last(hi_W_m.x()); ++i) {
    for (int j = first(lo_W_m.y()); j <= last(hi_W_m.y()); ++j) {
      for (int k = first(lo_W_m.z()); k <= last(hi_W_m.z()); ++k) {
        markVoxel(tree, Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5) * kResolutionM, occupied);
      }
    }
  }
}

/// A trunk occupying x in [1.9, 2.1], y in [-0.1, 0.1], z in [0, 3] (2 x 2 x 30 voxels).
std::shared_ptr<octomap::OcTree> makeTrunkTree() {
  auto tree = std::make_shared<octomap::OcTree>(kResolutionM);
  fillBox(*tree, {1.9, -0.1, 0.0}, {2.1, 0.1, 3.0});
  return tree;
}

TrajectoryChecker makeChecker(double margin_m = 0.0, int group = 16) {
  TrajectoryCheckerParams params;
  params.margin_m = margin_m;
  params.broad_phase_group = group;
  return aerotrack::test::require(TrajectoryChecker::create(params), "TrajectoryChecker::create");
}

CollisionReport checkOk(const TrajectoryChecker& checker, const Trajectory& trajectory, const octomap::OcTree& tree) {
  return aerotrack::test::require(checker.check(trajectory, 0.0, trajectory.durationS(), tree),
                                  "TrajectoryChecker::check");
}

// ---- the slow obvious reference ----

double sphereBoxDistanceSquared(const Eigen::Vector3d& c, const Eigen::Vector3d& box_centre, double half_size) {
  double d2 = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double excess = std::abs(c[i] - box_centre[i]) - half_size;
    if (excess > 0.0) d2 += excess * excess;
  }
  return d2;
}

bool referenceCollides(const octomap::OcTree& tree, const Eigen::Vector3d& c_W_m, double radius_m) {
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const octomap::point3d c = it.getCoordinate();
    const Eigen::Vector3d centre_W_m(static_cast<double>(c.x()), static_cast<double>(c.y()),
                                     static_cast<double>(c.z()));
    if (sphereBoxDistanceSquared(c_W_m, centre_W_m, it.getSize() / 2) <= radius_m * radius_m) {
      return true;
    }
  }
  return false;
}

/// Index of the first colliding sample, or -1.
int referenceFirstCollision(const std::vector<CheckSample>& samples, const octomap::OcTree& tree, double radius_m) {
  for (int i = 0; i < static_cast<int>(samples.size()); ++i) {
    if (referenceCollides(tree, samples[i].p_W_m, radius_m)) return i;
  }
  return -1;
}

// ---- trunk, side pass, unknown space, wall, margin ----

TEST(TrajectoryChecker, GivenLineThroughTrunkWhenCheckedThenRejectedAtFirstSampleWithinRadius) {
  const auto tree = makeTrunkTree();
  // x(t) = 0.02 + t at 1 m/s, y = 0, z = 1.5: the sphere (0.25 m) first reaches the trunk face
  // x = 1.9 at t = 1.63 s. Samples fall every 0.05 s (a = 0: dt = step / speed), so the first
  // colliding sample is t = 1.65 s, the 34th.
  const LineTrajectory line({0.02, 0.0, 1.5}, {1.0, 0.0, 0.0}, 4.0);
  const CollisionReport report = checkOk(makeChecker(), line, *tree);
  EXPECT_FALSE(report.collision_free);
  ASSERT_TRUE(report.first_collision_t_s.has_value());
  EXPECT_NEAR(*report.first_collision_t_s, 1.65, 1e-9);
  EXPECT_NEAR(report.first_collision_p_W_m.x(), 1.67, 1e-9);
  EXPECT_NEAR(report.first_collision_p_W_m.y(), 0.0, 1e-12);
  EXPECT_EQ(report.samples_checked, 34);
}

TEST(TrajectoryChecker, GivenLinePassingTrunkAtRadiusPlusTenCentimetresWhenCheckedThenAccepted) {
  const auto tree = makeTrunkTree();
  // Trunk side at y = 0.1; centre line at 0.1 + 0.25 + 0.10.
  const LineTrajectory beside({0.0, 0.45, 1.5}, {1.0, 0.0, 0.0}, 4.0);
  const CollisionReport report = checkOk(makeChecker(), beside, *tree);
  EXPECT_TRUE(report.collision_free);
  EXPECT_FALSE(report.first_collision_t_s.has_value());
  EXPECT_EQ(report.samples_checked, 81);  // t = 0, 0.05, ..., 4.0
}

TEST(TrajectoryChecker, GivenLineOneCentimetreInsideRadiusOfTrunkSideWhenCheckedThenRejected) {
  const auto tree = makeTrunkTree();
  const LineTrajectory grazing({0.0, 0.34, 1.5}, {1.0, 0.0, 0.0}, 4.0);
  const CollisionReport report = checkOk(makeChecker(), grazing, *tree);
  EXPECT_FALSE(report.collision_free);
  // Reaches the trunk's edge x = 1.9 horizontally within sqrt(0.25^2 - 0.24^2) = 0.07 m.
  ASSERT_TRUE(report.first_collision_t_s.has_value());
  EXPECT_GE(report.first_collision_p_W_m.x(), 1.9 - 0.07 - 1e-9);
  EXPECT_LT(report.first_collision_p_W_m.x(), 1.9 - 0.07 + 0.05);
}

TEST(TrajectoryChecker, GivenUnknownAndFreeSpaceAroundLineWhenCheckedThenAccepted) {
  octomap::OcTree tree(kResolutionM);
  // Free voxels along part of the path, one occupied voxel 3 m away, everything else unknown.
  fillBox(tree, {0.0, -0.5, 1.0}, {2.0, 0.5, 2.0}, /*occupied=*/false);
  markVoxel(tree, {2.05, 3.05, 1.55});
  const LineTrajectory line({-3.0, 0.0, 1.5}, {2.0, 0.0, 0.0}, 4.0);
  const CollisionReport report = checkOk(makeChecker(), line, tree);
  EXPECT_TRUE(report.collision_free);

  const octomap::OcTree empty(kResolutionM);
  EXPECT_TRUE(checkOk(makeChecker(), line, empty).collision_free);
}

TEST(TrajectoryChecker, GivenMinJerkFlightAcrossWallWhenCheckedThenFirstCollisionJustAfterContact) {
  octomap::OcTree tree(kResolutionM);
  fillBox(tree, {3.0, -2.0, 0.0}, {3.1, 2.0, 3.0});  // wall x in [3.0, 3.1]
  auto tour = MinJerkTour::create({{0, 0, 1}, {6, 0, 1}}, 3.0, 3.0);
  ASSERT_TRUE(tour);
  const CollisionReport report = checkOk(makeChecker(), *tour, tree);
  ASSERT_FALSE(report.collision_free);
  ASSERT_TRUE(report.first_collision_t_s.has_value());
  // Contact at x = 3.0 - 0.25; samples are at most 0.05 m apart.
  EXPECT_GE(report.first_collision_p_W_m.x(), 2.75 - 1e-9);
  EXPECT_LT(report.first_collision_p_W_m.x(), 2.75 + 0.05);
  EXPECT_LT((tour->sample(*report.first_collision_t_s).p_W_m - report.first_collision_p_W_m).norm(), 1e-12);
  // Symmetric min-jerk leg: x = 3 at half time; contact comes a little before.
  EXPECT_LT(*report.first_collision_t_s, tour->durationS() / 2);
}

TEST(TrajectoryChecker, GivenWallAfterCheckedIntervalWhenCheckedThenAccepted) {
  octomap::OcTree tree(kResolutionM);
  fillBox(tree, {3.0, -2.0, 0.0}, {3.1, 2.0, 3.0});
  const LineTrajectory line({0.0, 0.0, 1.0}, {1.0, 0.0, 0.0}, 6.0);
  auto report = makeChecker().check(line, 0.5, 2.5, tree);  // x up to 2.5: 0.25 short of contact
  ASSERT_TRUE(report);
  EXPECT_TRUE(report->collision_free);
  EXPECT_EQ(report->samples_checked, 41);
  // From t = 2.52 s (t_end clamped to 6 s): contact at x = 2.75, first sample after it 2.77 s.
  auto late = makeChecker().check(line, 2.52, 10.0, tree);
  ASSERT_TRUE(late);
  EXPECT_FALSE(late->collision_free);
  EXPECT_NEAR(*late->first_collision_t_s, 2.77, 1e-9);
}

TEST(TrajectoryChecker, GivenMarginWhenCheckedThenClearanceIsRadiusPlusMargin) {
  const auto tree = makeTrunkTree();
  const LineTrajectory beside({0.0, 0.45, 1.5}, {1.0, 0.0, 0.0}, 4.0);  // 0.35 m from the trunk side
  EXPECT_TRUE(checkOk(makeChecker(0.09), beside, *tree).collision_free);
  EXPECT_FALSE(checkOk(makeChecker(0.11), beside, *tree).collision_free);
  // Head-on with margin 0.1: contact when 0.02 + t + 0.35 >= 1.9, t >= 1.53, first sample 1.55 s.
  const LineTrajectory line({0.02, 0.0, 1.5}, {1.0, 0.0, 0.0}, 4.0);
  const CollisionReport report = checkOk(makeChecker(0.1), line, *tree);
  ASSERT_TRUE(report.first_collision_t_s.has_value());
  EXPECT_NEAR(*report.first_collision_t_s, 1.55, 1e-9);
}

TEST(TrajectoryChecker, GivenPrunedOccupiedBlockWhenCheckedThenItsWholeVolumeIsAnObstacle) {
  octomap::OcTree tree(kResolutionM);
  fillBox(tree, {0.0, 0.0, 0.0}, {0.8, 0.8, 0.8});  // an aligned 8^3 block: one 0.8 m leaf after pruning
  tree.prune();
  ASSERT_EQ(tree.getNumLeafNodes(), 1u);
  const LineTrajectory line({-1.02, 0.4, 0.4}, {1.0, 0.0, 0.0}, 3.0);
  const CollisionReport report = checkOk(makeChecker(), line, tree);
  ASSERT_TRUE(report.first_collision_t_s.has_value());
  EXPECT_NEAR(*report.first_collision_t_s, 0.8, 1e-9);  // contact at x = -0.25 (t = 0.77 s)
}

TEST(TrajectoryChecker, GivenTreeOccupancyThresholdWhenCheckedThenOnlyNodesAtOrAboveItAreObstacles) {
  for (const double threshold : {0.4, 0.5, 0.7}) {
    octomap::OcTree tree(kResolutionM);
    tree.setOccupancyThres(threshold);
    // Two voxels of p = 0.45 and 0.6, far apart; their inner nodes hold the same values.
    tree.setNodeValue(octomap::point3d(1.05f, 0.05f, 1.05f), static_cast<float>(octomap::logodds(0.45)));
    tree.setNodeValue(octomap::point3d(1.05f, 5.05f, 1.05f), static_cast<float>(octomap::logodds(0.6)));
    const LineTrajectory low({0.0, 0.05, 1.05}, {1.0, 0.0, 0.0}, 2.0);
    const LineTrajectory high({0.0, 5.05, 1.05}, {1.0, 0.0, 0.0}, 2.0);
    EXPECT_EQ(checkOk(makeChecker(), low, tree).collision_free, threshold > 0.45) << threshold;
    EXPECT_EQ(checkOk(makeChecker(), high, tree).collision_free, threshold > 0.6) << threshold;
  }
}

TEST(TrajectoryChecker, GivenSharedSnapshotWhenCheckedThenSameAsReferenceOverload) {
  const std::shared_ptr<const octomap::OcTree> snapshot = makeTrunkTree();
  const LineTrajectory line({0.02, 0.0, 1.5}, {1.0, 0.0, 0.0}, 4.0);
  auto by_handle = makeChecker().check(line, 0.0, 4.0, snapshot);
  ASSERT_TRUE(by_handle);
  EXPECT_EQ(snapshot.use_count(), 1);  // not kept
  EXPECT_NEAR(*by_handle->first_collision_t_s, 1.65, 1e-9);
  EXPECT_FALSE(makeChecker().check(line, 0.0, 4.0, std::shared_ptr<const octomap::OcTree>()));
}

// ---- agreement with the reference ----

TEST(TrajectoryChecker, GivenRandomTrajectoriesInRandomOctreeWhenCheckedThenSameFirstSampleAsBruteForce) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> coord(0.0, 6.0);
  std::uniform_real_distribution<double> height(0.3, 2.7);
  std::uniform_real_distribution<double> size(0.1, 0.6);
  octomap::OcTree tree(kResolutionM);
  fillBox(tree, {0.0, 0.0, 0.0}, {6.0, 6.0, 3.0}, /*occupied=*/false);  // known free space
  for (int i = 0; i < 6; ++i) {                                         // blobs
    const Eigen::Vector3d lo(coord(rng), coord(rng), height(rng));
    fillBox(tree, lo, lo + Eigen::Vector3d(size(rng), size(rng), size(rng)));
  }
  for (int i = 0; i < 3; ++i) {  // trunks
    const Eigen::Vector3d lo(coord(rng), coord(rng), 0.0);
    fillBox(tree, lo, lo + Eigen::Vector3d(0.2, 0.2, 3.0));
  }
  for (int i = 0; i < 30; ++i) markVoxel(tree, {coord(rng), coord(rng), height(rng)});  // specks
  fillBox(tree, {4.0, 0.8, 1.6}, {4.8, 1.6, 2.4});  // an aligned block that prunes into one leaf
  tree.prune();

  const std::vector<TrajectoryChecker> checkers = {makeChecker(0.0, 1), makeChecker(0.0, 16), makeChecker(0.05, 64)};
  int collisions = 0;
  int trials = 0;
  std::uniform_real_distribution<double> hop(-1.5, 1.5);
  for (int trial = 0; trial < 100; ++trial) {
    std::vector<Eigen::Vector3d> waypoints = {{coord(rng), coord(rng), height(rng)}};
    for (int k = 0; k < 2; ++k)
      waypoints.push_back(waypoints.back() + Eigen::Vector3d(hop(rng), hop(rng), hop(rng) / 3));
    auto tour = MinJerkTour::create(waypoints, 3.0, 4.0);
    ASSERT_TRUE(tour);
    const double t_begin_s = std::uniform_real_distribution<double>(0.0, 0.3)(rng) * tour->durationS();
    const double t_end_s = tour->durationS();
    std::vector<CheckSample> samples;
    ASSERT_TRUE(sampleTrajectory(*tour, t_begin_s, t_end_s, 0.05, samples));
    for (const TrajectoryChecker& checker : checkers) {
      const double radius_m = checker.params().radius_m + checker.params().margin_m;
      const int expected = referenceFirstCollision(samples, tree, radius_m);
      auto report = checker.check(*tour, t_begin_s, t_end_s, tree);
      ASSERT_TRUE(report) << report.error().message;
      ++trials;
      EXPECT_EQ(report->collision_free, expected < 0) << "trial " << trial;
      if (expected < 0) {
        EXPECT_EQ(report->samples_checked, static_cast<int>(samples.size()));
        continue;
      }
      ++collisions;
      ASSERT_TRUE(report->first_collision_t_s.has_value()) << "trial " << trial;
      EXPECT_EQ(*report->first_collision_t_s, samples[expected].t_s) << "trial " << trial;
      EXPECT_EQ(report->first_collision_p_W_m, samples[expected].p_W_m) << "trial " << trial;
      EXPECT_EQ(report->samples_checked, expected + 1) << "trial " << trial;
    }
  }
  // The scene is meant to give both verdicts.
  EXPECT_GT(collisions, trials / 5);
  EXPECT_LT(collisions, trials * 4 / 5);
}

// ---- sampling ----

TEST(SampleTrajectory, GivenMinJerkTourWhenSampledThenEndsIncludedAndChordsWithinStep) {
  auto tour = MinJerkTour::create({{0, 0, 1}, {3, 1, 1}, {3, 4, 2}}, 3.0, 4.0);
  ASSERT_TRUE(tour);
  std::vector<CheckSample> samples;
  ASSERT_TRUE(sampleTrajectory(*tour, -1.0, tour->durationS() + 1.0, 0.05, samples));  // clamped
  ASSERT_GE(samples.size(), 2u);
  EXPECT_EQ(samples.front().t_s, 0.0);
  EXPECT_EQ(samples.back().t_s, tour->durationS());
  double path_m = 0.0;
  for (size_t i = 1; i < samples.size(); ++i) {
    const double chord_m = (samples[i].p_W_m - samples[i - 1].p_W_m).norm();
    EXPECT_LE(chord_m, 0.05 + 1e-12);
    EXPECT_GT(samples[i].t_s, samples[i - 1].t_s);
    path_m += chord_m;
  }
  // Not wasteful: on average within 15 % of the step (path length / count).
  EXPECT_GT(path_m / static_cast<double>(samples.size() - 1), 0.85 * 0.05);
}

TEST(SampleTrajectory, GivenZeroLengthIntervalWhenSampledThenOneSample) {
  const LineTrajectory line({0, 0, 1}, {1, 0, 0}, 2.0);
  std::vector<CheckSample> samples;
  ASSERT_TRUE(sampleTrajectory(line, 1.0, 1.0, 0.05, samples));
  ASSERT_EQ(samples.size(), 1u);
  EXPECT_EQ(samples[0].t_s, 1.0);
}

TEST(SampleTrajectory, GivenJumpOrBadIntervalWhenSampledThenError) {
  std::vector<CheckSample> samples;
  EXPECT_FALSE(sampleTrajectory(JumpingTrajectory(), 0.0, 2.0, 0.05, samples));
  const LineTrajectory line({0, 0, 1}, {1, 0, 0}, 2.0);
  EXPECT_FALSE(sampleTrajectory(line, 1.0, 0.5, 0.05, samples));
  EXPECT_FALSE(sampleTrajectory(line, kNan, 0.5, 0.05, samples));
  EXPECT_FALSE(sampleTrajectory(line, 0.0, 1.0, 0.0, samples));
  const octomap::OcTree tree(kResolutionM);
  EXPECT_FALSE(makeChecker().check(JumpingTrajectory(), 0.0, 2.0, tree));
  EXPECT_FALSE(makeChecker().check(line, 0.0, kInf, tree));
}

// ---- parameters ----

TEST(TrajectoryChecker, GivenBadParamsWhenCreatedThenError) {
  const auto bad = [](auto mutate) {
    TrajectoryCheckerParams params;
    mutate(params);
    return !TrajectoryChecker::create(params).has_value();
  };
  EXPECT_FALSE(bad([](TrajectoryCheckerParams&) {}));
  EXPECT_TRUE(bad([](TrajectoryCheckerParams& p) { p.radius_m = 0.0; }));
  EXPECT_TRUE(bad([](TrajectoryCheckerParams& p) { p.radius_m = kNan; }));
  EXPECT_TRUE(bad([](TrajectoryCheckerParams& p) { p.sample_step_m = 0.0; }));
  EXPECT_TRUE(bad([](TrajectoryCheckerParams& p) { p.sample_step_m = 0.3; }));  // > radius
  EXPECT_TRUE(bad([](TrajectoryCheckerParams& p) { p.sample_step_m = kInf; }));
  EXPECT_TRUE(bad([](TrajectoryCheckerParams& p) { p.margin_m = -0.01; }));
  EXPECT_TRUE(bad([](TrajectoryCheckerParams& p) { p.margin_m = kNan; }));
  EXPECT_TRUE(bad([](TrajectoryCheckerParams& p) { p.broad_phase_group = 0; }));
  EXPECT_TRUE(bad([](TrajectoryCheckerParams& p) { p.broad_phase_group = 65; }));
  TrajectoryCheckerParams params;
  params.sample_step_m = 0.0;
  EXPECT_NE(TrajectoryChecker::create(params).error().message.find("sample_step_m"), std::string::npos);
}

}  // namespace
}  // namespace aerotrack::mapping
