// Tests of OctomapMap: a wall seen from the origin (occupied wall voxels, free voxels between,
// hand-computed probabilities from the log-odds sensor model), repeated frames, misses that
// clear without occupying, occupied winning over free, change detection, the incremental
// occupied count, snapshots, and -- the reference -- equality with OctoMap's own batched update
// (OccupancyOcTreeBase::computeUpdate + updateNode, what insertPointCloud does) on a scene that
// prunes and re-expands nodes.
#include "aerotrack/mapping/octomap_map.hpp"

#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <tuple>

#include <gtest/gtest.h>

namespace aerotrack::mapping {
namespace {

constexpr double kProbTol = 1e-5;  // OctoMap stores log-odds as float.

double logOdds(double p) {
  return std::log(p / (1.0 - p));
}
double probability(double log_odds) {
  return 1.0 / (1.0 + std::exp(-log_odds));
}
/// P after n hits (n > 0) or n misses (n < 0) with the default sensor model and clamping.
double expectedProbability(int n) {
  const double l = n > 0 ? n * logOdds(0.7) : -n * logOdds(0.4);
  return probability(std::clamp(l, logOdds(0.12), logOdds(0.97)));
}

OctomapMap makeMap() {
  return OctomapMap::create().value();
}

/// Voxel centre x = 0.05 + 0.1 i (likewise y, z).
octomap::point3d centre(int i, int j, int k) {
  return {static_cast<float>(0.05 + 0.1 * i), static_cast<float>(0.05 + 0.1 * j), static_cast<float>(0.05 + 0.1 * k)};
}

const Eigen::Vector3d kOrigin(0.05, 0.05, 0.05);  // Centre of voxel (0, 0, 0).

/// A 21 x 21 voxel wall in the plane of voxel column i = 40 (x = 4.05 m).
octomap::Pointcloud wallAt4m() {
  octomap::Pointcloud wall;
  for (int j = -10; j <= 10; ++j) {
    for (int k = -10; k <= 10; ++k) wall.push_back(centre(40, j, k));
  }
  return wall;
}

/// Occupancy probability at a voxel centre, or -1 if unknown.
double probabilityAt(const octomap::OcTree& tree, const octomap::point3d& p) {
  const octomap::OcTreeNode* node = tree.search(p);
  return node == nullptr ? -1.0 : node->getOccupancy();
}

TEST(OctomapMap, GivenInvalidParams_WhenCreate_ThenError) {
  OctomapMapParams params;
  params.resolution_m = 0.0;
  EXPECT_FALSE(OctomapMap::create(params).has_value());
  params = {};
  params.prob_hit = 0.4;
  EXPECT_FALSE(OctomapMap::create(params).has_value());
  params = {};
  params.prob_miss = 0.6;
  EXPECT_FALSE(OctomapMap::create(params).has_value());
  params = {};
  params.clamp_min = 0.6;
  EXPECT_FALSE(OctomapMap::create(params).has_value());
  params = {};
  params.clamp_max = 1.0;
  EXPECT_FALSE(OctomapMap::create(params).has_value());
}

TEST(OctomapMap, GivenDefaults_WhenCreate_ThenOctomapSensorModelAndNoChanges) {
  const OctomapMap map = makeMap();
  EXPECT_DOUBLE_EQ(map.tree().getResolution(), 0.1);
  EXPECT_NEAR(map.tree().getProbHit(), 0.7, 1e-6);
  EXPECT_NEAR(map.tree().getProbMiss(), 0.4, 1e-6);
  EXPECT_NEAR(map.tree().getClampingThresMin(), 0.12, 1e-6);
  EXPECT_NEAR(map.tree().getClampingThresMax(), 0.97, 1e-6);
  EXPECT_FALSE(map.tree().isChangeDetectionEnabled());  // insert() reports changes() itself
  EXPECT_TRUE(map.changes().empty());
  EXPECT_EQ(map.occupiedVoxelCount(), 0U);
  EXPECT_EQ(map.framesInserted(), 0U);
}

TEST(OctomapMap, GivenWallAt4m_WhenInsertedOnce_ThenWallOccupiedSpaceBetweenFreeBehindUnknown) {
  OctomapMap map = makeMap();
  const InsertStats stats = map.insert(wallAt4m(), {}, kOrigin).value();
  const octomap::OcTree& tree = map.tree();
  for (int j = -10; j <= 10; ++j) {
    for (int k = -10; k <= 10; ++k) {
      ASSERT_NEAR(probabilityAt(tree, centre(40, j, k)), 0.7, kProbTol) << j << " " << k;
    }
  }
  // The central ray: voxels 0 .. 39 along x crossed once each (though ~441 rays start there).
  for (int i = 0; i < 40; ++i) EXPECT_NEAR(probabilityAt(tree, centre(i, 0, 0)), 0.4, kProbTol) << i;
  EXPECT_EQ(probabilityAt(tree, centre(41, 0, 0)), -1.0);   // Behind the wall: unknown.
  EXPECT_EQ(probabilityAt(tree, centre(20, 30, 0)), -1.0);  // Outside the field of view.
  EXPECT_EQ(stats.hit_points, 441U);
  EXPECT_EQ(stats.occupied_voxels, 441U);
  EXPECT_EQ(stats.saturated_voxels, 0U);
  EXPECT_EQ(map.occupiedVoxelCount(), 441U);
  EXPECT_EQ(countOccupiedVoxels(tree), 441U);
  EXPECT_EQ(map.framesInserted(), 1U);
  EXPECT_EQ(map.lastInsert().updatedVoxels(), stats.updatedVoxels());
}

TEST(OctomapMap, GivenOneRayAlongX_WhenInserted_ThenTenFreeVoxelsAndOneOccupied) {
  OctomapMap map = makeMap();
  octomap::Pointcloud hit;
  hit.push_back(centre(10, 0, 0));
  const InsertStats stats = map.insert(hit, {}, kOrigin).value();
  EXPECT_EQ(stats.free_voxels, 10U);  // Voxels 0 .. 9 (the origin's included).
  EXPECT_EQ(stats.occupied_voxels, 1U);
  EXPECT_EQ(stats.updatedVoxels(), 11U);
}

TEST(OctomapMap, GivenRepeatedFrames_WhenInserted_ThenProbabilitiesFollowLogOddsUntilClamped) {
  OctomapMap map = makeMap();
  const octomap::Pointcloud wall = wallAt4m();
  for (int n = 1; n <= 6; ++n) {
    const InsertStats stats = map.insert(wall, {}, kOrigin).value();
    EXPECT_NEAR(probabilityAt(map.tree(), centre(40, 3, -2)), expectedProbability(n), kProbTol) << n;
    EXPECT_NEAR(probabilityAt(map.tree(), centre(20, 0, 0)), expectedProbability(-n), kProbTol) << n;
    if (n == 6) {
      EXPECT_EQ(stats.saturated_voxels, stats.updatedVoxels());  // All clamped after 5.
    }
  }
  EXPECT_NEAR(expectedProbability(2), 0.8448, 1e-4);  // Hand check of the helper.
  EXPECT_NEAR(expectedProbability(6), 0.97, 1e-9);
  EXPECT_NEAR(expectedProbability(-6), 0.12, 1e-9);
}

TEST(OctomapMap, GivenMisses_WhenInserted_ThenRaysClearedAndNothingOccupied) {
  OctomapMap map = makeMap();
  octomap::Pointcloud misses;
  for (int j = -5; j <= 5; ++j) misses.push_back(centre(30, j, 0));
  const InsertStats stats = map.insert({}, misses, kOrigin).value();
  EXPECT_EQ(stats.occupied_voxels, 0U);
  EXPECT_EQ(stats.miss_points, 11U);
  EXPECT_EQ(countOccupiedVoxels(map.tree()), 0U);
  EXPECT_EQ(map.occupiedVoxelCount(), 0U);
  for (int i = 0; i < 30; ++i) EXPECT_NEAR(probabilityAt(map.tree(), centre(i, 0, 0)), 0.4, kProbTol) << i;
  EXPECT_EQ(probabilityAt(map.tree(), centre(30, 0, 0)), -1.0);  // The end voxel is not touched.
}

TEST(OctomapMap, GivenOccupiedVoxel_WhenMissesPassThroughIt_ThenItIsClearedWithoutReoccupying) {
  OctomapMap map = makeMap();
  octomap::Pointcloud hit;
  hit.push_back(centre(20, 0, 0));
  (void)map.insert(hit, {}, kOrigin).value();
  EXPECT_EQ(map.occupiedVoxelCount(), 1U);
  octomap::Pointcloud miss;
  miss.push_back(centre(30, 0, 0));
  // One miss: l = 0.847 - 0.405 = 0.442, P = 0.609, still occupied.
  (void)map.insert({}, miss, kOrigin).value();
  EXPECT_NEAR(probabilityAt(map.tree(), centre(20, 0, 0)), probability(logOdds(0.7) + logOdds(0.4)), kProbTol);
  EXPECT_EQ(map.occupiedVoxelCount(), 1U);
  // Three misses: l = 0.847 - 1.216 < 0: free.
  (void)map.insert({}, miss, kOrigin).value();
  (void)map.insert({}, miss, kOrigin).value();
  EXPECT_NEAR(probabilityAt(map.tree(), centre(20, 0, 0)), probability(logOdds(0.7) + 3 * logOdds(0.4)), kProbTol);
  EXPECT_EQ(map.occupiedVoxelCount(), 0U);
  EXPECT_EQ(countOccupiedVoxels(map.tree()), 0U);
}

TEST(OctomapMap, GivenHitOnAnotherHitsRay_WhenInserted_ThenOccupiedWinsAndEachVoxelUpdatedOnce) {
  OctomapMap map = makeMap();
  octomap::Pointcloud hits;
  hits.push_back(centre(20, 0, 0));
  hits.push_back(centre(40, 0, 0));  // Its ray crosses voxel 20.
  const InsertStats stats = map.insert(hits, {}, kOrigin).value();
  EXPECT_NEAR(probabilityAt(map.tree(), centre(20, 0, 0)), 0.7, kProbTol);  // One hit, no miss.
  EXPECT_NEAR(probabilityAt(map.tree(), centre(10, 0, 0)), 0.4, kProbTol);  // Crossed twice, updated once.
  EXPECT_NEAR(probabilityAt(map.tree(), centre(30, 0, 0)), 0.4, kProbTol);
  EXPECT_EQ(stats.occupied_voxels, 2U);
  EXPECT_EQ(stats.free_voxels, 39U);  // 0 .. 39 but 20.
}

std::map<std::tuple<int, int, int>, bool> changedKeys(const OctomapMap& map) {
  std::map<std::tuple<int, int, int>, bool> keys;
  for (const VoxelChange& change : map.changes()) {
    const auto [it, inserted] =
        keys.emplace(std::make_tuple(int{change.key[0]}, int{change.key[1]}, int{change.key[2]}), change.occupied);
    EXPECT_TRUE(inserted) << "a voxel reported twice";
  }
  return keys;
}

/// What OctoMap's own change detection recorded, with each voxel's state now (occupied or not).
std::map<std::tuple<int, int, int>, bool> referenceChanges(const octomap::OcTree& tree) {
  std::map<std::tuple<int, int, int>, bool> keys;
  for (auto it = tree.changedKeysBegin(); it != tree.changedKeysEnd(); ++it) {
    const octomap::OcTreeNode* node = tree.search(it->first);
    keys[{it->first[0], it->first[1], it->first[2]}] = node != nullptr && tree.isNodeOccupied(node);
  }
  return keys;
}

TEST(OctomapMap, GivenInserts_WhenReadingChanges_ThenNewVoxelsWithTheirStateThenOnlyFlippedOnes) {
  OctomapMap map = makeMap();
  const InsertStats first = map.insert(wallAt4m(), {}, kOrigin).value();
  // Every voxel of the first frame is new, reported with the state the frame gave it.
  const auto keys = changedKeys(map);
  EXPECT_EQ(keys.size(), first.updatedVoxels());
  std::size_t occupied = 0;
  for (const auto& entry : keys) occupied += entry.second ? 1 : 0;
  EXPECT_EQ(occupied, first.occupied_voxels);

  // The same frame again: nothing new, nothing flips.
  (void)map.insert(wallAt4m(), {}, kOrigin).value();
  EXPECT_TRUE(map.changes().empty());

  // A hit at voxel 30 on the central ray, free twice (l = -0.811): l = +0.036, occupied: the
  // only change.
  octomap::Pointcloud hit;
  hit.push_back(centre(30, 0, 0));
  (void)map.insert(hit, {}, kOrigin).value();
  octomap::OcTreeKey key;
  ASSERT_TRUE(map.tree().coordToKeyChecked(centre(30, 0, 0), key));
  const auto flipped = changedKeys(map);
  ASSERT_EQ(flipped.size(), 1U);
  EXPECT_EQ(flipped.begin()->first, std::make_tuple(int{key[0]}, int{key[1]}, int{key[2]}));
  EXPECT_TRUE(flipped.begin()->second);
  EXPECT_EQ(map.occupiedVoxelCount(), 442U);

  // A failed insert reports nothing.
  EXPECT_FALSE(map.insert(hit, {}, Eigen::Vector3d(std::nan(""), 0.0, 0.0)).has_value());
  EXPECT_TRUE(map.changes().empty());
}

TEST(OctomapMap, GivenBlockOccupiedUntilClamped_WhenPruned_ThenCountCoversItsEightVoxels) {
  OctomapMap map = makeMap();
  octomap::Pointcloud block;  // Keys 32788..32789 x 32768..32769 x 32768..32769: one depth-15 node.
  for (int i = 20; i <= 21; ++i) {
    for (int j = 0; j <= 1; ++j) {
      for (int k = 0; k <= 1; ++k) block.push_back(centre(i, j, k));
    }
  }
  for (int n = 0; n < 5; ++n) (void)map.insert(block, {}, kOrigin).value();
  const octomap::OcTreeNode* node = map.tree().search(centre(20, 0, 0));
  ASSERT_NE(node, nullptr);
  EXPECT_FALSE(map.tree().nodeHasChildren(node));
  octomap::OcTreeKey key;
  ASSERT_TRUE(map.tree().coordToKeyChecked(centre(20, 0, 0), key));
  unsigned depth = 0;
  for (auto it = map.tree().begin_leafs(); it != map.tree().end_leafs(); ++it) {
    if (&*it == node) depth = it.getDepth();
  }
  EXPECT_EQ(depth, 15U);  // Pruned: one node for the 8 voxels.
  EXPECT_EQ(countOccupiedVoxels(map.tree()), 8U);
  EXPECT_EQ(map.occupiedVoxelCount(), 8U);
}

TEST(OctomapMap, GivenBadPointsOrOrigin_WhenInsert_ThenPointsRejectedOrError) {
  OctomapMap map = makeMap();
  octomap::Pointcloud hits;
  hits.push_back(centre(10, 0, 0));
  hits.push_back(5000.0F, 0.0F, 0.0F);  // Beyond the +-3276.8 m extent.
  hits.push_back(std::numeric_limits<float>::quiet_NaN(), 0.0F, 0.0F);
  hits.push_back(0.0F, 1e30F, 0.0F);
  hits.push_back(0.0F, 0.0F, -std::numeric_limits<float>::infinity());
  const InsertStats stats = map.insert(hits, {}, kOrigin).value();
  EXPECT_EQ(stats.points_rejected, 4U);
  EXPECT_EQ(stats.occupied_voxels, 1U);
  const std::size_t size = map.tree().size();
  EXPECT_FALSE(map.insert(hits, {}, Eigen::Vector3d(std::nan(""), 0.0, 0.0)).has_value());
  EXPECT_FALSE(map.insert(hits, {}, Eigen::Vector3d(4000.0, 0.0, 0.0)).has_value());
  EXPECT_EQ(map.tree().size(), size);
  EXPECT_EQ(map.framesInserted(), 1U);
}

TEST(OctomapMap, GivenMap_WhenSnapshot_ThenEqualDeepCopyUnaffectedByLaterInserts) {
  OctomapMap map = makeMap();
  (void)map.insert(wallAt4m(), {}, kOrigin).value();
  const std::shared_ptr<const octomap::OcTree> snapshot = map.snapshot();
  ASSERT_NE(snapshot, nullptr);
  EXPECT_TRUE(*snapshot == map.tree());
  EXPECT_EQ(snapshot->numChangesDetected(), 0U);
  const octomap::OcTree copy(*snapshot);
  octomap::Pointcloud more;
  more.push_back(centre(0, 30, 0));
  (void)map.insert(more, {}, kOrigin).value();
  EXPECT_FALSE(*snapshot == map.tree());
  EXPECT_TRUE(*snapshot == copy);
  EXPECT_EQ(probabilityAt(*snapshot, centre(0, 30, 0)), -1.0);
}

/// A plain OcTree with the map's sensor model (OcTree's own clamping defaults are 0.1192 / 0.971).
octomap::OcTree makeReference() {
  octomap::OcTree tree(0.1);
  tree.setClampingThresMin(0.12);
  tree.setClampingThresMax(0.97);
  tree.enableChangeDetection(true);
  return tree;
}

/// OctoMap's own frame update: insertPointCloud's computeUpdate (hits, no maxrange) plus the
/// miss rays as free space, occupied winning, then updateNode per key.
void referenceInsert(octomap::OcTree& tree, const octomap::Pointcloud& hits, const octomap::Pointcloud& misses,
                     const octomap::point3d& origin) {
  octomap::KeySet free_cells;
  octomap::KeySet occupied_cells;
  tree.computeUpdate(hits, origin, free_cells, occupied_cells, -1.0);
  octomap::KeyRay ray;
  for (const octomap::point3d& p : misses) {
    if (tree.computeRayKeys(origin, p, ray)) free_cells.insert(ray.begin(), ray.end());
  }
  for (const octomap::OcTreeKey& key : occupied_cells) free_cells.erase(key);
  for (const octomap::OcTreeKey& key : free_cells) tree.updateNode(key, false);
  for (const octomap::OcTreeKey& key : occupied_cells) tree.updateNode(key, true);
}

TEST(OctomapMap, GivenClutteredFramesThatPruneAndReexpand_WhenInserted_ThenSameTreeAndChangesAsOctomap) {
  OctomapMap map = makeMap();
  octomap::OcTree reference = makeReference();
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(-1.0F, 1.0F);
  const octomap::point3d origins[] = {{0.03F, 0.02F, 1.01F}, {0.52F, -0.31F, 1.24F}, {-0.4F, 0.45F, 0.9F}};
  // A thick wall (two voxel layers, densely sampled, so its blocks clamp and prune) and random
  // rays: hits at 1 .. 5 m, misses at 6 m.
  octomap::Pointcloud wall;
  for (float y = -1.0F; y <= 1.0F; y += 0.04F) {
    for (float z = 0.0F; z <= 2.0F; z += 0.04F) {
      wall.push_back(3.02F, y, z);
      wall.push_back(3.12F, y, z);
    }
  }
  bool pruned_inner_leaf_seen = false;
  for (int round = 0; round < 10; ++round) {
    for (const octomap::point3d& origin : origins) {
      octomap::Pointcloud hits = wall;
      octomap::Pointcloud misses;
      for (int i = 0; i < 400; ++i) {
        octomap::point3d dir(1.0F, 0.7F * unit(rng), 0.5F * unit(rng));
        dir.normalize();
        const float range_m = round < 8 ? 1.0F + 2.0F * (1.0F + unit(rng)) : 0.5F + 0.75F * (1.0F + unit(rng));
        if (i % 4 == 0 && round < 8) {
          misses.push_back(origin + dir * 6.0F);
        } else {
          hits.push_back(origin + dir * range_m);  // Rounds 8, 9: obstacles inside cleared space.
        }
      }
      (void)map.insert(hits, misses, Eigen::Vector3f(origin.x(), origin.y(), origin.z()).cast<double>()).value();
      referenceInsert(reference, hits, misses, origin);
      ASSERT_TRUE(map.tree() == reference) << "round " << round;
      ASSERT_EQ(changedKeys(map), referenceChanges(reference)) << "round " << round;
      ASSERT_EQ(map.occupiedVoxelCount(), countOccupiedVoxels(map.tree())) << "round " << round;
      reference.resetChangeDetection();
    }
    for (auto it = reference.begin_leafs(); it != reference.end_leafs(); ++it) {
      if (it.getDepth() < 16) pruned_inner_leaf_seen = true;
    }
  }
  EXPECT_TRUE(pruned_inner_leaf_seen);  // The scene did exercise pruning.
  EXPECT_GT(map.occupiedVoxelCount(), 0U);
}

TEST(OctomapMap, GivenHitsOnly_WhenInserted_ThenSameTreeAsOctomapInsertPointCloud) {
  OctomapMap map = makeMap();
  octomap::OcTree reference = makeReference();
  const octomap::Pointcloud wall = wallAt4m();
  const octomap::point3d origin(0.05F, 0.05F, 0.05F);
  for (int n = 0; n < 3; ++n) {
    (void)map.insert(wall, {}, kOrigin).value();
    reference.insertPointCloud(wall, origin);
    EXPECT_TRUE(map.tree() == reference) << n;
    EXPECT_EQ(changedKeys(map), referenceChanges(reference)) << n;
    reference.resetChangeDetection();
  }
}

TEST(OctomapMap, GivenAColumnThroughAWall_WhenCleared_ThenExactlyTheVoxelsInsideAreFreeAndReported) {
  OctomapMap map = makeMap();
  for (int n = 0; n < 3; ++n) (void)map.insert(wallAt4m(), {}, kOrigin).value();
  const std::size_t before = map.occupiedVoxelCount();
  ASSERT_EQ(before, 21U * 21U);
  // Centre on the wall's column j = 0, 0.25 m wide: j = -2..2; heights 0.05 + 0.1 k in [-0.3, 0.5]: k = -3..4.
  const std::size_t cleared = map.clearColumn(Eigen::Vector2d(4.05, 0.05), 0.25, -0.3, 0.5);
  EXPECT_EQ(cleared, 5U * 8U);
  EXPECT_EQ(map.occupiedVoxelCount(), before - cleared);
  EXPECT_EQ(map.recountOccupiedVoxels(), before - cleared);
  EXPECT_EQ(map.changes().size(), cleared);
  for (const VoxelChange& change : map.changes()) EXPECT_FALSE(change.occupied);
  for (int j = -10; j <= 10; ++j) {
    for (int k = -10; k <= 10; ++k) {
      const bool inside = std::abs(j) <= 2 && k >= -3 && k <= 4;
      const double p = probabilityAt(map.tree(), centre(40, j, k));
      if (inside) {
        EXPECT_NEAR(p, probability(static_cast<double>(map.tree().getClampingThresMinLog())), kProbTol)
            << j << " " << k;
      } else {
        EXPECT_GT(p, 0.5) << j << " " << k;
      }
    }
  }
  // Nothing left to clear; a column that is not finite or has no width clears nothing.
  EXPECT_EQ(map.clearColumn(Eigen::Vector2d(4.05, 0.05), 0.25, -0.3, 0.5), 0U);
  EXPECT_EQ(map.clearColumn(Eigen::Vector2d(4.05, 0.05), 0.0, -5.0, 5.0), 0U);
  EXPECT_EQ(map.clearColumn(Eigen::Vector2d(NAN, 0.05), 1.0, -5.0, 5.0), 0U);
  EXPECT_EQ(map.clearColumn(Eigen::Vector2d(1e9, 0.05), 1.0, -5.0, 5.0), 0U);
}

TEST(OctomapMap, GivenAPrunedBlockHalfInAColumn_WhenCleared_ThenOnlyItsHalfInsideIsFree) {
  OctomapMap map = makeMap();
  octomap::Pointcloud block;  // one pruned depth-15 node (GivenBlockOccupiedUntilClamped)
  for (int i = 20; i <= 21; ++i) {
    for (int j = 0; j <= 1; ++j) {
      for (int k = 0; k <= 1; ++k) block.push_back(centre(i, j, k));
    }
  }
  for (int n = 0; n < 5; ++n) (void)map.insert(block, {}, kOrigin).value();
  // Around x = 2.05 (i = 20), y = 0.1: the i = 20 voxels are 0.05 m away, the i = 21 ones over 0.1 m.
  EXPECT_EQ(map.clearColumn(Eigen::Vector2d(2.05, 0.1), 0.08, -1.0, 1.0), 4U);
  EXPECT_EQ(map.recountOccupiedVoxels(), 4U);
  EXPECT_LT(probabilityAt(map.tree(), centre(20, 1, 1)), 0.5);
  EXPECT_GT(probabilityAt(map.tree(), centre(21, 1, 1)), 0.5);
}

}  // namespace
}  // namespace aerotrack::mapping
