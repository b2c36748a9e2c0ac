// occupiedSnapshot(): the occupied voxels of an octree inside a box, as a new octree (see mapper.hpp).
//
// The copy walks the source tree from the root and enters only the children that overlap the box and
// hold something occupied. OctoMap keeps an inner node at the maximum log-odds of its children
// (OcTreeNode::updateOccupancyChildren, which our insertion calls too), so an inner node that is not
// occupied has no occupied voxel below it and its whole subtree -- most of the map is free space -- is
// skipped without visiting it. Occupied leaves are copied as they are, coarse (pruned) ones included:
// FCL's octree collision treats any leaf as a box of its size. A coarse leaf that straddles the box's
// faces is split so that only its voxels inside the box are kept. Nodes are created directly under
// their parent, never by a walk from the root per voxel.
#include "aerotrack/mapping/mapper.hpp"

namespace aerotrack::mapping {

namespace {

using octomap::key_type;
using octomap::OcTreeKey;
using octomap::OcTreeNode;

constexpr unsigned kTreeDepth = 16;

/// Key box [lo, hi) per axis.
struct KeyBox {
  std::array<unsigned, 3> lo{};
  std::array<unsigned, 3> hi{};
  /// Relation of the cube [base, base + span) to the box: 0 disjoint, 1 partly inside, 2 inside.
  int relation(const std::array<unsigned, 3>& base, unsigned span) const {
    bool inside = true;
    for (int a = 0; a < 3; ++a) {
      if (base[a] + span <= lo[a] || base[a] >= hi[a]) return 0;
      if (base[a] < lo[a] || base[a] + span > hi[a]) inside = false;
    }
    return inside ? 2 : 1;
  }
};

/// An OcTree that can be filled node by node. Subclasses OcTree only to create its root (protected);
/// it adds no state.
class SnapshotOcTree final : public octomap::OcTree {
 public:
  explicit SnapshotOcTree(const octomap::OcTree& source) : octomap::OcTree(source.getResolution()) {
    setProbHit(source.getProbHit());
    setProbMiss(source.getProbMiss());
    setClampingThresMin(source.getClampingThresMin());
    setClampingThresMax(source.getClampingThresMax());
    setOccupancyThres(source.getOccupancyThres());
  }

  void copyOccupied(const octomap::OcTree& source, const KeyBox& box) {
    const OcTreeNode* source_root = source.getRoot();
    if (source_root == nullptr || !occupiedInBox(source, source_root, 0, {0, 0, 0}, box)) return;
    root = new OcTreeNode();  // NOLINT(cppcoreguidelines-owning-memory): OcTree owns it.
    ++tree_size;
    copyChildren(source, source_root, root, 0, {0, 0, 0}, box);
  }

 private:
  /// Whether the source node (at depth, its cube's lowest key base; inner) has an occupied voxel in box.
  static bool occupiedInBox(const octomap::OcTree& source, const OcTreeNode* source_node, unsigned depth,
                            const std::array<unsigned, 3>& base, const KeyBox& box) {
    const unsigned child_span = 1U << (kTreeDepth - 1 - depth);
    for (unsigned i = 0; i < 8; ++i) {
      if (!source.nodeChildExists(source_node, i)) continue;
      const OcTreeNode* source_child = source.getNodeChild(source_node, i);
      if (!source.isNodeOccupied(source_child)) continue;  // nothing occupied below
      const std::array<unsigned, 3> child_base = childBase(base, i, child_span);
      const int relation = box.relation(child_base, child_span);
      if (relation == 0) continue;
      if (relation == 2 || !source.nodeHasChildren(source_child)) return true;
      if (occupiedInBox(source, source_child, depth + 1, child_base, box)) return true;
    }
    return false;
  }

  /// Copies below node the occupied content of source_node (inner, at depth, its cube's lowest key
  /// base) inside box, which occupiedInBox() found not empty; sets node to its children's maximum.
  /// Only children that will hold something are created, so none is ever deleted again.
  void copyChildren(const octomap::OcTree& source, const OcTreeNode* source_node, OcTreeNode* node, unsigned depth,
                    const std::array<unsigned, 3>& base, const KeyBox& box) {
    const unsigned child_span = 1U << (kTreeDepth - 1 - depth);
    for (unsigned i = 0; i < 8; ++i) {
      if (!source.nodeChildExists(source_node, i)) continue;
      const OcTreeNode* source_child = source.getNodeChild(source_node, i);
      if (!source.isNodeOccupied(source_child)) continue;
      const std::array<unsigned, 3> child_base = childBase(base, i, child_span);
      const int relation = box.relation(child_base, child_span);
      if (relation == 0) continue;
      const bool inner = source.nodeHasChildren(source_child);
      if (relation == 1 && inner && !occupiedInBox(source, source_child, depth + 1, child_base, box)) continue;
      OcTreeNode* child = createNodeChild(node, i);
      child->setLogOdds(source_child->getLogOdds());
      if (inner) {
        copyChildren(source, source_child, child, depth + 1, child_base, box);
      } else if (relation == 1) {  // a coarse leaf across the box's faces: keep its voxels inside
        splitLeaf(child, depth + 1, child_base, box);
      }
    }
    node->updateOccupancyChildren();
  }

  /// node: a leaf at depth copied from a coarse occupied source leaf that is partly inside box. Gives
  /// it the children (same value) that overlap the box, recursively.
  void splitLeaf(OcTreeNode* node, unsigned depth, const std::array<unsigned, 3>& base, const KeyBox& box) {
    const unsigned child_span = 1U << (kTreeDepth - 1 - depth);
    for (unsigned i = 0; i < 8; ++i) {
      const std::array<unsigned, 3> child_base = childBase(base, i, child_span);
      const int relation = box.relation(child_base, child_span);
      if (relation == 0) continue;
      OcTreeNode* child = createNodeChild(node, i);
      child->setLogOdds(node->getLogOdds());
      if (relation == 1) splitLeaf(child, depth + 1, child_base, box);
    }
  }

  /// OctoMap's child order: bit 0 of i is x, bit 1 y, bit 2 z (octomap::computeChildIdx).
  static std::array<unsigned, 3> childBase(const std::array<unsigned, 3>& base, unsigned i, unsigned child_span) {
    return {base[0] + ((i & 1U) != 0 ? child_span : 0U), base[1] + ((i & 2U) != 0 ? child_span : 0U),
            base[2] + ((i & 4U) != 0 ? child_span : 0U)};
  }
};

}  // namespace

std::shared_ptr<const octomap::OcTree> occupiedSnapshot(const octomap::OcTree& tree, const Eigen::Vector3d& min_W_m,
                                                        const Eigen::Vector3d& max_W_m) {
  auto out = std::make_shared<SnapshotOcTree>(tree);
  // Voxels whose key lies in [key(min), key(max)): the voxels of the cells [floor(min/res), floor(max/res)).
  KeyBox box;
  const double inv_res = 1.0 / tree.getResolution();
  const auto to_key = [inv_res](double v) {
    const double k = std::floor(v * inv_res) + 32768.0;
    return static_cast<unsigned>(std::clamp(k, 0.0, 65536.0));
  };
  for (int a = 0; a < 3; ++a) {
    box.lo[a] = to_key(min_W_m[a]);
    box.hi[a] = to_key(max_W_m[a]);
  }
  out->copyOccupied(tree, box);
  return out;
}

}  // namespace aerotrack::mapping
