// OctomapMap: batched OctoMap insertion with free-space clearing (see octomap_map.hpp). The key
// batch is an open-addressing hash set (linear probing, Fibonacci hashing of the packed 48-bit
// key) whose entries also record insertion order, so updates are applied in a deterministic
// order (ray by ray, origin outwards) and clearing costs O(entries), not O(slots). The batch is
// then applied in one pass by InsertionOcTree::applyBatch (below), which shares the walk from
// the root between consecutive keys.
#include "aerotrack/mapping/octomap_map.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <octomap/OcTreeKey.h>

namespace aerotrack::mapping {

namespace {

constexpr unsigned kInitialLog2Slots = 17;

bool isProbability(double p) {
  return p > 0.0 && p < 1.0;
}

std::uint64_t packKey(const octomap::OcTreeKey& key) {
  return static_cast<std::uint64_t>(key[0]) | (static_cast<std::uint64_t>(key[1]) << 16U) |
         (static_cast<std::uint64_t>(key[2]) << 32U);
}

octomap::OcTreeKey unpackKey(std::uint64_t packed) {
  return octomap::OcTreeKey(static_cast<octomap::key_type>(packed & 0xFFFFU),
                            static_cast<octomap::key_type>((packed >> 16U) & 0xFFFFU),
                            static_cast<octomap::key_type>((packed >> 32U) & 0xFFFFU));
}

/// |x|, |y|, |z| < extent_m (false for NaN and inf). Checked before OcTree::coordToKeyChecked,
/// whose float-to-int conversion is undefined for huge coordinates.
bool withinExtent(const octomap::point3d& p, float extent_m) {
  return std::abs(p.x()) < extent_m && std::abs(p.y()) < extent_m && std::abs(p.z()) < extent_m;
}

/// The distinct voxel keys of one frame, each flagged occupied or free (occupied wins).
class KeyBatch {
 public:
  struct Entry {
    std::uint64_t packed_key;
    std::uint32_t slot;
    bool occupied;
  };

  explicit KeyBatch(unsigned log2_slots) { allocate(log2_slots); }

  void clear() {
    for (const Entry& entry : entries_) slot_keys_[entry.slot] = kEmpty;
    entries_.clear();
  }

  /// Adds key; if present, occupied is OR-ed into its flag.
  void add(const octomap::OcTreeKey& key, bool occupied) {
    if (2 * (entries_.size() + 1) > slot_keys_.size()) grow();
    const std::uint64_t packed = packKey(key);
    std::size_t slot = slotOf(packed);
    while (true) {
      const std::uint64_t slot_key = slot_keys_[slot];
      if (slot_key == packed) {
        if (occupied) entries_[slot_entries_[slot]].occupied = true;
        return;
      }
      if (slot_key == kEmpty) {
        slot_keys_[slot] = packed;
        slot_entries_[slot] = static_cast<std::uint32_t>(entries_.size());
        entries_.push_back(Entry{packed, static_cast<std::uint32_t>(slot), occupied});
        return;
      }
      slot = (slot + 1) & mask_;
    }
  }

  const std::vector<Entry>& entries() const { return entries_; }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};  ///< Not a packed key (those use 48 bits).

  void allocate(unsigned log2_slots) {
    log2_slots_ = log2_slots;
    slot_keys_.assign(std::size_t{1} << log2_slots, kEmpty);
    slot_entries_.assign(slot_keys_.size(), 0);
    mask_ = slot_keys_.size() - 1;
    entries_.reserve(slot_keys_.size() / 2);
  }

  std::size_t slotOf(std::uint64_t packed) const {
    return static_cast<std::size_t>((packed * 0x9E3779B97F4A7C15ULL) >> (64U - log2_slots_));
  }

  /// Doubles the slots and re-inserts every entry (keeps their order).
  void grow() {
    allocate(log2_slots_ + 1);
    for (std::size_t i = 0; i < entries_.size(); ++i) {
      std::size_t slot = slotOf(entries_[i].packed_key);
      while (slot_keys_[slot] != kEmpty) slot = (slot + 1) & mask_;
      slot_keys_[slot] = entries_[i].packed_key;
      slot_entries_[slot] = static_cast<std::uint32_t>(i);
      entries_[i].slot = static_cast<std::uint32_t>(slot);
    }
  }

