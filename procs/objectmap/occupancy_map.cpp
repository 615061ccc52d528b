#include "procs/objectmap/occupancy_map.h"

#include <octomap/ColorOcTree.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iostream>
#include <iterator>
#include <map>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
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

double logit(double p) { return std::log(p / (1.0 - p)); }

// A voxel's evidence: its log-odds in the tree before (read from a file, or of the keyframes
// before a freeze), and the keyframes that saw it occupied or free since. 8 bytes: counts of
// 16 bits, kept within their range (a voxel of more than 32,767 keyframes at once, far beyond a
// SLAM map's, would stop counting there).
struct Evidence {
  float base = 0;
  int16_t hits = 0, misses = 0;
};
constexpr int kMaxCount = INT16_MAX;

// What one keyframe contributed: the points given (as given, for "unchanged") and the voxels it
// updated, each sorted.
struct KeyframeRecord {
  std::vector<Eigen::Vector3f> points;
  Eigen::Vector3f origin = Eigen::Vector3f::Zero();
  bool has_origin = false;
  bool one_origin = true;  // every batch of points came with the same origin
  std::vector<VoxelKey> occupied, free;
};

bool sameBits(const std::vector<Eigen::Vector3f>& a, const std::vector<Eigen::Vector3f>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Eigen::Vector3f)) == 0);
}
bool sameOrigin(const KeyframeRecord& r, const Eigen::Vector3f* origin) {
  if (!r.one_origin || r.has_origin != (origin != nullptr)) return false;
  return !origin || std::memcmp(r.origin.data(), origin->data(), sizeof(Eigen::Vector3f)) == 0;
}

