#pragma once
// Options of the object proposals (config/proposals.yaml, section "proposals"). A monocular map
// has no metric scale (its unit is the first keyframe's median depth, which may be a wall behind
// the table or the table itself), so with relative_lengths every length below is a fraction of
// the median viewing distance of the map at clustering time: for a camera about a metre from
// the table, 0.1 is about 10 cm.
#include <string>

namespace slamaware {

struct ProposalOptions {
  bool relative_lengths = true;  ///< lengths in units of the median viewing distance (else map units)
  // Map filtering.
  double voxel = 0.004;          ///< map units, the map is downsampled to one point per voxel
  int max_points = 120000;       ///< points clustered at most (bounded cost); the voxel grows to fit
  int outlier_neighbours = 12;   ///< statistical outlier removal: neighbours considered
  double outlier_std = 2.0;      ///< ... points farther than mean + this many std are dropped
  double max_depth_std = 0.0;    ///< map units, points with a less certain depth are ignored (<= 0: all kept)
  double crop_percentile = 2.0;  ///< %, points outside the [p, 100-p] percentiles per axis ...
  double crop_margin = 0.5;      ///< ... widened by this share of the range are dropped (stray depths)
  double plane_distance = 0.02;  ///< map units, RANSAC inlier distance of a plane
  int plane_iterations = 200;    ///< RANSAC iterations
  double plane_min_fraction = 0.1; ///< a plane is removed only if it holds this share of the points
  int max_planes = 3;            ///< planes removed at most (support, floor, walls)
  double support_margin = 0.03;  ///< map units: objects stand on the support plane (the largest,
                                 ///< facing the camera), within this distance of its points
  double min_height = 0.02;      ///< map units: clusters lower than this over the support plane are its texture
  bool add_footprint = true;     ///< a candidate over the support plane includes its footprint on it
  // Density-based clustering at `scales` radii, each twice the previous.
  double radius = 0.008;         ///< map units, neighbourhood radius of the finest scale
  int scales = 4;                ///< density thresholds, a factor 2 apart
  double colour_distance = 0;    ///< RGB distance (0..441) under which neighbours join; <= 0: position only
  int min_points = 60;           ///< smallest cluster
  double max_extent = 0.7;       ///< map units, clusters larger than this along any axis are not objects
  double min_extent = 0.02;      ///< map units, clusters smaller than this along every axis are noise
  double same_cluster_overlap = 0.9; ///< clusters of two scales sharing this share of points are one
  double id_overlap = 0.3;       ///< a new cluster keeps the id of an old one sharing this share of voxels
  // Projection into each frame.
  int max_points_per_candidate = 400; ///< points projected per candidate (evenly subsampled)
  int depth_buffer_cell_px = 8;  ///< px, cell of the candidates' depth buffer
  double occlusion_margin = 0.15; ///< relative depth: nearer than (1 - margin) x depth occludes
  double occluded_fraction = 0.6; ///< candidates with more of their points hidden are culled
  double min_visible_fraction = 0.5; ///< of a candidate's points in front of the camera and in the image
  int min_box_px = 20;           ///< boxes smaller than this along either side are dropped
  double nms_iou = 0.5;          ///< boxes overlapping a kept box more than this are suppressed
  int max_boxes = 100;           ///< boxes per frame at most

  template <class V>
  void visit(V& v) {
    v("relative_lengths", relative_lengths, "lengths in units of the median viewing distance (else map units)");
    v("voxel", voxel, "map units, downsampling voxel");
    v("max_points", max_points, "points clustered at most (the voxel grows to fit)");
    v("outlier_neighbours", outlier_neighbours, "statistical outlier removal: neighbours");
    v("outlier_std", outlier_std, "statistical outlier removal: std multiplier");
    v("max_depth_std", max_depth_std, "map units, points with a less certain depth are ignored (<= 0: all)");
    v("crop_percentile", crop_percentile, "%, per-axis percentile of the robust map bounds");
    v("crop_margin", crop_margin, "share of the robust range added to the bounds");
    v("plane_distance", plane_distance, "map units, RANSAC inlier distance of a plane");
    v("plane_iterations", plane_iterations, "RANSAC iterations");
    v("plane_min_fraction", plane_min_fraction, "share of points a plane must hold to be removed");
    v("max_planes", max_planes, "planes removed at most");
    v("support_margin", support_margin, "map units, objects are over the support plane within this");
    v("min_height", min_height, "map units, clusters lower than this over the support plane are dropped");
    v("add_footprint", add_footprint, "candidates over the support plane include their footprint on it");
    v("radius", radius, "map units, clustering radius of the finest scale (x2 per scale)");
    v("scales", scales, "density thresholds, a factor 2 apart");
    v("colour_distance", colour_distance, "RGB distance for neighbours to join (<= 0: position only)");
    v("min_points", min_points, "smallest cluster");
    v("max_extent", max_extent, "map units, largest object along any axis");
    v("min_extent", min_extent, "map units, smallest object along its largest axis");
    v("same_cluster_overlap", same_cluster_overlap, "share of points for clusters of two scales to be one");
    v("id_overlap", id_overlap, "share of voxels for a new cluster to keep an old id");
    v("max_points_per_candidate", max_points_per_candidate, "points projected per candidate");
    v("depth_buffer_cell_px", depth_buffer_cell_px, "px, depth-buffer cell");
    v("occlusion_margin", occlusion_margin, "relative depth margin of occlusion");
    v("occluded_fraction", occluded_fraction, "share of hidden points that culls a candidate");
    v("min_visible_fraction", min_visible_fraction, "share of points that must be in the image");
    v("min_box_px", min_box_px, "px, smallest box side");
    v("nms_iou", nms_iou, "IoU above which boxes are suppressed");
    v("max_boxes", max_boxes, "boxes per frame at most");
  }
};

}  // namespace slamaware