  unsigned log2_slots_ = 0;
  std::size_t mask_ = 0;
  std::vector<std::uint64_t> slot_keys_;     ///< Packed key per slot, or kEmpty.
  std::vector<std::uint32_t> slot_entries_;  ///< Index into entries_ per used slot.
  std::vector<Entry> entries_;               ///< Insertion order.
};

/// An OcTree that applies a whole frame's batch of voxel updates in one pass. The result equals
/// calling OcTree::updateNode(key, occupied, lazy_eval = false) once per entry -- same leaf
/// values, same inner-node values and pruning, same change-detection keys -- but the walk from the
/// root is shared between consecutive keys: a stack holds the path to the previous key, only the
/// levels below the two keys' common ancestor are left and re-entered, and an inner node's
/// occupancy / pruning is recomputed once when the walk leaves it (and only if something below it
/// changed) instead of once per update below it. Consecutive batch keys mostly lie along one ray,
/// so about two levels are re-entered per key instead of sixteen searched and sixteen updated.
/// It subclasses OcTree only to reach its protected root, changed_keys and sensor model; it adds
/// no state that a plain OcTree copy would need.
class InsertionOcTree final : public octomap::OcTree {
 public:
  explicit InsertionOcTree(double resolution_m) : octomap::OcTree(resolution_m) {}

  struct ApplyCounts {
    std::size_t saturated = 0;
    std::int64_t occupied_delta = 0;  ///< Change in occupied leaf-resolution voxels.
  };

  /// Applies the batch; appends to changes every voxel that is new or whose occupied/free state flipped.
  ApplyCounts applyBatch(const std::vector<KeyBatch::Entry>& entries, std::vector<VoxelChange>& changes) {
    ApplyCounts counts;
    if (entries.empty()) return counts;
    if (root == nullptr) {
      root = new octomap::OcTreeNode();  // NOLINT(cppcoreguidelines-owning-memory): OcTree owns it.
      ++tree_size;
      created_[0] = true;
    } else {
      created_[0] = false;
    }
    path_[0] = root;
    dirty_.fill(false);
    unsigned len = 0;  // Depth of the deepest node on path_ that is valid for the previous key.
    octomap::OcTreeKey previous;
    bool first = true;
    for (const KeyBatch::Entry& entry : entries) {
      const octomap::OcTreeKey key = unpackKey(entry.packed_key);
      if (!first) {
        const unsigned diff =
            static_cast<unsigned>((key[0] ^ previous[0]) | (key[1] ^ previous[1]) | (key[2] ^ previous[2]));
        // Keys differing first in bit b share the nodes at depths 0 .. kDepth - 1 - b.
        const unsigned common = kDepth - static_cast<unsigned>(std::bit_width(diff));
        len = unwind(len, common);
      }
      first = false;
      previous = key;
      applyOne(key, entry.occupied, len, counts, changes);
    }
    len = unwind(len, 0);
    if (dirty_[0]) finalize(path_[0]);
    return counts;
  }

 private:
  static constexpr unsigned kDepth = 16;  ///< OcTree's fixed depth (16-bit keys).

  bool unchanged(const octomap::OcTreeNode* node, bool occupied) const {
    return occupied ? node->getLogOdds() >= clamping_thres_max : node->getLogOdds() <= clamping_thres_min;
  }

  /// An inner node after its subtree changed: prune it, or set it to its children's maximum
  /// (OcTree's pruneNode, else updateOccupancyChildren). One pass over the children decides both:
  /// the two library calls would each chase the eight child pointers again.
  void finalize(octomap::OcTreeNode* node) {
    float max_log_odds = -std::numeric_limits<float>::max();  // getMaxChildLogOdds's start
    bool collapsible = true;                                  // isNodeCollapsible: 8 equal leaves
    float first = 0.0F;
    for (unsigned i = 0; i < 8; ++i) {
      if (!nodeChildExists(node, i)) {
        collapsible = false;
        continue;
      }
      const octomap::OcTreeNode* child = getNodeChild(node, i);
      const float log_odds = child->getLogOdds();
      max_log_odds = std::max(max_log_odds, log_odds);
      if (i == 0) first = log_odds;
      if (collapsible && (nodeHasChildren(child) || log_odds != first)) collapsible = false;
    }
    if (collapsible && pruneNode(node)) return;
    node->setLogOdds(max_log_odds);
  }

