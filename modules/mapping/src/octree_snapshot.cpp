// occupiedSnapshot(): the occupied voxels of an octree inside a box, as a new octree (see
// mapper.hpp). In a file of its own because GCC 12 reports -Wnull-dereference inside OctoMap's leaf
// iterator (OcTreeIterator.hxx, its stack of StackElement) wherever that iterator is instantiated
// with this loop: a false positive in third-party code, silenced for this file only.
#pragma GCC diagnostic ignored "-Wnull-dereference"

#include "aerotrack/mapping/mapper.hpp"

namespace aerotrack::mapping {

std::shared_ptr<const octomap::OcTree> occupiedSnapshot(const octomap::OcTree& tree, const Eigen::Vector3d& min_W_m,
                                                        const Eigen::Vector3d& max_W_m) {
  auto out = std::make_shared<octomap::OcTree>(tree.getResolution());
  out->setProbHit(tree.getProbHit());
  out->setProbMiss(tree.getProbMiss());
  out->setClampingThresMin(tree.getClampingThresMin());
  out->setClampingThresMax(tree.getClampingThresMax());
  out->setOccupancyThres(tree.getOccupancyThres());
  const octomap::point3d lo(static_cast<float>(min_W_m.x()), static_cast<float>(min_W_m.y()),
                            static_cast<float>(min_W_m.z()));
  const octomap::point3d hi(static_cast<float>(max_W_m.x()), static_cast<float>(max_W_m.y()),
                            static_cast<float>(max_W_m.z()));
  const unsigned max_depth = tree.getTreeDepth();
  for (auto it = tree.begin_leafs_bbx(lo, hi), end = tree.end_leafs_bbx(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const float log_odds = it->getLogOdds();
    // A pruned leaf at depth d stands for 2^(max_depth - d) voxels per axis: set each of them.
    const unsigned span = 1U << (max_depth - it.getDepth());
    const octomap::OcTreeKey base = tree.coordToKey(it.getCoordinate(), it.getDepth());
    const unsigned half = span / 2;
    for (unsigned dx = 0; dx < span; ++dx)
      for (unsigned dy = 0; dy < span; ++dy)
        for (unsigned dz = 0; dz < span; ++dz) {
          octomap::OcTreeKey k = span == 1 ? it.getKey() : base;
          if (span > 1) {
            k[0] = static_cast<octomap::key_type>(base[0] - half + dx);
            k[1] = static_cast<octomap::key_type>(base[1] - half + dy);
            k[2] = static_cast<octomap::key_type>(base[2] - half + dz);
          }
          out->setNodeValue(k, log_odds, true);
        }
  }
  out->updateInnerOccupancy();
  return out;
}

}  // namespace aerotrack::mapping