// a \ b of sorted vectors.
std::vector<VoxelKey> minus(const std::vector<VoxelKey>& a, const std::vector<VoxelKey>& b) {
  std::vector<VoxelKey> out;
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}
std::vector<VoxelKey> common(const std::vector<VoxelKey>& a, const std::vector<VoxelKey>& b) {
  std::vector<VoxelKey> out;
  std::set_intersection(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}
std::vector<VoxelKey> merged(const std::vector<VoxelKey>& a, const std::vector<VoxelKey>& b) {
  std::vector<VoxelKey> out;
  out.reserve(a.size() + b.size());
  std::merge(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

}  // namespace

struct OccupancyMap::Impl {
  OccupancyOptions options;
  // While `live`, the evidence is in `voxels` and the tree is empty but for the moment it is
  // written out (and does the key and ray arithmetic); a map read from a file or frozen keeps its
  // evidence in the tree only (less memory) until a keyframe is given (thaw()). (OctoMap 1.9's
  // deleteNode cannot remove a leaf whose parent has no other child, so the tree is built afresh
  // rather than kept in step.)
  octomap::ColorOcTree tree;
  bool live = true;
  std::unordered_map<VoxelKey, Evidence> voxels;
  std::map<int32_t, KeyframeRecord> keyframes;
  float hit, miss, low, high;       // log-odds
  mutable bool cache_valid = true;  // an empty map's list is empty; a read map's is built on use
  mutable std::vector<OccupiedVoxel> occupied;

  Impl(const OccupancyOptions& o, double resolution)
      : options(o),
        tree(resolution),
        hit(static_cast<float>(logit(o.prob_hit))),
        miss(static_cast<float>(logit(o.prob_miss))),
        low(static_cast<float>(logit(o.clamp_min))),
        high(static_cast<float>(logit(o.clamp_max))) {
    applySensorModel(tree, o);
  }

  float logOdds(const Evidence& e) const {
    const double v = static_cast<double>(e.base) + e.hits * static_cast<double>(hit) +
                     e.misses * static_cast<double>(miss);
    return std::clamp(static_cast<float>(v), low, high);
  }
  const Evidence* find(VoxelKey key) const {
    auto it = voxels.find(key);
    return it == voxels.end() ? nullptr : &it->second;
  }

  // Calls f(key, log-odds) for every finest voxel of the tree's leaves (`all`) or of its occupied
  // ones. A pruned occupied node (a file may have them) stands for every finest voxel it covers
  // (checkOctreeFile bounds their number). A pruned free node is skipped (this map never writes
  // one; a file's stays in the tree, its voxels unknown to a thawed map).
  template <class F>
  void forEachLeafVoxel(bool all, F f) const {
    const unsigned depth_max = tree.getTreeDepth();
    for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
      const float v = it->getLogOdds();
      const bool occ = tree.isNodeOccupied(*it);
      if (!all && !occ) continue;
      const octomap::OcTreeKey& k = it.getKey();
      if (it.getDepth() >= depth_max) {
        f(pack(k), v);
        continue;
      }
      if (!occ) continue;
      // A node at depth d with key k spans keys [k - h, k + h) with h = 2^(15 - d) on each axis.
      const int h = 1 << (depth_max - 1 - it.getDepth());
      for (int dx = -h; dx < h; ++dx)
        for (int dy = -h; dy < h; ++dy)
          for (int dz = -h; dz < h; ++dz)
            f(packVoxelKey(static_cast<uint32_t>(k[0] + dx), static_cast<uint32_t>(k[1] + dy),
                           static_cast<uint32_t>(k[2] + dz)),
              v);
    }
  }

  void buildCache() const {
    occupied.clear();
    const double res = tree.getResolution();
    if (live) {
      for (const auto& [key, e] : voxels)
        if (logOdds(e) >= 0) occupied.push_back({key, voxelCentre(key, res).cast<float>()});
    } else {
      forEachLeafVoxel(false, [&](VoxelKey key, float) {
        occupied.push_back({key, voxelCentre(key, res).cast<float>()});
      });
    }
    std::sort(occupied.begin(), occupied.end(), byKey);
    cache_valid = true;
  }

  // The evidence back from the tree into `voxels` (a read or frozen map given a keyframe).
  void thaw() {
    if (live) return;
    forEachLeafVoxel(true, [&](VoxelKey key, float v) { voxels.emplace(key, Evidence{v, 0, 0}); });
    tree.clear();
    live = true;
  }

  // The tree of the evidence in `voxels` (unpruned, so its shape depends only on the voxels).
  void buildTree() {
    tree.clear();
    std::vector<std::pair<VoxelKey, float>> sorted;  // neighbours one after another: 2.5x faster
    sorted.reserve(voxels.size());
    for (const auto& [key, e] : voxels) sorted.emplace_back(key, logOdds(e));
    std::sort(sorted.begin(), sorted.end());
    for (const auto& [key, v] : sorted) tree.setNodeValue(unpack(key), v, true);
  }

  // The evidence into the tree; `voxels` and the keyframes' records dropped.
  void freeze() {
    if (!live) return;
    buildTree();
    std::unordered_map<VoxelKey, Evidence>().swap(voxels);
    std::map<int32_t, KeyframeRecord>().swap(keyframes);
    live = false;
  }

  // The occupied list after an update in which the voxels `now_occupied` are occupied and
  // `now_not` are not (each voxel in one of them at most): one merge, not a pass over the map.
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

  // The voxels a batch of points updates: occupied where a point falls, free where a ray crosses
  // (and no point falls), each sorted.
  void updatesOf(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f* origin,
                 std::vector<VoxelKey>* occ, std::vector<VoxelKey>* free,
                 InsertStats* stats) const {
    for (const Eigen::Vector3f& p : points) {
      octomap::OcTreeKey key;
      if (!p.allFinite() ||
          (origin && options.max_range > 0 && (p - *origin).norm() > options.max_range) ||
          !tree.coordToKeyChecked(octomap::point3d(p.x(), p.y(), p.z()), key)) {
        ++stats->dropped;
        continue;
      }
      occ->push_back(pack(key));
      ++stats->points;
    }
    std::sort(occ->begin(), occ->end());
    occ->erase(std::unique(occ->begin(), occ->end()), occ->end());
    if (!origin || !origin->allFinite()) return;
    // One ray per occupied voxel, to its centre (OctoMap's "discretize"): points sharing a voxel
    // would cast nearly the same ray.
    octomap::KeyRay ray;
    for (VoxelKey k : *occ) {
      const octomap::point3d end = tree.keyToCoord(unpack(k));
      const Eigen::Vector3f p(end.x(), end.y(), end.z());
      Eigen::Vector3f from = *origin;
      const float length = (p - from).norm();
      if (options.free_band > 0 && length > options.free_band)
        from = p - (p - from) * static_cast<float>(options.free_band / length);
      // Keys from the start voxel up to, not including, the point's voxel.
      if (!tree.computeRayKeys(octomap::point3d(from.x(), from.y(), from.z()), end, ray)) continue;
      for (const auto& rk : ray) free->push_back(pack(rk));
    }
    std::sort(free->begin(), free->end());
    free->erase(std::unique(free->begin(), free->end()), free->end());
    *free = minus(*free, *occ);
  }

  // Adds `d` hits (or misses) to each voxel of `keys`.
  void count(const std::vector<VoxelKey>& keys, int d, bool hits, std::vector<VoxelKey>* changed) {
    for (VoxelKey k : keys) {
      Evidence& e = voxels[k];
      int16_t& c = hits ? e.hits : e.misses;
      c = static_cast<int16_t>(std::clamp(c + d, -kMaxCount, kMaxCount));
      changed->push_back(k);
    }
  }

  // Voxels left without evidence are dropped; the occupied list follows `changed`.
  void settle(std::vector<VoxelKey> changed) {
    std::sort(changed.begin(), changed.end());
    changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
    std::vector<VoxelKey> now_occupied, now_not;
    for (VoxelKey k : changed) {
      auto it = voxels.find(k);
      if (it != voxels.end() && it->second.base == 0 && it->second.hits == 0 &&
          it->second.misses == 0)
        voxels.erase(it), it = voxels.end();
      (it != voxels.end() && logOdds(it->second) >= 0 ? now_occupied : now_not).push_back(k);
    }
    if (cache_valid) applyChanges(std::move(now_occupied), std::move(now_not));
  }
};

OccupancyMap::OccupancyMap(const OccupancyOptions& options, double resolution)
    : impl_(std::make_unique<Impl>(options, resolution)) {}
OccupancyMap::OccupancyMap(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
OccupancyMap::~OccupancyMap() = default;
OccupancyMap::OccupancyMap(OccupancyMap&&) noexcept = default;
OccupancyMap& OccupancyMap::operator=(OccupancyMap&&) noexcept = default;

double OccupancyMap::resolution() const { return impl_->tree.getResolution(); }

InsertStats OccupancyMap::setKeyframe(int32_t kf, const std::vector<Eigen::Vector3f>& points,
                                      const Eigen::Vector3f* origin) {
  impl_->thaw();
  InsertStats stats;
  KeyframeRecord& r = impl_->keyframes[kf];
  if (sameOrigin(r, origin) && sameBits(r.points, points) && !points.empty()) {
    stats.unchanged = points.size();
    return stats;
  }
  std::vector<VoxelKey> occ, free, changed;
  impl_->updatesOf(points, origin, &occ, &free, &stats);
  // Only the difference: a voxel the keyframe updates the same way before and after is untouched.
  const std::vector<VoxelKey> hits_gone = minus(r.occupied, occ), hits_new = minus(occ, r.occupied);
  const std::vector<VoxelKey> misses_gone = minus(r.free, free), misses_new = minus(free, r.free);
  impl_->count(hits_gone, -1, true, &changed);
  impl_->count(hits_new, +1, true, &changed);
  impl_->count(misses_gone, -1, false, &changed);
  impl_->count(misses_new, +1, false, &changed);
  stats.occupied_updates = hits_gone.size() + hits_new.size();
  stats.free_updates = misses_gone.size() + misses_new.size();
  impl_->settle(std::move(changed));
  if (occ.empty() && free.empty()) {
    impl_->keyframes.erase(kf);
    return stats;
  }
  r.points = points;
  r.has_origin = origin != nullptr;
  r.origin = origin ? *origin : Eigen::Vector3f::Zero();
  r.one_origin = true;
  r.occupied = std::move(occ);
  r.free = std::move(free);
  return stats;
}

InsertStats OccupancyMap::addToKeyframe(int32_t kf, const std::vector<Eigen::Vector3f>& points,
                                        const Eigen::Vector3f* origin) {
  auto it = impl_->keyframes.find(kf);
  if (it == impl_->keyframes.end()) return setKeyframe(kf, points, origin);
  KeyframeRecord& r = it->second;
  InsertStats stats;
  std::vector<VoxelKey> occ, free, changed;
  impl_->updatesOf(points, origin, &occ, &free, &stats);
  // New occupied voxels; those the keyframe saw free turn occupied. New free voxels only where
  // the keyframe updated nothing yet.
  const std::vector<VoxelKey> hits_new = minus(occ, r.occupied);
  const std::vector<VoxelKey> freed_before = common(hits_new, r.free);
  const std::vector<VoxelKey> misses_new = minus(minus(free, r.occupied), r.free);
  impl_->count(hits_new, +1, true, &changed);
  impl_->count(freed_before, -1, false, &changed);
  impl_->count(misses_new, +1, false, &changed);
  stats.occupied_updates = hits_new.size();
  stats.free_updates = freed_before.size() + misses_new.size();
  impl_->settle(std::move(changed));
  r.points.insert(r.points.end(), points.begin(), points.end());
  r.one_origin = r.one_origin && sameOrigin(r, origin);
  r.occupied = merged(r.occupied, hits_new);
  r.free = merged(minus(r.free, freed_before), misses_new);
  return stats;
}

void OccupancyMap::removeKeyframe(int32_t kf) {
  auto it = impl_->keyframes.find(kf);
  if (it == impl_->keyframes.end()) return;
  std::vector<VoxelKey> changed;
  impl_->count(it->second.occupied, -1, true, &changed);
  impl_->count(it->second.free, -1, false, &changed);
  impl_->keyframes.erase(it);
  impl_->settle(std::move(changed));
}

std::vector<int32_t> OccupancyMap::keyframes() const {
  std::vector<int32_t> ids;
  for (const auto& [id, r] : impl_->keyframes) ids.push_back(id);
  return ids;
}

void OccupancyMap::freeze() { impl_->freeze(); }

OccupancyMap::Cell OccupancyMap::cell(const Eigen::Vector3d& p) const {
  VoxelKey key;
  if (!voxelKeyOf(p, resolution(), &key)) return Cell::kUnknown;
  return cell(key);
}

OccupancyMap::Cell OccupancyMap::cell(VoxelKey key) const {
  if (!impl_->live) {
    const octomap::ColorOcTreeNode* n = impl_->tree.search(unpack(key));
    if (!n) return Cell::kUnknown;
    return impl_->tree.isNodeOccupied(n) ? Cell::kOccupied : Cell::kFree;
  }
  const Evidence* e = impl_->find(key);
  if (!e) return Cell::kUnknown;
  return impl_->logOdds(*e) >= 0 ? Cell::kOccupied : Cell::kFree;
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

size_t OccupancyMap::numVoxels() const {
  return impl_->live ? impl_->voxels.size() : impl_->tree.getNumLeafNodes();
}

std::string OccupancyMap::serialize(const std::function<Rgb(VoxelKey)>& colour) {
  if (impl_->live) impl_->buildTree();
  octomap::ColorOcTree& tree = impl_->tree;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    // A pruned node (a file's) takes the colour of the voxel at its key; free voxels are white
    // (OctoMap's default), whatever they were while occupied.
    const Rgb c = tree.isNodeOccupied(*it) ? colour(pack(it.getKey())) : Rgb{255, 255, 255};
    it->setColor(c.r, c.g, c.b);
  }
  // ColorOcTree: inner nodes take the mean colour of their children. Its updateInnerOccupancy()
  // (OctoMap 1.9) does not check for an empty tree: a segment whose SLAM map sent no points yet.
  if (tree.getRoot()) tree.updateInnerOccupancy();
  std::ostringstream out;
  const bool written = tree.write(out);
  if (impl_->live) tree.clear();
  if (!written) throw std::runtime_error("OctoMap could not serialise the tree");
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
  impl->live = false;  // the evidence stays in the tree until a keyframe is given
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