  /// Leaves path_ depths len .. to + 1 (finalizing the changed ones); returns min(len, to).
  unsigned unwind(unsigned len, unsigned to) {
    for (unsigned depth = std::min(len, kDepth - 1); depth > to; --depth) {
      if (!dirty_[depth]) continue;
      finalize(path_[depth]);
      dirty_[depth] = false;
      dirty_[depth - 1] = true;
    }
    return std::min(len, to);
  }

  /// OcTree::updateNode(key, occupied) from path_[len]; len becomes the depth reached.
  void applyOne(const octomap::OcTreeKey& key, bool occupied, unsigned& len, ApplyCounts& counts,
                std::vector<VoxelChange>& changes) {
    octomap::OcTreeNode* node = path_[len];
    unsigned depth = len;
    for (; depth < kDepth; ++depth) {
      if (!nodeHasChildren(node) && !created_[depth]) {
        // A pruned node covering key: leave it if the update would not change it (OcTree's
        // early abort after its search), else expand it.
        if (unchanged(node, occupied)) {
          len = depth;
          ++counts.saturated;
          return;
        }
        expandNode(node);
        dirty_[depth] = true;
      }
      const unsigned pos = octomap::computeChildIdx(key, static_cast<int>(kDepth - 1 - depth));
      bool created = false;
      if (!nodeChildExists(node, pos)) {
        createNodeChild(node, pos);
        created = true;
      }
      node = getNodeChild(node, pos);
      path_[depth + 1] = node;
      created_[depth + 1] = created;
    }
    len = kDepth;
    const bool is_new = created_[kDepth];
    if (!is_new && unchanged(node, occupied)) {
      ++counts.saturated;
      return;
    }
    const bool was_occupied = !is_new && isNodeOccupied(node);
    updateNodeLogOdds(node, occupied ? prob_hit_log : prob_miss_log);
    const bool is_occupied = isNodeOccupied(node);
    counts.occupied_delta += static_cast<std::int64_t>(is_occupied) - static_cast<std::int64_t>(was_occupied);
    if (is_new || was_occupied != is_occupied) changes.push_back(VoxelChange{key, is_occupied});
    if (use_change_detection) {  // OccupancyOcTreeBase::updateNodeRecurs's bookkeeping.
      if (is_new) {
        changed_keys.insert(std::pair<octomap::OcTreeKey, bool>(key, true));
      } else if (was_occupied != is_occupied) {
        const auto it = changed_keys.find(key);
        if (it == changed_keys.end()) {
          changed_keys.insert(std::pair<octomap::OcTreeKey, bool>(key, false));
        } else if (!it->second) {
          changed_keys.erase(it);
        }
      }
    }
    dirty_[kDepth - 1] = true;
  }

  std::array<octomap::OcTreeNode*, kDepth + 1> path_{};  ///< path_[d]: node at depth d (0: root).
  std::array<bool, kDepth + 1> created_{};               ///< path_[d] was created by the update that reached it.
  std::array<bool, kDepth + 1> dirty_{};                 ///< Something below path_[d] changed: finalize it on leaving.
};

}  // namespace

struct OctomapMap::Workspace {
  Workspace() { changes.reserve(std::size_t{1} << (kInitialLog2Slots - 1)); }
  KeyBatch batch{kInitialLog2Slots};
  std::vector<VoxelChange> changes;         ///< The latest insert's, at most one per distinct voxel.
  octomap::KeyRay ray;                      ///< Preallocated by OctoMap (100 000 keys).
  std::vector<octomap::OcTreeKey> cleared;  ///< clearColumn's voxels, gathered before the tree changes.
};

rt::Status validate(const OctomapMapParams& params) {
  if (!(params.resolution_m > 0.0) || !std::isfinite(params.resolution_m)) {
    return rt::Error{"octomap map: resolution_m must be finite and > 0, got " + std::to_string(params.resolution_m)};
  }
  if (!isProbability(params.occupancy_threshold)) {
    return rt::Error{"octomap map: occupancy_threshold must be in (0, 1), got " +
                     std::to_string(params.occupancy_threshold)};
  }
  if (!(params.prob_hit > 0.5 && params.prob_hit < 1.0)) {
    return rt::Error{"octomap map: prob_hit must be in (0.5, 1), got " + std::to_string(params.prob_hit)};
  }
  if (!(params.prob_miss > 0.0 && params.prob_miss < 0.5)) {
    return rt::Error{"octomap map: prob_miss must be in (0, 0.5), got " + std::to_string(params.prob_miss)};
  }
  if (!(params.clamp_min > 0.0 && params.clamp_min < params.occupancy_threshold &&
        params.occupancy_threshold < params.clamp_max && params.clamp_max < 1.0)) {
    return rt::Error{"octomap map: need 0 < clamp_min < occupancy_threshold < clamp_max < 1, got " +
                     std::to_string(params.clamp_min) + ", " + std::to_string(params.occupancy_threshold) + ", " +
                     std::to_string(params.clamp_max)};
  }
  return rt::ok();
}

