#pragma once
// Options of the object map (config/objectmap.yaml, section "objectmap"). Lengths are in SLAM map
// units: a monocular map has no metric scale, its unit is about the median scene depth of the
// first keyframe (for a camera about 1 m from a table, 0.01 is about 1 cm).
#include <string>

#include "procs/objectmap/fusion.h"

namespace slamaware::objectmap {

/// The OctoMap occupancy of one map segment.
struct OccupancyOptions {
  double resolution = 0.01;  ///< map units, voxel edge (new segments; a loaded one keeps its own)
  double prob_hit = 0.7;     ///< OctoMap sensor model: a point in a voxel
  double prob_miss = 0.4;    ///< ... a ray through a voxel
  double clamp_min = 0.12;   ///< OctoMap clamping of the occupancy probability
  double clamp_max = 0.97;
  /// Map units: free space is carved only over this last stretch of each ray, in front of its
  /// point (<= 0: the whole ray from the keyframe; see occupancy_map.h for the cost).
  double free_band = 0.1;
  /// Map units, points farther from their keyframe are dropped (<= 0: all kept).
  double max_range = 5.0;
  /// Map units, points with a less certain depth are dropped (<= 0: all kept).
  double max_depth_std = 0;
  int max_points = 300000;  ///< a full map with more points is evenly subsampled to this many

  template <class V>
  void visit(V& v) {
    v("resolution", resolution, "map units, voxel edge of new segments");
    v("prob_hit", prob_hit, "occupancy update of a voxel holding a point");
    v("prob_miss", prob_miss, "occupancy update of a voxel a ray crosses");
    v("clamp_min", clamp_min, "lower clamping of the occupancy probability");
    v("clamp_max", clamp_max, "upper clamping of the occupancy probability");
    v("free_band", free_band,
      "map units, free space carved in front of each point (<= 0: whole ray)");
    v("max_range", max_range,
      "map units, points farther from their keyframe are dropped (<= 0: all)");
    v("max_depth_std", max_depth_std,
      "map units, points with a less certain depth are dropped (<= 0: all)");
    v("max_points", max_points, "a full map with more points is evenly subsampled");
  }
};

/// Which occupied voxels belong to a candidate: those that fall in its boxes, view after view.
struct VotingOptions {
  /// A voxel votes for a box if its depth is within depth_band x the box's median depth of it, or
  /// within depth_band_box x the box's larger side at that depth (map units; an object is about
  /// as deep as it is wide), whichever is larger.
  double depth_band = 0.05;
  double depth_band_box = 0.5;
  int min_votes = 3;            ///< a candidate's voxel was voted in at least this many views ...
  double min_vote_share = 0.5;  ///< ... and in at least this share of the views that voted
  double forget_share = 0.1;    ///< voxels voted in less than this share of the views are forgotten
  int grid_cell_px = 16;        ///< px, cell of the image grid that buckets projected voxels

  template <class V>
  void visit(V& v) {
    v("depth_band", depth_band, "relative depth band around a box's median depth");
    v("depth_band_box", depth_band_box,
      "depth band in box sizes at that depth (the larger band wins)");
    v("min_votes", min_votes, "views a voxel must be voted in to belong to a candidate");
    v("min_vote_share", min_vote_share, "share of a candidate's views a voxel must be voted in");
    v("forget_share", forget_share,
      "voxels voted in less than this share of the views are forgotten");
    v("grid_cell_px", grid_cell_px, "px, image grid cell for bucketing projected voxels");
  }
};

/// Which candidates are one object. The proposals stage over-segments at several scales and gives
/// a cluster a new id when it changes, so one object is often several candidates with nearly the
/// same voxels; but a coarse candidate also contains the fine ones of the objects on it, and a
/// candidate seen in few views holds much of the background of its boxes. Two groups of
/// candidates merge when their voxels overlap by merge_overlap of the smaller group AND the smaller
/// is at least merge_size_ratio of the larger (a part is not merged into a whole it lies in by
/// geometry alone). Then groups that are called the same object class (not background) merge when
/// they share same_label_overlap of the smaller's voxels: a mug's handle and the mug it belongs to
/// are one mug (without its label, the handle could as well be part of the table).
/// procs/objectmap/README.md has the measurements.
struct GroupingOptions {
  double merge_overlap = 0.8;     ///< share of the smaller group's voxels the two share
  double merge_size_ratio = 0.8;  ///< smaller group / larger group, in voxels
  double same_label_overlap =
      0.5;  ///< same class: share of the smaller's voxels (<= 0: no such merge)

