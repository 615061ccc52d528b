#pragma once
// Density-based clustering (DBSCAN, Ester et al. 1996) of 3D points on a uniform hash grid.
// Written here rather than taken from PCL: PCL's (conditional) Euclidean clustering is single
// linkage — one stray depth between two objects joins them — and its k-d tree radius searches
// cost ~650 ms for a 100k-point map at 4 scales, over the per-keyframe budget.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace slamaware::proposals {

struct DensityClusterOptions {
  float radius = 0.01f;  ///< neighbourhood radius
  int min_neighbours =
      4;  ///< points within radius (the point itself included) that make a core point
  /// RGB distance (0..441) under which two core points may join; <= 0: position only.
  float colour_distance = 0;
};

/// Clusters `points`: core points within `radius` of each other (and of similar colour, when
/// enabled) are one cluster; a non-core point joins the cluster of the nearest core point within
/// `radius`, else it is noise (-1). `colours` (RGB per point) may be empty when colour is off.
/// Cluster indices are 0..count-1 in the order of their lowest point index (deterministic).
std::vector<int> densityClusters(const std::vector<Eigen::Vector3f>& points,
                                 const std::vector<Eigen::Vector3f>& colours,
                                 const DensityClusterOptions& options, int* count);

}  // namespace slamaware::proposals