rt::Expected<OctomapMap> OctomapMap::create(const OctomapMapParams& params) {
  if (rt::Status status = validate(params); !status) return status.error();
  std::unique_ptr<octomap::OcTree> tree = std::make_unique<InsertionOcTree>(params.resolution_m);
  tree->setProbHit(params.prob_hit);
  tree->setProbMiss(params.prob_miss);
  tree->setClampingThresMin(params.clamp_min);
  tree->setClampingThresMax(params.clamp_max);
  tree->setOccupancyThres(params.occupancy_threshold);
  // OctoMap's own change detection keeps a std::unordered_map node per changed key (an allocation
  // each, thousands per frame); insert() reports its changes in a reused vector instead.
  tree->enableChangeDetection(false);
  return OctomapMap(params, std::move(tree), std::make_unique<Workspace>());
}

OctomapMap::OctomapMap(const OctomapMapParams& params, std::unique_ptr<octomap::OcTree> tree,
                       std::unique_ptr<Workspace> workspace)
    : params_(params), tree_(std::move(tree)), workspace_(std::move(workspace)) {}

OctomapMap::OctomapMap(OctomapMap&& other) noexcept = default;
OctomapMap& OctomapMap::operator=(OctomapMap&& other) noexcept = default;
OctomapMap::~OctomapMap() = default;

rt::Expected<InsertStats> OctomapMap::insert(const octomap::Pointcloud& hits_W, const octomap::Pointcloud& misses_W,
                                             const Eigen::Vector3d& origin_W) {
  octomap::OcTree& tree = *tree_;
  workspace_->changes.clear();
  const octomap::point3d origin(static_cast<float>(origin_W.x()), static_cast<float>(origin_W.y()),
                                static_cast<float>(origin_W.z()));
  // Half the tree's edge: 2^15 voxels (3276.8 m at 0.1 m).
  const auto extent_m = static_cast<float>(tree.getResolution() * 32768.0);
  octomap::OcTreeKey key;
  if (!withinExtent(origin, extent_m) || !tree.coordToKeyChecked(origin, key)) {
    return rt::Error{"octomap map: sensor origin is not finite or outside the map's extent"};
  }

  InsertStats stats;
  stats.hit_points = hits_W.size();
  stats.miss_points = misses_W.size();
  KeyBatch& batch = workspace_->batch;
  octomap::KeyRay& ray = workspace_->ray;
  batch.clear();

  // 1. The frame's distinct voxels. Both ends are checked before computeRayKeys, which would
  // print a warning for an out-of-extent point.
  const auto add_ray = [&](const octomap::point3d& end) {
    tree.computeRayKeys(origin, end, ray);  // Origin voxel .. the voxel before end's.
    for (const octomap::OcTreeKey& free_key : ray) batch.add(free_key, false);
  };
  for (const octomap::point3d& hit : hits_W) {
    if (!withinExtent(hit, extent_m) || !tree.coordToKeyChecked(hit, key)) {
      ++stats.points_rejected;
      continue;
    }
    add_ray(hit);  // Ray first, then its end voxel: consecutive keys stay neighbours.
    batch.add(key, true);
  }
  for (const octomap::point3d& miss : misses_W) {
    if (!withinExtent(miss, extent_m) || !tree.coordToKeyChecked(miss, key)) {
      ++stats.points_rejected;
      continue;
    }
    add_ray(miss);
  }

  // 2. One update per voxel, in batch order.
  for (const KeyBatch::Entry& entry : batch.entries()) {
    if (entry.occupied) {
      ++stats.occupied_voxels;
    } else {
      ++stats.free_voxels;
    }
  }
  const InsertionOcTree::ApplyCounts counts =
      static_cast<InsertionOcTree&>(tree).applyBatch(batch.entries(), workspace_->changes);
  stats.saturated_voxels = counts.saturated;
  const std::int64_t occupied_delta = counts.occupied_delta;
  occupied_voxels_ += occupied_delta;
  ++frames_inserted_;
  last_insert_ = stats;
  return stats;
}

