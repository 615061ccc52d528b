#include "procs/objectmap/occupancy_map.h"

#include <octomap/ColorOcTree.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace slamaware::objectmap {

namespace {

VoxelKey pack(const octomap::OcTreeKey& k) { return packVoxelKey(k[0], k[1], k[2]); }
octomap::OcTreeKey unpack(VoxelKey key) {
  return octomap::OcTreeKey(static_cast<octomap::key_type>(voxelKeyAxis(key, 0)),
                            static_cast<octomap::key_type>(voxelKeyAxis(key, 1)),
                            static_cast<octomap::key_type>(voxelKeyAxis(key, 2)));
}

void applySensorModel(octomap::ColorOcTree& tree, const OccupancyOptions& o) {
  tree.setProbHit(o.prob_hit);
  tree.setProbMiss(o.prob_miss);
  tree.setClampingThresMin(o.clamp_min);
  tree.setClampingThresMax(o.clamp_max);
  tree.setOccupancyThres(0.5);
}

}  // namespace

struct OccupancyMap::Impl {
  OccupancyOptions options;
  octomap::ColorOcTree tree;
  mutable bool cache_valid = true;  // an empty tree's list is empty; a read tree's is built on use
  mutable std::vector<OccupiedVoxel> occupied;

  Impl(const OccupancyOptions& o, double resolution) : options(o), tree(resolution) {
    applySensorModel(tree, o);
  }

  void buildCache() const {
    occupied.clear();
    const double res = tree.getResolution();
    for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
      if (!tree.isNodeOccupied(*it)) continue;
      const unsigned depth = it.getDepth();
      const octomap::OcTreeKey& k = it.getKey();
      if (depth >= tree.getTreeDepth()) {
        occupied.push_back({pack(k), voxelCentre(pack(k), res).cast<float>()});
        continue;
      }
      // A pruned node (a loaded file may have them): every finest voxel it covers. A node at
      // depth d with key k spans keys [k - h, k + h) with h = 2^(15 - d) on each axis.
      const int h = 1 << (tree.getTreeDepth() - 1 - depth);
      for (int dx = -h; dx < h; ++dx)
        for (int dy = -h; dy < h; ++dy)
          for (int dz = -h; dz < h; ++dz) {
            const VoxelKey v =
                packVoxelKey(static_cast<uint32_t>(k[0] + dx), static_cast<uint32_t>(k[1] + dy),
                             static_cast<uint32_t>(k[2] + dz));
            occupied.push_back({v, voxelCentre(v, res).cast<float>()});
          }
    }
    std::sort(occupied.begin(), occupied.end(), byKey);
    cache_valid = true;
  }

  // The occupied list after an update in which the voxels `now_occupied` are occupied and
  // `now_not` are not (each voxel in one of them at most): one merge, not a pass over the tree.
  void applyChanges(std::vector<VoxelKey> now_occupied, std::vector<VoxelKey> now_not) {
    std::sort(now_occupied.begin(), now_occupied.end());
    std::sort(now_not.begin(), now_not.end());
    const double res = tree.getResolution();
    std::vector<OccupiedVoxel> merged;
    merged.reserve(occupied.size() + now_occupied.size());
    auto add = now_occupied.begin();
    auto gone = now_not.begin();
    for (const OccupiedVoxel& v : occupied) {
      for (; add != now_occupied.end() && *add < v.key; ++add)
        merged.push_back({*add, voxelCentre(*add, res).cast<float>()});
      if (add != now_occupied.end() && *add == v.key) ++add;  // was occupied already
      while (gone != now_not.end() && *gone < v.key) ++gone;
      if (gone != now_not.end() && *gone == v.key) continue;  // freed
      merged.push_back(v);
    }
    for (; add != now_occupied.end(); ++add)
      merged.push_back({*add, voxelCentre(*add, res).cast<float>()});
    occupied = std::move(merged);
  }

  static bool byKey(const OccupiedVoxel& a, const OccupiedVoxel& b) { return a.key < b.key; }
};

OccupancyMap::OccupancyMap(const OccupancyOptions& options, double resolution)
    : impl_(std::make_unique<Impl>(options, resolution)) {}