  template <class V>
  void visit(V& v) {
    v("merge_overlap", merge_overlap, "share of the smaller group's voxels both must share");
    v("merge_size_ratio", merge_size_ratio,
      "the smaller group has at least this share of the larger's voxels");
    v("same_label_overlap", same_label_overlap,
      "groups of the same object class merge when they share this share of the smaller's voxels "
      "(<= 0: never)");
  }
};

/// Where and how often the map is saved (docs/architecture.md §6).
struct PersistenceOptions {
  /// Folder of the map files (relative to the working directory); --map-dir overrides it.
  std::string dir = "build/objectmap";
  double save_period_s = 10.0;  ///< s of wall time between saves (<= 0: only at shutdown)
  /// auto: load in real time, not in lockstep (a log must give the same bytes whatever the folder
  /// holds); always; never (--fresh: never).
  std::string load_at_start = "auto";

  template <class V>
  void visit(V& v) {
    v("dir", dir, "folder of the map files (relative to the working directory)");
    v("save_period_s", save_period_s, "s between saves (<= 0: only at shutdown)");
    v("load_at_start", load_at_start, "auto (real time yes, lockstep no), always or never");
  }
};

struct ObjectMapOptions {
  OccupancyOptions occupancy;
  VotingOptions voting;
  GroupingOptions grouping;
  double publish_period_s = 1.0;  ///< s, OBJECT_MAP also goes out this often (real time)
  /// Real time: s between regroupings of the objects (each costs more as the session grows);
  /// lockstep and <= 0: after every DETECTIONS.
  double regroup_period_s = 0.5;
  /// Each view's log p weighted by 1 - p(background | view) in the sum (procs/objectmap/fusion.h).
  bool objectness_weights = true;
  /// The posterior is the softmax of the summed evidence / W^e, W the views' total weight
  /// (procs/objectmap/fusion.h: 0 = views independent, 1 = the average view). Labels do not change.
  double posterior_views_exponent = 1;
  FusionOptions fusion() const { return {objectness_weights, posterior_views_exponent}; }
  /// s: every view of the last views_full_rate_s is kept; older ones are merged as they age into
  /// time bins, the same for every candidate, each merged view standing for its frames
  /// (ObjectTable::mergeOldViews: 16 views per doubling of age, so memory and fusion cost stay
  /// about flat over a session); what the map calls background is forgotten once out of view for as
  /// long (<= 0: every view is kept, nothing forgotten).
  double views_full_rate_s = 30;
  /// SLAM_POSE and PROPOSALS messages kept for joining with DETECTIONS.
  int seq_buffer = 64;
  PersistenceOptions persistence;

  template <class V>
  void visit(V& v) {
    v.note(
        "Lengths are in SLAM map units: the map's unit is about the median scene depth of the "
        "first "
        "keyframe, so for a camera about 1 m from a table, 0.01 is about 1 cm.");
    v.section("occupancy", occupancy);
    v.section("voting", voting);
    v.section("grouping", grouping, "when two groups of candidates are one object");
    v("publish_period_s", publish_period_s, "s between periodic OBJECT_MAP messages (real time)");
    v("regroup_period_s", regroup_period_s,
      "real time: s between regroupings of the objects (lockstep and <= 0: after every "
      "DETECTIONS)");
    v("objectness_weights", objectness_weights,
      "each view's log p weighted by 1 - p(background | view) in the fused sum (false: the paper's "
      "plain sum)");
    v("posterior_views_exponent", posterior_views_exponent,
      "posterior = softmax(fused sum / W^e), W the views' total weight (0: views independent, 1: "
      "the average view)");
    v("views_full_rate_s", views_full_rate_s,
      "s of the newest views all kept; older ones are merged into time bins (16 per doubling of "
      "age) standing for their frames, and background out of view as long is forgotten (<= 0: "
      "every view kept)");
    v("seq_buffer", seq_buffer,
      "SLAM_POSE and PROPOSALS messages kept for joining with DETECTIONS");
    v.section("persistence", persistence);
  }
};

}  // namespace slamaware::objectmap
