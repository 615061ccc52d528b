#pragma once
// Options of the object proposals (config/proposals.yaml, section "proposals"). A monocular map
// has no metric scale (its unit is the first keyframe's median depth, which may be a wall behind
// the table or the table itself), so with relative_lengths every length below is a fraction of
// the median viewing distance of the map at clustering time: for a camera about a metre from
// the table, 0.1 is about 10 cm.
#include <string>

namespace slamaware::proposals {

/// Free-space carving of the map (free_space.h): points that keyframes saw through are dropped.
struct FreeSpaceOptions {
  double bin_rad = 0.004;  ///< rad, angular bin of a keyframe's rays (about 2 px at f = 525)
  double margin = 0.05;  ///< a point is seen through when nearer than (1 - margin) x the ray's end
  int min_violations = 2;  ///< keyframes that must see through a point to drop it (0: off) ...
  double min_share = 0.3;  ///< ... and this share of the keyframes that have a ray through it

  template <class V>
  void visit(V& v) {
    v.note(
        "A monocular map has no metric scale, so lengths (\"map units\") are fractions of the "
        "median "
        "viewing distance when relative_lengths is true: for a camera about 1 m from the table, "
        "0.1 is "
        "about 10 cm.");
    v("bin_rad", bin_rad, "rad, angular bin of a keyframe's rays");
    v("margin", margin, "a point is seen through when nearer than (1 - margin) x the ray's end");
    v("min_violations", min_violations,
      "keyframes that must see through a point to drop it (0: off)");
    v("min_share", min_share,
      "share of the keyframes with a ray through a point that must see through it");
  }
};

struct ProposalOptions {
  bool relative_lengths =
      true;  ///< lengths in units of the median viewing distance (else map units)
  // Map filtering.
  double multiview_voxel = 0.008;  ///< map units, voxel of the multi-keyframe check
  int min_keyframes = 4;  ///< a point is kept if its voxel and neighbours hold points of this many
                          ///< keyframes (at most half of the map's keyframes)
  double voxel = 0.004;   ///< map units, the map is downsampled to one point per voxel
  int max_points = 120000;  ///< points clustered at most (bounded cost); the voxel grows to fit
  double max_depth_std =
      0.0;  ///< map units, points with a less certain depth are ignored (<= 0: all kept)
  double crop_percentile = 2.0;  ///< %, points outside the [p, 100-p] percentiles per axis ...
  double crop_margin = 0.5;  ///< ... widened by this share of the range are dropped (stray depths)
  double plane_distance = 0.02;  ///< map units, RANSAC inlier distance of a plane
  int plane_iterations = 200;    ///< RANSAC iterations
  int ransac_points = 20000;     ///< RANSAC runs on an even subsample of this many points
  double plane_min_fraction =
      0.05;                      ///< planes are searched while they hold this share of the points
  int max_planes = 5;            ///< planes searched at most (table, floor, walls)
  double structure_cell = 0.03;  ///< map units, grid cell of a plane's connected patches
  int structure_min_points = 1;  ///< points a cell of a plane must hold to be part of a patch (a
                                 ///< plain table of a young map has about one per cell)
  double structure_extent =
      0.6;  ///< map units, a plane patch larger than this is structure (removed)
  double support_max_tilt_deg = 40;  ///< deg, a support's normal is this close to the views' up
  double support_radius =
      0.8;  ///< map units, the support's region: its cells this close to where the views look
  double support_below =
      0.1;  ///< map units, the views' look-at point is at most this far under a support
  double support_fill =
      0.2;  ///< share of plane cells around where a view's axis meets a support that hold points
  double support_distance = 0.012;  ///< map units, points this close to the support are its own
  double support_margin =
      0.03;  ///< map units, objects stand over the support's region grown by this
  double min_height =
      0.015;  ///< map units: clusters lower than this over the support are its texture
  double max_height = 0.5;    ///< map units: points higher than this over the support are not on it
  bool add_footprint = true;  ///< a candidate over the support plane includes its footprint on it
  // What of an object lies in the support's band (a cap's brim, a bowl's foot): band points of a
  // colour far more common on a candidate than in the band, connected to its base, are its own.
  double band_grow =
      0.06;  ///< map units, how far past its bounds a candidate takes band points (<= 0: off)
  double band_colour_ratio = 5;  ///< a band point's colour is the candidate's when its share of the
                                 ///< candidate's points is over this x its share of the band
  int band_colour_bin =
      32;  ///< RGB levels per bin of the candidate's and the band's colour histograms
  bool band_reference_elsewhere =
      true;  ///< the support's colours for a candidate: the band outside its bounds
             ///< grown by band_grow (false: the whole band)
  FreeSpaceOptions free_space;  ///< points seen through by other keyframes are not objects
  int max_maps =
      4;  ///< SLAM maps whose candidates are kept (SLAM may relocalise into an older one)
  int max_views = 512;  ///< camera poses kept for the up / look-at priors (thinned beyond)
  double recluster_interval_s = 0.25;  ///< s of frame time between re-clusterings of a growing map
  double recluster_growth = 1.5;  ///< ...or sooner, once the map holds this many times the points
                                  ///< of its last clustering (a young map grows fast; <= 1: off)
  // Density-based clustering (DBSCAN) at `scales` radii, each twice the previous.
  double radius = 0.008;   ///< map units, neighbourhood radius of the finest scale
  int scales = 5;          ///< density thresholds, a factor 2 apart
  int min_neighbours = 4;  ///< points within the radius (on a grid of half of it) of a core point
  double colour_distance =
      40;  ///< RGB distance (0..441) under which core points join in a second clustering,
           ///< on position and colour at the coarser scales, whose clusters are added
           ///< (<= 0: position only)
  int min_points = 60;  ///< smallest cluster, in map points (on the voxel grid) at every scale
  int young_map_points =
      16000;  ///< a map of fewer points (SLAM's first keyframes: its triangulated features,
              ///< provisional and first converged seeds) is young ... (0: never). All of the
              ///< map's points: SLAM's depth.young_map_points counts converged seeds only
  int young_min_points =
      15;  ///< ... and its smallest cluster is this (its objects hold few points yet)
  double young_radius_scale =
      1.5;  ///< ... and `radius` is this many times larger (its objects are pieces with
            ///< no converged seed between them yet): the clustering radii, and with them
            ///< the band points' connection step and the id voxel; <= 0: as radius
  double max_extent = 0.5;  ///< map units, clusters larger than this along any axis are not objects
  double min_extent = 0.02;  ///< map units, clusters smaller than this along every axis are noise
  double same_cluster_overlap =
      0.9;                    ///< clusters of two scales sharing this share of points are one
  double split_share = 0.35;  ///< a cluster whose points fall into two or more clusters of the next
                              ///< finer scale, each holding this share of them, is two touching
                              ///< objects: its box ranks after those of single objects (> 0.5: off)
  double id_overlap =
      0.3;  ///< a new cluster keeps the id of an old one sharing this share of voxels
  // Projection into each frame.
  int max_points_per_candidate = 400;  ///< points projected per candidate (evenly subsampled)
  int depth_buffer_cell_px = 8;        ///< px, cell of the candidates' depth buffer
  double occlusion_margin = 0.15;  ///< relative depth: nearer than (1 - margin) x depth occludes
  double occluded_fraction = 0.6;  ///< candidates with more of their points hidden are culled
  double min_visible_fraction =
      0.5;                  ///< of a candidate's points in front of the camera and in the image
  double box_trim_pct = 3;  ///< %, a box spans its projected points without this share on each side
  /// %, the same for a candidate that does not stand on a support (no table found under it: an
  /// object on an untextured ground, whose outermost points are its own).
  double box_trim_pct_unsupported = 0;
  /// ...and then grows over the trimmed points while each is within this many times the mean
  /// spacing of the points inside of the last (<= 0: off): an object's own points run on densely
  /// to its outline, a smear thins out.
  double box_trim_gap = 0;
  int min_box_px = 20;  ///< boxes smaller than this along either side are dropped
  /// Boxes overlapping a kept box (ranked ahead) by more than this IoU are suppressed here; >= 1:
  /// none, the default: the recognizer suppresses at IoU 0.5 by the classifier's confidence
  /// (config/recognizer.yaml nms_iou), which keeps whole objects whose parts this ranking put
  /// first.
  double nms_iou = 1.0;
  int max_boxes = 100;  ///< boxes per frame at most
  /// A candidate that a re-clustering does not find again, and whose voxels the new clusters do
  /// not hold (at least `lost_held` of them), is kept for this many seconds of frame time (0:
  /// dropped at once). Ranked after every candidate found.
  double keep_lost_s = 0;
  double lost_held =
      0.8;  ///< share of a lost candidate's voxels that new clusters hold when it is represented
  /// A keyframe whose frame was not located when its pose came (the reference frame a map is
  /// initialised from) gets its PROPOSALS once the map is this many seconds of frame time older
  /// than it: the objects seen before SLAM initialised are proposed too, from a map grown for
  /// that long (< 0: never). The recognizer keeps `frame_buffer` frames to join them with.
  double late_keyframe_delay_s = 0.5;