OccupancyMap::OccupancyMap(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
OccupancyMap::~OccupancyMap() = default;
OccupancyMap::OccupancyMap(OccupancyMap&&) noexcept = default;
OccupancyMap& OccupancyMap::operator=(OccupancyMap&&) noexcept = default;

double OccupancyMap::resolution() const { return impl_->tree.getResolution(); }

InsertStats OccupancyMap::insert(const std::vector<Eigen::Vector3f>& points,
                                 const Eigen::Vector3f* origin) {
  InsertStats stats;
  octomap::ColorOcTree& tree = impl_->tree;
  const OccupancyOptions& o = impl_->options;
  octomap::KeySet occupied, free;
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f& p = points[i];
    octomap::OcTreeKey key;
    if (!p.allFinite() || (origin && o.max_range > 0 && (p - *origin).norm() > o.max_range) ||
        !tree.coordToKeyChecked(octomap::point3d(p.x(), p.y(), p.z()), key)) {
      ++stats.dropped;
      continue;
    }
    occupied.insert(key);
    ++stats.points;
  }
  if (origin && origin->allFinite()) {
    // One ray per occupied voxel, to its centre (OctoMap's "discretize"): points sharing a voxel
    // would cast nearly the same ray.
    octomap::KeyRay ray;
    for (const auto& key : occupied) {
      const octomap::point3d end = tree.keyToCoord(key);
      const Eigen::Vector3f p(end.x(), end.y(), end.z());
      Eigen::Vector3f from = *origin;
      const float length = (p - from).norm();
      if (o.free_band > 0 && length > o.free_band)
        from = p - (p - from) * static_cast<float>(o.free_band / length);
      // Keys from the start voxel up to, not including, the point's voxel.
      if (!tree.computeRayKeys(octomap::point3d(from.x(), from.y(), from.z()), end, ray)) continue;
      for (const auto& k : ray)
        if (!occupied.count(k)) free.insert(k);
    }
  }
  // Lazy updates never prune, so the tree (and the .ot bytes) do not depend on the hash order.
  // Lazy updates: inner nodes are brought up to date only before writing (serialize()); the
  // leaves, which every query here reads, are exact. (A whole-tree pass per keyframe batch made a
  // 40-keyframe rebuild twice as slow.) The occupied list is brought up to date from the voxels
  // this batch touched (rebuilding it from every leaf of the tree after each keyframe was a fifth
  // of the node's time).
  std::vector<VoxelKey> now_occupied, now_not;
  const auto update = [&](const octomap::OcTreeKey& k, bool hit) {
    const octomap::ColorOcTreeNode* n = tree.updateNode(k, hit, true);
    (n && tree.isNodeOccupied(n) ? now_occupied : now_not).push_back(pack(k));
  };
  for (const auto& k : free) update(k, false);
  for (const auto& k : occupied) update(k, true);
  stats.occupied_updates = occupied.size();
  stats.free_updates = free.size();
  if (impl_->cache_valid) impl_->applyChanges(std::move(now_occupied), std::move(now_not));
  return stats;
}

void OccupancyMap::clear() {
  impl_->tree.clear();
  impl_->occupied.clear();
  impl_->cache_valid = true;
}

OccupancyMap::Cell OccupancyMap::cell(const Eigen::Vector3d& p) const {
  octomap::OcTreeKey key;
  if (!impl_->tree.coordToKeyChecked(
          octomap::point3d(static_cast<float>(p.x()), static_cast<float>(p.y()),
                           static_cast<float>(p.z())),
          key))
    return Cell::kUnknown;
  return cell(pack(key));
}

OccupancyMap::Cell OccupancyMap::cell(VoxelKey key) const {
  const octomap::ColorOcTreeNode* n = impl_->tree.search(unpack(key));
  if (!n) return Cell::kUnknown;
  return impl_->tree.isNodeOccupied(n) ? Cell::kOccupied : Cell::kFree;
}

const std::vector<OccupiedVoxel>& OccupancyMap::occupied() const {
  if (!impl_->cache_valid) impl_->buildCache();
  return impl_->occupied;
}

bool OccupancyMap::isOccupied(VoxelKey key) const {
  const auto& v = occupied();
  auto it = std::lower_bound(v.begin(), v.end(), key,
                             [](const OccupiedVoxel& a, VoxelKey k) { return a.key < k; });
  return it != v.end() && it->key == key;
}

size_t OccupancyMap::numLeaves() const { return impl_->tree.getNumLeafNodes(); }

std::string OccupancyMap::serialize(const std::function<Rgb(VoxelKey)>& colour) {
  octomap::ColorOcTree& tree = impl_->tree;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    // A pruned node takes the colour of the voxel at its key.
    const Rgb c = colour(pack(it.getKey()));
    it->setColor(c.r, c.g, c.b);
  }
  // ColorOcTree: inner nodes take the mean colour of their children. Its updateInnerOccupancy()
  // (OctoMap 1.9) does not check for an empty tree: a segment whose SLAM map sent no points yet.
  if (tree.getRoot()) tree.updateInnerOccupancy();
  std::ostringstream out;
  if (!tree.write(out)) throw std::runtime_error("OctoMap could not serialise the tree");
  return out.str();
}

