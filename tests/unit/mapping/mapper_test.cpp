// The mapper's own behaviour: frames without a pose are skipped and counted, published grid
// snapshots stay as they were while the mapper moves on, the pool is reused, and the octree
// snapshot holds the occupied voxels of the window and nothing else.
#include <gtest/gtest.h>

#include <cmath>

#include "aerotrack/mapping/mapper.hpp"

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
  f.depth_m = cv::Mat(30, 40, CV_32FC1, cv::Scalar(range_m));
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

}  // namespace
}  // namespace aerotrack::mapping
