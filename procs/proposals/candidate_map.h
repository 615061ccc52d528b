#pragma once
// Object candidates from the semi-dense map (docs/architecture.md §3): the map of one SLAM map id
// is kept per keyframe (incremental updates replace a keyframe's points, a full cloud replaces
// all), with the views (camera poses) of that map; recluster() removes the map's structure (large
// planes, and everything not standing on the support the views look at) and over-segments the rest
// by density-based clustering at several radii, a factor 2 apart. A cluster that survives a map
// update keeps its id (association by shared voxels).
#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <optional>
#include <vector>

#include "common/geometry.h"
#include "procs/proposals/proposal_options.h"
#include "procs/proposals/scene_structure.h"

namespace slamaware::proposals {

struct Candidate {
  int32_t id = -1;
  int scale = 0;           ///< 0 = finest radius
  int stability = 1;       ///< scales at which the same cluster was found
  bool by_colour = false;  ///< found only by the clustering on position and colour
  int parts = 1;  ///< clusters of the next finer scale holding split_share of its points each (1 at
                  ///< the finest)
  std::vector<Eigen::Vector3f> points;  ///< world frame, map units
  Eigen::Vector3f min, max;             ///< axis-aligned bounds
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
  bool on_support = false;  ///< stands on the map's support (its box is trimmed by box_trim_pct)
  int64_t lost_since =
      -1;  ///< frame time of the clustering that lost it (-1: found by the last one)
};

struct ClusterStats {
  int64_t input_points = 0, clustered_points = 0, plane_points = 0, cropped = 0;
  int64_t single_view = 0;   ///< points dropped because too few keyframes agree on them
  int64_t seen_through = 0;  ///< points dropped by free-space carving
  int64_t band_points = 0;   ///< points of the support's band (removed with it)
  int64_t band_taken = 0;    ///< of them, taken back by candidates (summed over candidates)
  int planes = 0;
  bool support = false;  ///< a support plane was found and the map restricted to what stands on it
  bool young = false;  ///< the map had fewer than young_map_points points: young_min_points applied
  int clusters = 0;
  int retired = 0;             ///< dropped candidates remembered so that their ids can come back
  int64_t retired_points = 0;  ///< their points (one per key voxel)
  int views = 0;               ///< camera poses the priors came from
  bool look_at = false;        ///< the views' optical axes meet
  double voxel = 0;            ///< voxel used for downsampling
  double scene_scale = 1;  ///< map units per length unit of the options (median viewing distance)
  double ms = 0;           ///< time of the last recluster()
  double filter_ms = 0, structure_ms = 0,
         cluster_ms = 0;  ///< its parts: agreement + crop + grid, planes, clustering
};

/// What clustering a map needs of it (a copy: a worker thread can cluster it while the map goes on
/// growing and its last candidates are projected).
struct ClusterInput {
  int32_t map_id = -1;
  ProposalOptions options;
  std::map<int32_t, std::vector<MapPoint>> by_keyframe;
  std::map<int32_t, Eigen::Vector3f> keyframe_centres;
  std::vector<View> views;
};

/// The same, without copying (CandidateMap::recluster() clusters its own map in place).
struct ClusterInputRef {
  int32_t map_id;
  const ProposalOptions& options;
  const std::map<int32_t, std::vector<MapPoint>>& by_keyframe;
  const std::map<int32_t, Eigen::Vector3f>& keyframe_centres;
  const std::vector<View>& views;
};

/// What clustering found; CandidateMap::adopt() gives the clusters their ids.
struct Clustering {
  int32_t map_id = -1;
  std::vector<Candidate> found;  ///< ids not assigned
  Support support;
  ClusterStats stats;
  double key_voxel = 0;  ///< voxel for associating the clusters with the previous candidates
};

/// Filters and clusters a map (the heavy part of CandidateMap::recluster(); no state, so it may
/// run on any thread).
Clustering clusterMap(const ClusterInputRef& input);
Clustering clusterMap(const ClusterInput& input);

class CandidateMap {
 public:
  /// `ids`: where new candidate ids come from (shared by several maps so that ids are unique
  /// across them); nullptr: a counter of this map's own.
  explicit CandidateMap(const ProposalOptions& options, int32_t* ids = nullptr)
      : options_(options), ids_(ids ? ids : &own_ids_) {}
  CandidateMap(CandidateMap&& other) noexcept;