namespace {

/// Checks the bytes of a ColorOcTree file before OctoMap reads them. OctoMap's reader trusts them:
/// past the end of the data it goes on creating the children a damaged byte asks for, and a chain
/// deeper than the tree's 16 levels, so 3 kB can make it build millions of nodes or write beyond
/// its keys. And an occupied leaf above the deepest level stands for every voxel below it, which
/// the map's list of occupied voxels holds one by one: a damaged root marked occupied would be
/// 2.8e14 of them. The file: text header lines (comments, "id", "size", "res") up to "data", then
/// each node depth first as its log-odds (float), colour (3 bytes) and a byte of child flags.
void checkOctreeFile(const std::string& bytes, const std::string& what) {
  auto fail = [&](const std::string& why) {
    throw std::runtime_error(what + ": not a valid OctoMap file: " + why);
  };
  if (bytes.rfind("# Octomap OcTree file", 0) != 0) fail("no OctoMap header");
  size_t at = 0;
  std::string id;
  long long declared = -1;
  double resolution = 0;
  for (;;) {
    const size_t end = bytes.find('\n', at);
    if (end == std::string::npos) fail("the header does not end with 'data'");
    const std::string line = bytes.substr(at, end - at);
    at = end + 1;
    if (line.empty() || line[0] == '#') continue;
    if (line == "data") break;
    std::istringstream ls(line);
    std::string key;
    ls >> key;
    if (key == "id")
      ls >> id;
    else if (key == "size")
      ls >> declared;
    else if (key == "res")
      ls >> resolution;
    else
      fail("unexpected header line '" + line.substr(0, 40) + "'");
    if (ls.fail()) fail("unreadable header line '" + line.substr(0, 40) + "'");
  }
  if (id != "ColorOcTree") fail("tree type '" + id + "', expected ColorOcTree");
  if (!(resolution > 0) || !std::isfinite(resolution)) fail("resolution is not a positive number");
  if (declared < 0) fail("no node count");
  constexpr int kDepth = 16;        // OctoMap's tree depth: nodes at this level have no children
  constexpr size_t kNodeBytes = 8;  // float log-odds, r, g, b, child flags
  long long nodes = 0;
  double occupied_voxels = 0;
  if (declared > 0) {
    std::vector<int> pending = {0};  // depths of the nodes still to read, depth first
    while (!pending.empty()) {
      const int depth = pending.back();
      pending.pop_back();
      if (bytes.size() - at < kNodeBytes) fail("the data end inside node " + std::to_string(nodes));
      float log_odds;
      std::memcpy(&log_odds, bytes.data() + at, sizeof(float));
      if (!std::isfinite(log_odds))
        fail("node " + std::to_string(nodes) + " has no finite occupancy");
      const auto children = static_cast<uint8_t>(bytes[at + 7]);
      at += kNodeBytes;
      ++nodes;
      if (children && depth == kDepth) fail("a node below the deepest level");
      // An occupied leaf (the occupancy threshold is 0.5, log-odds 0) covers 8^(16 - depth) voxels.
      if (!children && log_odds >= 0) {
        occupied_voxels += std::ldexp(1.0, 3 * (kDepth - depth));
        if (occupied_voxels > static_cast<double>(kMaxOccupiedVoxels))
          fail("its occupied nodes cover more than " + std::to_string(kMaxOccupiedVoxels) +
               " voxels");
      }
      for (int i = 0; i < 8; ++i)
        if (children & (1u << i)) pending.push_back(depth + 1);
    }
  }
  if (at != bytes.size()) fail(std::to_string(bytes.size() - at) + " bytes after the last node");
  if (nodes != declared)
    fail("the header says " + std::to_string(declared) + " nodes, the data hold " +
         std::to_string(nodes));
}

}  // namespace

OccupancyMap OccupancyMap::deserialize(const std::string& bytes, const OccupancyOptions& options,
                                       const std::string& what) {
  checkOctreeFile(bytes, what);
  std::istringstream in(bytes);
  // OctoMap reports progress and problems on std::cerr: keep them for the error message only.
  std::ostringstream chatter;
  std::streambuf* cerr_buf = std::cerr.rdbuf(chatter.rdbuf());
  std::unique_ptr<octomap::AbstractOcTree> tree;
  try {
    tree.reset(octomap::AbstractOcTree::read(in));
  } catch (...) {
    std::cerr.rdbuf(cerr_buf);
    throw;
  }
  std::cerr.rdbuf(cerr_buf);
  auto* color = dynamic_cast<octomap::ColorOcTree*>(tree.get());
  if (!color)
    throw std::runtime_error(what + ": not an OctoMap ColorOcTree (" + chatter.str() + ")");
  if (!(color->getResolution() > 0))
    throw std::runtime_error(what + ": resolution is not positive");
  auto impl = std::make_unique<Impl>(options, color->getResolution());
  impl->tree.swapContent(*color);
  impl->cache_valid = false;
  return OccupancyMap(std::move(impl));
}

bool OccupancyMap::colourOf(VoxelKey key, Rgb* colour) const {
  const octomap::ColorOcTreeNode* n = impl_->tree.search(unpack(key));
  if (!n) return false;
  const auto c = n->getColor();
  *colour = Rgb{c.r, c.g, c.b};
  return true;
}

}  // namespace slamaware::objectmap
