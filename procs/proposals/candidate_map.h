#pragma once
// Object candidates from the semi-dense map (DESIGN.md §3): the map of one SLAM map id is kept
// per keyframe (incremental updates replace a keyframe's points, a full cloud replaces all);
// recluster() filters it (outliers, the dominant support plane) and over-segments it by
// density-based clustering on position and colour at several radii, a factor 2 apart. A cluster
// that survives a map update keeps its id (association by shared voxels). PCL stays inside the
// .cpp file.
#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <vector>

#include "procs/proposals/proposal_options.h"

namespace slamaware {

struct MapPoint {
  Eigen::Vector3f p;
  uint8_t r = 0, g = 0, b = 0;
};

struct Candidate {
  int32_t id = -1;
  int scale = 0;                       ///< 0 = finest radius
  int stability = 1;                   ///< scales at which the same cluster was found
  std::vector<Eigen::Vector3f> points; ///< world frame, map units
  Eigen::Vector3f min, max;            ///< axis-aligned bounds
  Eigen::Vector3f centroid;
};

struct ClusterStats {
  int64_t input_points = 0, clustered_points = 0, outliers = 0, plane_points = 0, cropped = 0;
  int planes = 0;
  bool support = false;  ///< a support plane was found and the map restricted to what stands on it
  int clusters = 0;
  double voxel = 0;   ///< voxel used for downsampling
  double scene_scale = 1;  ///< map units per length unit of the options (median viewing distance)
  double ms = 0;      ///< time of the last recluster()
};

class CandidateMap {
 public:
  explicit CandidateMap(const ProposalOptions& options) : options_(options) {}

  /// Replaces the points of `keyframe_id` (incremental update) or, with full = true, the whole
  /// map. A new map id drops the old map and its candidates. Non-finite points are ignored.
  void update(int32_t map_id, bool full, int32_t keyframe_id, const std::vector<int32_t>& keyframe_ids,
              const std::vector<MapPoint>& points);
  /// Re-runs filtering and clustering when the map changed since the last call; true if it ran.
  /// `viewpoint` (a camera centre) tells the side of the support plane that objects stand on.
  bool recluster(const Eigen::Vector3f& viewpoint = Eigen::Vector3f::Zero());

  int32_t mapId() const { return map_id_; }
  const std::vector<Candidate>& candidates() const { return candidates_; }
  const ClusterStats& stats() const { return stats_; }
  size_t points() const;

 private:
  ProposalOptions options_;
  int32_t map_id_ = -1;
  std::map<int32_t, std::vector<MapPoint>> by_keyframe_;
  bool dirty_ = false;
  std::vector<Candidate> candidates_;
  int32_t next_id_ = 1;
  ClusterStats stats_;
};

/// The options with every length multiplied by `scale`.
ProposalOptions scaledLengths(const ProposalOptions& options, double scale);

/// Clusters `points` (already filtered) at every scale of `options`; ids are not assigned.
/// Exposed for tests and the benchmark.
std::vector<Candidate> clusterPoints(const std::vector<MapPoint>& points, const ProposalOptions& options);

}  // namespace slamaware
