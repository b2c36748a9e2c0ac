// The mapper's own behaviour: frames without a pose are skipped and counted, published grid
// snapshots stay as they were while the mapper moves on, the pool is reused, the grid synced from
// the insertion's change list equals a rebuild from the tree, and the octree snapshot holds the
// occupied voxels of the window and nothing else (checked voxel by voxel against the source tree,
// coarse leaves across the box's faces included).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "aerotrack/mapping/mapper.hpp"
#include "grid/grid_test_util.hpp"

namespace aerotrack::mapping {
namespace {

hal::OdometrySample still(rt::TimeNs t_ns) {
  hal::OdometrySample s;
  s.stamp_ns = t_ns;
  s.p_WB_m = Eigen::Vector3d(0, 0, 1.0);
  return s;
}

/// A 40 x 30 depth image of a wall at `range_m` straight ahead (camera looks along body x).
hal::DepthFrame wallFrame(rt::TimeNs t_ns, float range_m) {
  hal::DepthFrame f;
  f.stamp_ns = t_ns;
  f.intrinsics = {40, 30, 20.0, 20.0, 20.0, 15.0, {}};
  f.depth_m = cv::Mat(30, 40, CV_32FC1, cv::Scalar(static_cast<double>(range_m)));
  Eigen::Matrix3d optical;
  optical << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  f.T_BC.linear() = optical;
  return f;
}

MapperParams smallParams() {
  MapperParams p;
  p.points.decimation = 1;
  p.grid.size_m = Eigen::Vector3d(10, 10, 4);
  p.octree_snapshot_every_n_frames = 2;
  return p;
}

TEST(Mapper, GivenNoPoseAtTheFramesTimeThenSkippedAndCounted) {
  auto mapper = Mapper::create(smallParams());
  ASSERT_TRUE(mapper);
  EXPECT_FALSE(mapper->insert(wallFrame(1'000'000, 3.0F)));  // no odometry at all
  mapper->addOdometry(still(0));
  mapper->addOdometry(still(10'000'000));
  EXPECT_FALSE(mapper->insert(wallFrame(50'000'000, 3.0F)));  // after the newest sample
  EXPECT_EQ(mapper->stats().frames_skipped_no_pose, 2U);
  EXPECT_EQ(mapper->stats().frames_inserted, 0U);
  EXPECT_TRUE(mapper->insert(wallFrame(5'000'000, 3.0F)));
  EXPECT_EQ(mapper->stats().frames_inserted, 1U);
}

TEST(Mapper, PublishedGridSnapshotsDoNotChangeAndThePoolIsReused) {
  auto mapper = Mapper::create(smallParams());
  ASSERT_TRUE(mapper);
  for (int i = 0; i <= 10; ++i) mapper->addOdometry(still(i * 10'000'000LL));
  const auto first = mapper->insert(wallFrame(10'000'000, 3.0F));
  ASSERT_TRUE(first);
  const Eigen::Vector3d wall(3.05, 0.0, 1.0);
  EXPECT_TRUE(first->grid->isOccupied(wall));
  EXPECT_FALSE(first->grid->isOccupied(Eigen::Vector3d(4.05, 0.0, 1.0)));
  // A later frame sees the wall a metre farther; the first snapshot must not change.
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(mapper->insert(wallFrame(20'000'000 + i, 4.0F)));
  EXPECT_FALSE(first->grid->isOccupied(Eigen::Vector3d(4.05, 0.0, 1.0)));
  EXPECT_TRUE(mapper->grid().isOccupied(Eigen::Vector3d(4.05, 0.0, 1.0)));
  EXPECT_EQ(mapper->stats().grid_snapshots_allocated, 0U);  // the pool of three sufficed
}

hal::OdometrySample at(rt::TimeNs t_ns, const Eigen::Vector3d& p_WB_m, double yaw_rad) {
  hal::OdometrySample s = still(t_ns);
  s.p_WB_m = p_WB_m;
  s.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()));
  return s;
}