std::size_t OctomapMap::clearColumn(const Eigen::Vector2d& center_W_m, double radius_m, double min_z_m,
                                    double max_z_m) {
  octomap::OcTree& tree = *tree_;
  if (!center_W_m.allFinite() || !(radius_m > 0.0) || !std::isfinite(radius_m) || !std::isfinite(min_z_m) ||
      !std::isfinite(max_z_m) || !(min_z_m < max_z_m))
    return 0;
  const auto extent_m = static_cast<float>(tree.getResolution() * 32768.0);
  const octomap::point3d lo(static_cast<float>(center_W_m.x() - radius_m),
                            static_cast<float>(center_W_m.y() - radius_m), static_cast<float>(min_z_m));
  const octomap::point3d hi(static_cast<float>(center_W_m.x() + radius_m),
                            static_cast<float>(center_W_m.y() + radius_m), static_cast<float>(max_z_m));
  if (!withinExtent(lo, extent_m) || !withinExtent(hi, extent_m)) return 0;
  // Gathered first: setNodeValue may expand the pruned node an iterator stands on.
  std::vector<octomap::OcTreeKey>& keys = workspace_->cleared;
  keys.clear();
  const double radius_sq = radius_m * radius_m;
  const auto inside = [&](const octomap::OcTreeKey& key) {
    const double dx = tree.keyToCoord(key[0]) - center_W_m.x();
    const double dy = tree.keyToCoord(key[1]) - center_W_m.y();
    const double z = tree.keyToCoord(key[2]);
    return dx * dx + dy * dy < radius_sq && z >= min_z_m && z <= max_z_m;
  };
  const octomap::OcTreeKey lo_key = tree.coordToKey(lo);
  const octomap::OcTreeKey hi_key = tree.coordToKey(hi);
  const unsigned depth = tree.getTreeDepth();
  for (auto it = tree.begin_leafs_bbx(lo, hi), end = tree.end_leafs_bbx(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    // A pruned (coarse) leaf stands for 2^(depth - its depth) leaf voxels per axis: each in the column's box is
    // judged (the box bounds the work, however large a pruned block the column touches).
    const unsigned size = 1U << (depth - it.getDepth());
    const octomap::OcTreeKey base = it.getIndexKey();
    std::array<unsigned, 3> first{}, last{};
    for (std::size_t a = 0; a < 3; ++a) {
      first[a] = std::max<unsigned>(base[a], lo_key[a]);
      last[a] = std::min<unsigned>(base[a] + size - 1U, hi_key[a]);
    }
    for (unsigned x = first[0]; x <= last[0]; ++x)
      for (unsigned y = first[1]; y <= last[1]; ++y)
        for (unsigned z = first[2]; z <= last[2]; ++z) {
          const octomap::OcTreeKey key(static_cast<octomap::key_type>(x), static_cast<octomap::key_type>(y),
                                       static_cast<octomap::key_type>(z));
          if (inside(key)) keys.push_back(key);
        }
  }
  for (const octomap::OcTreeKey& key : keys) {
    tree.setNodeValue(key, tree.getClampingThresMinLog(), /*lazy_eval=*/false);
    workspace_->changes.push_back({key, false});
  }
  occupied_voxels_ -= static_cast<std::int64_t>(keys.size());
  return keys.size();
}

const std::vector<VoxelChange>& OctomapMap::changes() const {
  return workspace_->changes;
}

std::size_t OctomapMap::recountOccupiedVoxels() {
  const std::size_t count = countOccupiedVoxels(*tree_);
  occupied_voxels_ = static_cast<std::int64_t>(count);
  return count;
}

std::shared_ptr<const octomap::OcTree> OctomapMap::snapshot() const {
  auto copy = std::make_shared<octomap::OcTree>(*tree_);
  copy->resetChangeDetection();
  copy->enableChangeDetection(false);
  return copy;
}

std::size_t countOccupiedVoxels(const octomap::OcTree& tree) {
  const unsigned max_depth = tree.getTreeDepth();
  std::size_t count = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (tree.isNodeOccupied(*it)) count += std::size_t{1} << (3U * (max_depth - it.getDepth()));
  }
  return count;
}

}  // namespace aerotrack::mapping
