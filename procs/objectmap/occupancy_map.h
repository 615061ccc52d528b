#pragma once
// The occupancy of one map segment: an OctoMap ColorOcTree (Hornung et al. 2013) filled from the
// semi-dense SLAM points with ray casting from their keyframes' centres. OctoMap stays inside
// occupancy_map.cpp; the rest of the object map sees voxels as VoxelKeys.
//
// Each insert() is one batch (the points of one keyframe): every voxel is updated at most once
// per batch, occupied if a point falls in it, else free if a ray crosses it (OctoMap's
// insertPointCloud rule: occupied wins), with one ray per occupied voxel (OctoMap's "discretize").
// Rays are cast only over their last `free_band` map units in front of the point: that is where
// free space matters for objects (it erases depth outliers in front of surfaces), and whole rays
// from the keyframe cost 10x more at a 1-unit scene depth and 0.01 resolution (measured on a
// 250k-point map of 40 keyframes: 13.4 s and a 22 MB .ot with whole rays, 1.3 s and 4 MB with a
// 0.1 band).
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
  size_t points = 0;   ///< points inserted
  size_t dropped = 0;  ///< not finite, outside the grid, or beyond max_range
  size_t occupied_updates = 0;
  size_t free_updates = 0;
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

  /// Inserts one batch of points seen from `origin` (the keyframe's camera centre; nullptr when
  /// unknown: the points are marked occupied, no ray is cast). Points farther than max_range from
  /// the origin are dropped.
  InsertStats insert(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f* origin);
  /// Forgets everything (a full SLAM map replaces the segment's points).
  void clear();

  Cell cell(const Eigen::Vector3d& p) const;
  Cell cell(VoxelKey key) const;
  /// Every occupied voxel at the finest level, sorted by key (cached until the next change).
  const std::vector<OccupiedVoxel>& occupied() const;
  bool isOccupied(VoxelKey key) const;
  size_t numLeaves() const;

  /// The map as an OctoMap .ot file (what octovis opens), every occupied voxel coloured by
  /// colour(key). Sets the colours in the tree (they are not part of the occupancy).
  std::string serialize(const std::function<Rgb(VoxelKey)>& colour);
  /// Reads .ot bytes written by serialize(); throws std::runtime_error prefixed with `what` when
  /// they are not a ColorOcTree. The sensor model comes from `options`, the resolution from the
  /// file.
  static OccupancyMap deserialize(const std::string& bytes, const OccupancyOptions& options,
                                  const std::string& what);
  /// The colour a voxel has in the tree (tests: what octovis would show); false if not in the tree.
  bool colourOf(VoxelKey key, Rgb* colour) const;

 private:
  struct Impl;
  explicit OccupancyMap(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace slamaware::objectmap