TEST(Mapper, GivenAMovingTurningCameraThenTheGridSyncedFromTheInsertsEqualsARebuildFromTheTree) {
  MapperParams params = smallParams();
  params.grid.recenter_distance_m = 0.5;  // the window moves several times
  params.grid.inflation_radius_m = 0.35;
  auto mapper = Mapper::create(params);
  ASSERT_TRUE(mapper);
  // The drone flies along x and turns while the wall's range changes: voxels appear, turn occupied,
  // and are cleared again by later rays.
  for (int i = 0; i < 24; ++i) {
    const rt::TimeNs t_ns = (i + 1) * 100'000'000LL;
    mapper->addOdometry(at(t_ns - 10'000'000, Eigen::Vector3d(0.2 * i, 0.05 * i, 1.0), 0.15 * std::sin(0.5 * i)));
    mapper->addOdometry(at(t_ns + 10'000'000, Eigen::Vector3d(0.2 * i, 0.05 * i, 1.0), 0.15 * std::sin(0.5 * i)));
    const float range_m = i % 3 == 0 ? 2.5F : 3.5F + 0.1F * static_cast<float>(i % 5);
    ASSERT_TRUE(mapper->insert(wallFrame(t_ns, range_m)));
    test::expectSameGrid(mapper->grid(), test::rebuiltAt(mapper->grid(), mapper->octomap().tree()),
                         "frame " + std::to_string(i));
  }
  EXPECT_GT(mapper->octomap().occupiedVoxelCount(), 100U);
}

/// Inner nodes hold their children's maximum log-odds (OctoMap's invariant); returns the node's.
float expectInnerMaxima(const octomap::OcTree& tree, const octomap::OcTreeNode* node) {
  if (!tree.nodeHasChildren(node)) return node->getLogOdds();
  float max = -1e9F;
  for (unsigned i = 0; i < 8; ++i)
    if (tree.nodeChildExists(node, i)) max = std::max(max, expectInnerMaxima(tree, tree.getNodeChild(node, i)));
  EXPECT_FLOAT_EQ(node->getLogOdds(), max);
  return node->getLogOdds();
}

TEST(OccupiedSnapshot, GivenPrunedBlocksAcrossTheBoxThenEveryVoxelMatchesTheSourceInsideAndIsAbsentOutside) {
  octomap::OcTree tree(0.1);
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> cell(-20, 19);
  std::uniform_int_distribution<int> coin(0, 2);
  // Free and occupied voxels at random, with unclamped values too; then aligned 4 x 4 x 4 blocks
  // driven to the upper clamp, which OctoMap prunes to one depth-14 leaf each.
  for (int i = 0; i < 3000; ++i) {
    const CellIndex c(cell(rng), cell(rng), cell(rng));
    tree.updateNode(test::keyOf(c), coin(rng) == 0);
  }
  for (const CellIndex& corner : {CellIndex(-4, -4, 0), CellIndex(8, 0, -4), CellIndex(0, 4, 0)}) {
    for (int n = 0; n < 6; ++n)
      for (int dx = 0; dx < 4; ++dx)
        for (int dy = 0; dy < 4; ++dy)
          for (int dz = 0; dz < 4; ++dz) tree.updateNode(test::keyOf(corner + CellIndex(dx, dy, dz)), true);
  }
  bool coarse = false;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) coarse |= it.getDepth() < 16;
  ASSERT_TRUE(coarse);
  // The box's faces cut through the blocks at (-4..-1, -4..-1, 0..3) and (8..11, 0..3, -4..-1); the
  // block at (0..3, 4..7, 0..3) lies inside.
  const CellIndex lo(-2, -3, -2);
  const CellIndex hi(10, 15, 6);
  const auto snapshot =
      occupiedSnapshot(tree, lo.cast<double>() * 0.1 + Eigen::Vector3d::Constant(0.01), hi.cast<double>() * 0.1);
  std::size_t inside_occupied = 0;
  for (int x = -22; x < 22; ++x)
    for (int y = -22; y < 22; ++y)
      for (int z = -22; z < 22; ++z) {
        const CellIndex c(x, y, z);
        const octomap::OcTreeNode* source = tree.search(test::keyOf(c));
        const bool in_box = (c.array() >= lo.array()).all() && (c.array() < hi.array()).all();
        const bool expected = in_box && source != nullptr && tree.isNodeOccupied(source);
        const octomap::OcTreeNode* copied = snapshot->search(test::keyOf(c));
        ASSERT_EQ(copied != nullptr, expected) << x << " " << y << " " << z;
        if (!expected) continue;
        ++inside_occupied;
        EXPECT_EQ(copied->getLogOdds(), source->getLogOdds());
      }
  EXPECT_GT(inside_occupied, 100U);  // the inside block alone has 64
  for (auto it = snapshot->begin_leafs(), end = snapshot->end_leafs(); it != end; ++it)
    EXPECT_TRUE(snapshot->isNodeOccupied(*it));
  expectInnerMaxima(*snapshot, snapshot->getRoot());
  // The block inside stays one coarse leaf, as in the source.
  const octomap::OcTreeNode* block = snapshot->search(test::keyOf(CellIndex(1, 5, 2)));
  unsigned block_depth = 0;
  for (auto it = snapshot->begin_leafs(), end = snapshot->end_leafs(); it != end; ++it)
    if (&*it == block) block_depth = it.getDepth();
  EXPECT_EQ(block_depth, 14U);
}

