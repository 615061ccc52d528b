#pragma once
// The occupancy of one map segment, filled from the semi-dense SLAM points with ray casting from
// their keyframes' centres and written as an OctoMap ColorOcTree (Hornung et al. 2013), what
// octovis opens. OctoMap stays inside occupancy_map.cpp; the rest of the object map sees voxels as
// VoxelKeys.
//
// Evidence is kept per keyframe: a keyframe updates each voxel at most once, occupied if one of its
// points falls in it, else free if one of its rays crosses it (OctoMap's insertPointCloud rule:
// occupied wins), with one ray per occupied voxel (OctoMap's "discretize"). A voxel counts the
// keyframes that saw it occupied (hits) and free (misses); its log-odds is
// clamp(hits·logit(prob_hit) + misses·logit(prob_miss)) to [logit(clamp_min), logit(clamp_max)],
// occupied at >= 0. The sum does not depend on the order the keyframes came in, so a keyframe whose
// points moved (SLAM's bundle adjustment) or that left SLAM's map is replaced exactly: its old
// updates are taken back and its new ones applied, and the map is what a build from scratch of
// every keyframe's current points gives. A full SLAM map then costs only the keyframes that
// changed, not a rebuild (docs/experiments/objectmap.md, 2026-12-04). (OctoMap's own updateNode
// clamps after every update, so its result depends on the order and cannot be undone.)
//
// Rays are cast only over their last `free_band` map units in front of the point: that is where
// free space matters for objects (it erases depth outliers in front of surfaces), and whole rays
// from the keyframe cost 10x more at a 1-unit scene depth and 0.01 resolution (measured on a
// 250k-point map of 40 keyframes: 13.4 s and a 22 MB .ot with whole rays, 1.3 s and 4 MB with a
// 0.1 band).
//
// The voxels' evidence lives in a hash table; the OctoMap tree is built when the map is written
// (serialize()). A map read from a file, or frozen, keeps its evidence in the tree instead.
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "procs/objectmap/objectmap_options.h"
#include "procs/objectmap/voxel_key.h"

namespace slamaware::objectmap {

struct Rgb {
  uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb& o) const { return r == o.r && g == o.g && b == o.b; }
};

struct OccupiedVoxel {
  VoxelKey key;
  Eigen::Vector3f centre;  ///< map units
};

/// The most occupied voxels a loaded segment may hold (about 400 MB as the occupied list): 16.7M
/// voxels of 4 cm are some 27,000 m² of surface, far beyond a room; a file asking for more is
/// damaged (OccupancyMap::deserialize refuses it).
constexpr int64_t kMaxOccupiedVoxels = int64_t{1} << 24;

struct InsertStats {
  size_t points = 0;            ///< points inserted
  size_t dropped = 0;           ///< not finite, outside the grid, or beyond max_range
  size_t unchanged = 0;         ///< points of a keyframe given again as they were (nothing to do)
  size_t occupied_updates = 0;  ///< voxels whose hits changed
  size_t free_updates = 0;      ///< voxels whose misses changed
};

class OccupancyMap {
 public:
  enum class Cell { kUnknown, kFree, kOccupied };

  /// An empty map with voxels of `resolution` map units.
  OccupancyMap(const OccupancyOptions& options, double resolution);
  ~OccupancyMap();
  OccupancyMap(OccupancyMap&&) noexcept;
  OccupancyMap& operator=(OccupancyMap&&) noexcept;

  double resolution() const;

  /// Keyframe `kf`'s points seen from `origin` (its camera centre; nullptr when unknown: the
  /// points are marked occupied, no ray is cast) replace what the keyframe contributed before:
  /// its old updates are taken back and the new ones applied. Points and origin equal to those it
  /// has (bit for bit): nothing to do (stats.unchanged). Points farther than max_range from the
  /// origin are dropped.
  InsertStats setKeyframe(int32_t kf, const std::vector<Eigen::Vector3f>& points,
                          const Eigen::Vector3f* origin);
  /// More points of keyframe `kf` (SLAM appends them as their depths converge), seen from
  /// `origin`: voxels the keyframe updated already are not updated again, except that a point in
  /// a voxel it saw free makes it occupied.
  InsertStats addToKeyframe(int32_t kf, const std::vector<Eigen::Vector3f>& points,
                            const Eigen::Vector3f* origin);
  /// Takes back everything keyframe `kf` contributed (it left SLAM's map).
  void removeKeyframe(int32_t kf);
  /// The keyframes with points in the map, ascending.
  std::vector<int32_t> keyframes() const;
  /// Forgets what each keyframe contributed (the voxels stay as they are): for a segment that
  /// takes no more clouds. Keyframes given later start from nothing.
  void freeze();

  Cell cell(const Eigen::Vector3d& p) const;
  Cell cell(VoxelKey key) const;
  /// Every occupied voxel at the finest level, sorted by key (cached until the next change).
  const std::vector<OccupiedVoxel>& occupied() const;
  bool isOccupied(VoxelKey key) const;
  /// Voxels with any evidence (occupied or free).
  size_t numVoxels() const;

  /// The map as an OctoMap .ot file (what octovis opens), every occupied voxel coloured by
  /// colour(key). Sets the colours in the tree (they are not part of the occupancy).
  std::string serialize(const std::function<Rgb(VoxelKey)>& colour);
  /// Reads .ot bytes written by serialize(); throws std::runtime_error prefixed with `what` when
  /// they are not a ColorOcTree. The sensor model comes from `options`, the resolution from the
  /// file; each voxel's log-odds in the file is its evidence before any keyframe's (keyframes
  /// given later add to it).
  static OccupancyMap deserialize(const std::string& bytes, const OccupancyOptions& options,
                                  const std::string& what);
  /// The colour a voxel has in a map read from a file (tests: what octovis shows); false if not in
  /// the file.
  bool colourOf(VoxelKey key, Rgb* colour) const;

 private:
  struct Impl;
  explicit OccupancyMap(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace slamaware::objectmap