  template <class V>
  void visit(V& v) {
    v("relative_lengths", relative_lengths,
      "lengths in units of the median viewing distance (else map units)");
    v("multiview_voxel", multiview_voxel, "map units, voxel of the multi-keyframe check");
    v("min_keyframes", min_keyframes,
      "keyframes whose points must be near a point for it to be kept (<= 1: off)");
    v("voxel", voxel, "map units, downsampling voxel");
    v("max_points", max_points, "points clustered at most (the voxel grows to fit)");
    v("max_depth_std", max_depth_std,
      "map units, points with a less certain depth are ignored (<= 0: all)");
    v("crop_percentile", crop_percentile, "%, per-axis percentile of the robust map bounds");
    v("crop_margin", crop_margin, "share of the robust range added to the bounds");
    v("plane_distance", plane_distance, "map units, RANSAC inlier distance of a plane");
    v("plane_iterations", plane_iterations, "RANSAC iterations");
    v("ransac_points", ransac_points, "RANSAC runs on an even subsample of this many points");
    v("plane_min_fraction", plane_min_fraction,
      "share of points a plane must hold to be searched further");
    v("max_planes", max_planes, "planes searched at most");
    v("structure_cell", structure_cell, "map units, grid cell of a plane's connected patches");
    v("structure_min_points", structure_min_points,
      "points a plane cell must hold to be part of a patch");
    v("structure_extent", structure_extent,
      "map units, plane patches larger than this are structure");
    v("support_max_tilt_deg", support_max_tilt_deg,
      "deg, largest angle of a support's normal to the views' up");
    v("support_radius", support_radius,
      "map units, the support's region: its cells this close to where the views look");
    v("support_below", support_below,
      "map units, the views' look-at point is at most this far under a support");
    v("support_fill", support_fill,
      "share of plane cells around a view's aim point that hold points");
    v("support_distance", support_distance,
      "map units, points this close to the support are its own");
    v("support_margin", support_margin,
      "map units, objects stand over the support's region grown by this");
    v("min_height", min_height, "map units, clusters lower than this over the support are dropped");
    v("max_height", max_height, "map units, points higher than this over the support are dropped");
    v("add_footprint", add_footprint,
      "candidates over the support plane include their footprint on it");
    v("band_grow", band_grow,
      "map units, how far past its bounds a candidate takes support-band points (<= 0: off)");
    v("band_colour_ratio", band_colour_ratio,
      "a band point is the candidate's when its colour's share of the candidate is over this x its "
      "share of the band");
    v("band_colour_bin", band_colour_bin,
      "RGB levels per bin of the candidate's and the band's colour histograms");
    v("band_reference_elsewhere", band_reference_elsewhere,
      "a candidate's band colours are compared with the band outside its bounds grown by band_grow "
      "(false: the whole band)");
    v.section("free_space", free_space, "free-space carving (free_space.h)");
    v("max_maps", max_maps,
      "SLAM maps whose candidates are kept (SLAM may return to an older one)");
    v("max_views", max_views, "camera poses kept for the up and look-at priors");
    v("recluster_interval_s", recluster_interval_s,
      "s of frame time between re-clusterings of a growing map (0: every change)");
    v("recluster_growth", recluster_growth,
      "or sooner, once the map holds this many times the points of its last clustering (<= 1: "
      "off)");
    v("radius", radius, "map units, clustering radius of the finest scale (x2 per scale)");
    v("scales", scales, "density thresholds, a factor 2 apart");
    v("min_neighbours", min_neighbours, "points within the radius that make a core point");
    v("colour_distance", colour_distance,
      "RGB distance for core points to join in a second, colour-aware clustering (<= 0: position "
      "only)");
    v("min_points", min_points, "smallest cluster");
    v("young_map_points", young_map_points, "a map of fewer points is young (0: never)");
    v("young_min_points", young_min_points, "smallest cluster of a young map");
    v("young_radius_scale", young_radius_scale,
      "clustering radii of a young map, times radius (<= 0: as radius)");
    v("max_extent", max_extent, "map units, largest object along any axis");
    v("min_extent", min_extent, "map units, smallest object along its largest axis");
    v("same_cluster_overlap", same_cluster_overlap,
      "share of points for clusters of two scales to be one");
    v("split_share", split_share,
      "share of a cluster's points that each of two finer-scale clusters must hold for it to rank "
      "as two objects (> 0.5: off)");
    v("id_overlap", id_overlap, "share of voxels for a new cluster to keep an old id");
    v("max_points_per_candidate", max_points_per_candidate, "points projected per candidate");
    v("depth_buffer_cell_px", depth_buffer_cell_px, "px, depth-buffer cell");
    v("occlusion_margin", occlusion_margin, "relative depth margin of occlusion");
    v("occluded_fraction", occluded_fraction, "share of hidden points that culls a candidate");
    v("min_visible_fraction", min_visible_fraction, "share of points that must be in the image");
    v("box_trim_pct", box_trim_pct,
      "%, a box spans its projected points without this share on each side");
    v("box_trim_pct_unsupported", box_trim_pct_unsupported,
      "%, the same for a candidate that does not stand on a support");
    v("box_trim_gap", box_trim_gap,
      "...then grows over trimmed points this close (x mean spacing) to the last (<= 0: off)");
    v("min_box_px", min_box_px, "px, smallest box side");
    v("nms_iou", nms_iou,
      "IoU above which boxes are suppressed here (>= 1: none; the recognizer suppresses by "
      "confidence)");
    v("max_boxes", max_boxes, "boxes per frame at most");
    v("keep_lost_s", keep_lost_s,
      "s of frame time a candidate that a re-clustering lost (its region in no new cluster) is "
      "kept (0: off)");
    v("lost_held", lost_held,
      "share of a lost candidate's voxels in new clusters at which it counts as found in them");
    v("late_keyframe_delay_s", late_keyframe_delay_s,
      "s of frame time after which a keyframe whose frame was not located (a map's reference "
      "frame) gets its proposals (< 0: never)");
  }
};

}  // namespace slamaware::proposals