TEST(Mapper, OctreeSnapshotHoldsTheWindowsOccupiedVoxelsOnly) {
  auto mapper = Mapper::create(smallParams());
  ASSERT_TRUE(mapper);
  for (int i = 0; i <= 10; ++i) mapper->addOdometry(still(i * 10'000'000LL));
  ASSERT_TRUE(mapper->insert(wallFrame(10'000'000, 3.0F)));
  EXPECT_TRUE(mapper->octreeDue());  // first frame, then every second
  const auto snapshot = mapper->octreeSnapshot();
  std::size_t occupied = 0, free = 0;
  for (auto it = snapshot->begin_leafs(), end = snapshot->end_leafs(); it != end; ++it)
    (snapshot->isNodeOccupied(*it) ? occupied : free) += 1;
  EXPECT_EQ(free, 0U);  // the source tree also has thousands of free voxels along the rays
  EXPECT_GT(occupied, 100U);
  const octomap::OcTreeNode* node = snapshot->search(3.05, 0.0, 1.0);
  ASSERT_NE(node, nullptr);
  EXPECT_TRUE(snapshot->isNodeOccupied(node));
  // A voxel outside the window is left out.
  const auto outside = occupiedSnapshot(mapper->octomap().tree(), Eigen::Vector3d(-1, -1, 0), Eigen::Vector3d(1, 1, 2));
  EXPECT_EQ(outside->getNumLeafNodes(), 0U);
}

TEST(BodyAround, GivenAnEstimateThenTheColumnGrowsWithTheMajorAxisOfItsUncertaintyAndTooUncertainIsNone) {
  TargetExclusionParams params;
  params.body_radius_m = 0.4;
  params.sigmas = 2.0;
  params.max_radius_m = 1.2;
  params.floor_above_estimate_m = 0.5;
  params.height_above_estimate_m = 2.5;
  // A covariance of std 0.1 m along (1, 1) / sqrt 2 and 0.3 m across it: the major axis is 0.3 m.
  const Eigen::Matrix2d R = Eigen::Rotation2Dd(M_PI / 4).toRotationMatrix();
  const Eigen::Matrix2d cov = R * Eigen::Vector2d(0.01, 0.09).asDiagonal() * R.transpose();
  const std::optional<ExcludedBody> body = bodyAround(Eigen::Vector3d(1.0, 2.0, -0.3), cov, params);
  ASSERT_TRUE(body.has_value());
  EXPECT_TRUE(body->center_W_m.isApprox(Eigen::Vector2d(1.0, 2.0)));
  EXPECT_NEAR(body->radius_m, 0.4 + 2.0 * 0.3, 1e-12);
  EXPECT_NEAR(body->min_z_m, 0.2, 1e-12);
  EXPECT_NEAR(body->max_z_m, 2.2, 1e-12);
  // An uncertain estimate (std 0.5 m: 1.4 m wide): nothing, rather than a wall beside the person erased.
  EXPECT_FALSE(bodyAround(Eigen::Vector3d::Zero(), 0.25 * Eigen::Matrix2d::Identity(), params).has_value());
  // Off, or an estimate that is not finite: nothing.
  EXPECT_FALSE(
      bodyAround(Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0), cov, params).has_value());
  params.enabled = false;
  EXPECT_FALSE(bodyAround(Eigen::Vector3d::Zero(), cov, params).has_value());
}

}  // namespace
}  // namespace aerotrack::mapping