  /// Replaces the points of `keyframe_id` (incremental update) or, with full = true, the whole
  /// map. A new map id drops the old map, its views and its candidates. Non-finite points are
  /// ignored.
  void update(int32_t map_id, bool full, int32_t keyframe_id,
              const std::vector<int32_t>& keyframe_ids, const std::vector<MapPoint>& points);
  /// The camera centre of a keyframe (lengths are relative to the distance points were seen from).
  void setKeyframeCentre(int32_t map_id, int32_t keyframe_id, const Eigen::Vector3f& centre);
  /// A camera pose localised in map `map_id` (the up direction and what the camera looks at come
  /// from these). Poses of another map than the current one are ignored.
  void addView(int32_t map_id, const SE3& T_world_camera);
  /// Re-runs filtering and clustering when the map changed since the last call; true if it ran.
  /// The same as adopt(clusterMap(*takeClusterInput())), without the copy.
  bool recluster(int64_t utime = 0);
  /// A copy of what clustering needs when the map changed since the last call (it then counts as
  /// clustered), else nothing.
  std::optional<ClusterInput> takeClusterInput();
  /// Takes a clustering of this map as the candidates: each cluster keeps the id of the candidate
  /// it shares most voxels with; a cluster that takes no current id takes back the id of a
  /// candidate of its scale that an earlier clustering dropped, if it shares as many voxels with
  /// it (an object whose cluster comes and goes as the map grows keeps one id). False (nothing
  /// changes) when it is of another map id. `utime`: the frame time (for keep_lost_s).
  bool adopt(Clustering&& clustering, int64_t utime = 0);

  int32_t mapId() const { return map_id_; }
  const std::vector<Candidate>& candidates() const { return candidates_; }
  const ClusterStats& stats() const { return stats_; }
  /// The support of the last recluster (valid when stats().support).
  const Support& support() const { return support_; }
  size_t points() const;

 private:
  void resetMap(int32_t map_id);

  ProposalOptions options_;
  int32_t map_id_ = -1;
  std::map<int32_t, std::vector<MapPoint>> by_keyframe_;
  std::map<int32_t, Eigen::Vector3f> keyframe_centres_;
  std::vector<View> views_;
  int view_stride_ = 1;  ///< every view_stride_-th pose is kept (bounded memory)
  int64_t views_seen_ = 0;
  bool dirty_ = false;
  std::vector<Candidate> candidates_;
  /// A dropped candidate, kept so that its cluster can take its id back: one point per key voxel.
  /// Points, not keys: the key voxel (2 x radius) follows each clustering's scene scale and the
  /// young-map radius, so the keys are made again at the scale of the clustering that matches.
  struct Retired {
    int32_t id;
    int scale;  ///< a cluster takes it back only at the same scale
    std::vector<Eigen::Vector3f> points;
    Eigen::Vector3f min, max;
  };
  /// Dropped candidates remembered (a bound on memory: each is at most a few hundred points).
  static constexpr size_t kMaxRetired = 1024;
  std::vector<Retired> retired_;  ///< oldest first
  Support support_;
  int32_t own_ids_ = 1;
  int32_t* ids_;  ///< the next new candidate id
  ClusterStats stats_;
};

/// Points that several keyframes agree on: a surface is seen, and seeded, from many keyframes,
/// while a wrong depth (a seed that converged on the wrong match, a smear at an occluding edge) is
/// one keyframe's mistake. Keeps the points whose voxel and its 26 neighbours hold points of at
/// least `min_keyframes` different keyframes (counted in a 128-bit mask of keyframe id hashes:
/// exact for the small counts the threshold looks at), in their input order. One sort and one
/// sweep over the occupied voxels. Exposed for tests.
std::vector<MapPoint> keepMultiView(const std::map<int32_t, std::vector<MapPoint>>& by_keyframe,
                                    double voxel, int min_keyframes);

/// The options with every length multiplied by `scale`.
ProposalOptions scaledLengths(const ProposalOptions& options, double scale);

/// Clusters `points` (already filtered) at every scale of `options`; ids are not assigned.
/// Exposed for tests and the benchmark.
std::vector<Candidate> clusterPoints(const std::vector<MapPoint>& points,
                                     const ProposalOptions& options);

}  // namespace slamaware::proposals
