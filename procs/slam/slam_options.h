#pragma once
// Options of the SLAM process (config/slam.yaml, section "slam"). One struct per component, each
// with its defaults inline and one visit() that the config loader and the printer share.
#include <cstdint>
#include <string>

namespace slamaware::slam {

/// ORB features on an image pyramid (Rublee et al. 2011, distributed as in ORB-SLAM).
struct OrbOptions {
  int num_features = 1200;     ///< features per image, over all levels
  double scale_factor = 1.2;   ///< scale between pyramid levels
  int num_levels = 8;          ///< pyramid levels
  int fast_threshold = 20;     ///< FAST threshold tried first in each cell
  int fast_threshold_min = 7;  ///< FAST threshold used in cells where the first finds nothing
  int cell_size_px = 32;       ///< px, FAST runs per cell so that weak cells still get corners
  int threads = 2;             ///< pyramid levels are described on this many threads
  uint64_t pattern_seed = 7;   ///< seed of the BRIEF test pattern (fixed: descriptors are data)

  template <class V>
  void visit(V& v) {
    v("num_features", num_features, "features per image over all pyramid levels");
    v("scale_factor", scale_factor, "scale between pyramid levels");
    v("num_levels", num_levels, "pyramid levels");
    v("fast_threshold", fast_threshold, "FAST threshold tried first in each cell");
    v("fast_threshold_min", fast_threshold_min,
      "FAST threshold in cells where the first finds nothing");
    v("cell_size_px", cell_size_px, "px, side of the cells FAST runs in");
    v("threads", threads,
      "threads the pyramid levels are shared out to (results do not depend on it)");
    v("pattern_seed", pattern_seed,
      "seed of the BRIEF test pattern (descriptors of different seeds do not match)");
  }
};

/// Two-view initialisation: homography or fundamental matrix, chosen by a score.
struct InitOptions {
  int ransac_iterations = 200;       ///< RANSAC iterations (the same 8-point sets for H and F)
  double sigma_px = 1.0;             ///< px, feature position noise used in the model scores
  double homography_ratio = 0.40;    ///< choose H when S_H / (S_H + S_F) exceeds this
  int min_matches = 80;              ///< fewer matches to the reference frame: take a new reference
  int min_triangulated = 50;         ///< points the initial map needs
  double min_parallax_deg = 1.0;     ///< median parallax the two views need
  double match_ratio = 0.8;          ///< nearest / second-nearest descriptor distance ratio
  int ba_iterations = 20;            ///< bundle adjustment iterations on the two-view map
  double max_reference_age_s = 3.0;  ///< s, a reference frame older than this is replaced
  int threads =
      2;  ///< candidate poses are refined on this many threads (results do not depend on it)

  template <class V>
  void visit(V& v) {
    v("ransac_iterations", ransac_iterations, "RANSAC iterations for H and F");
    v("sigma_px", sigma_px, "px, feature noise in the model scores");
    v("homography_ratio", homography_ratio, "choose H when S_H / (S_H + S_F) is above this");
    v("min_matches", min_matches, "fewer matches to the reference frame: take a new reference");
    v("min_triangulated", min_triangulated, "points the initial map needs");
    v("min_parallax_deg", min_parallax_deg, "deg, median parallax the two views need");
    v("match_ratio", match_ratio, "nearest / second nearest descriptor distance ratio");
    v("ba_iterations", ba_iterations, "bundle adjustment iterations on the two-view map");
    v("max_reference_age_s", max_reference_age_s,
      "s, a reference frame older than this is replaced");
    v("threads", threads,
      "threads the candidate poses are refined on (results do not depend on it)");
  }
};

/// Frame-to-map tracking and the keyframe policy.
struct TrackingOptions {
  double motion_search_radius_px = 15;  ///< px at level 0, search window of the motion model
  int min_motion_matches = 20;          ///< fewer: search again with twice the window
  double local_search_radius = 1.0;  ///< factor on the viewing-angle radius of the local map search
  int min_inliers = 25;              ///< inliers the local-map optimisation needs to keep tracking
  int min_inliers_relocalized = 40;  ///< the same just after relocalisation
  int max_local_keyframes = 60;      ///< keyframes in the local map
  double reference_match_ratio = 0.75;  ///< descriptor ratio when matching against a keyframe
  double keyframe_ratio = 0.9;  ///< keyframe when tracked points < this x the reference's...
  double min_keyframe_baseline =
      0.06;  ///< ...and the camera moved this x the scene depth since the last
  double weak_tracking_ratio = 0.5;  ///< below this x the reference's points: a keyframe regardless
  double max_keyframe_interval_s = 1.0;  ///< s, or this long passed (if the ratio test says so)
  int min_keyframe_points = 15;          ///< no keyframe with fewer tracked points
  double max_velocity_age_s = 2.0;       ///< s, a motion model older than this is not used

  template <class V>
  void visit(V& v) {
    v("motion_search_radius_px", motion_search_radius_px, "px, search window of the motion model");
    v("min_motion_matches", min_motion_matches,
      "fewer matches: search again with twice the window");
    v("local_search_radius", local_search_radius, "factor on the local map search window");
    v("min_inliers", min_inliers, "inliers needed to keep tracking");
    v("min_inliers_relocalized", min_inliers_relocalized,
      "inliers needed just after relocalisation");
    v("max_local_keyframes", max_local_keyframes, "keyframes in the local map");
    v("reference_match_ratio", reference_match_ratio,
      "descriptor ratio when matching to a keyframe");
    v("keyframe_ratio", keyframe_ratio,
      "new keyframe when tracked points fall below this x the reference's...");
    v("min_keyframe_baseline", min_keyframe_baseline,
      "...and the camera moved this x the median scene depth");
    v("weak_tracking_ratio", weak_tracking_ratio,
      "below this x the reference's points: a keyframe regardless");
    v("max_keyframe_interval_s", max_keyframe_interval_s,
      "s, or this long passed since the last keyframe");
    v("min_keyframe_points", min_keyframe_points, "no keyframe with fewer tracked points");
    v("max_velocity_age_s", max_velocity_age_s, "s, an older motion model is not used");
  }
};

/// Local mapping: triangulation, fusion, local bundle adjustment, culling.
struct MappingOptions {
  bool threaded = true;              ///< run on its own thread (false: inline, for tests)
  int triangulation_neighbors = 15;  ///< covisible keyframes searched for new points
  double min_parallax_deg = 1.0;     ///< deg, no new point from rays closer than this
  int fuse_neighbors = 15;           ///< keyframes whose points are fused with the new one's
  int ba_local_keyframes = 12;       ///< keyframes optimised by local bundle adjustment
  int ba_iterations_robust = 5;      ///< Huber-loss iterations before outlier removal
  int ba_iterations_refine = 10;     ///< iterations after outlier removal
  double point_found_ratio =
      0.25;  ///< cull a new point matched in fewer than this x the frames it should be seen
  double keyframe_redundancy = 0.9;  ///< cull a keyframe when this share of its points is seen by 3
                                     ///< others (and make none of a frame whose tracked points are)
  int min_covisibility_weight = 15;  ///< shared points for a covisibility edge

  template <class V>
  void visit(V& v) {
    v("threaded", threaded, "run local mapping on its own thread");
    v("triangulation_neighbors", triangulation_neighbors,
      "covisible keyframes searched for new points");
    v("min_parallax_deg", min_parallax_deg, "deg, no new point from rays closer than this");
    v("fuse_neighbors", fuse_neighbors, "keyframes whose points are fused with the new one's");
    v("ba_local_keyframes", ba_local_keyframes, "keyframes optimised by local bundle adjustment");
    v("ba_iterations_robust", ba_iterations_robust, "Huber-loss iterations before outlier removal");
    v("ba_iterations_refine", ba_iterations_refine, "iterations after outlier removal");
    v("point_found_ratio", point_found_ratio,
      "cull new points found in fewer than this share of their views");
    v("keyframe_redundancy", keyframe_redundancy,
      "cull a keyframe when this share of its points is seen thrice elsewhere");
    v("min_covisibility_weight", min_covisibility_weight, "shared points for a covisibility edge");
  }
};

/// Relocalisation when lost, and re-initialisation with a new map.
struct RelocOptions {
  int candidates = 8;              ///< keyframes tried, most similar first (small blurry images)
  int min_matches = 15;            ///< descriptor matches a candidate needs
  int pnp_iterations = 200;        ///< RANSAC iterations of PnP
  double pnp_threshold_px = 5.99;  ///< squared px (chi-square 2 dof, 95%) at level 0
  int min_pnp_inliers = 12;        ///< PnP inliers before the projection search
  double reinit_after_s = 1.0;     ///< s lost before a new map may be started
  bool search_all_maps = true;     ///< also relocalise into earlier maps

  template <class V>
  void visit(V& v) {
    v("candidates", candidates, "keyframes tried, most similar first");
    v("min_matches", min_matches, "descriptor matches a candidate needs");
    v("pnp_iterations", pnp_iterations, "RANSAC iterations of PnP");
    v("pnp_threshold_px", pnp_threshold_px, "px^2 at level 0, PnP inlier threshold");
    v("min_pnp_inliers", min_pnp_inliers, "PnP inliers before the projection search");
    v("reinit_after_s", reinit_after_s, "s lost before a new map may be started");
    v("search_all_maps", search_all_maps, "also relocalise into earlier maps");
  }
};

/// Semi-dense depth: Gaussian x Beta depth filter (Vogiatzis & Hernandez 2011, as in SVO).
struct DepthFilterOptions {
  bool enabled = true;
  bool threaded = true;                ///< run on its own thread (false: inline, for tests)
  int max_seeds_per_keyframe = 6000;   ///< seeds per keyframe, highest gradients first
  int seed_cell_px = 3;                ///< px, at most one seed per cell of this size
  double min_gradient = 10.0;          ///< grey levels per px, weakest gradient a seed may have
  int max_keyframes = 3;               ///< seeds live until this many newer keyframes exist...
  int min_frames = 8;                  ///< ...and were searched in this many frames (bounded by
                                       ///< max_keyframes + this newer keyframes; depth_filter.h)
  double convergence_ratio = 200.0;    ///< converged when sigma < inverse-depth range / this
  double pixel_noise = 1.0;            ///< px, matching noise (tau of SVO's computeTau)
  double max_search_px = 400.0;        ///< px, longer epipolar segments are not searched
  double max_ssd_per_sample = 300.0;   ///< grey levels^2 per sample, worst accepted match
  double uniqueness_ratio = 0.7;       ///< best / second-best SSD must be below this
  double min_epipolar_gradient = 6.0;  ///< grey levels, seed gradient along the epipolar line
  double min_inlier_ratio = 0.25;      ///< a / (a + b) below this: the seed is dropped
  double min_baseline_ratio = 0.004;   ///< baseline / depth below this: the frame is not used
  int max_queue = 3;                   ///< real time: frames waiting beyond this are skipped
  /// A keyframe made while fewer seeds of its map have converged than this takes its map points
  /// (triangulated features) as its first points (0: never): a young map's objects have points
  /// before its first seeds converge, which at low frame rates takes several frames.
  int young_map_points = 2000;
  double sparse_depth_std = 0.01;  ///< depth std of those points, as a share of their distance
  /// Those keyframes also publish each seed once sigma < inverse-depth range / this, as a
  /// provisional point, and filter it on to convergence_ratio (<= 0: off): at 30 fps a young map's
  /// first seeds converge about ten frames after it is made. The provisional points are dropped
  /// with the map points.
  double young_convergence_ratio = 30.0;

  template <class V>
  void visit(V& v) {
    v("enabled", enabled, "semi-dense depth on/off");
    v("threaded", threaded, "run on its own thread");
    v("max_seeds_per_keyframe", max_seeds_per_keyframe, "seeds per keyframe");
    v("seed_cell_px", seed_cell_px, "px, at most one seed per cell of this size");
    v("min_gradient", min_gradient, "grey levels per px, weakest seed gradient");
    v("max_keyframes", max_keyframes, "seeds live until this many newer keyframes exist...");
    v("min_frames", min_frames, "...and they were searched in this many frames");
    v("convergence_ratio", convergence_ratio, "converged when sigma < inverse-depth range / this");
    v("pixel_noise", pixel_noise, "px, matching noise");
    v("max_search_px", max_search_px, "px, longer epipolar segments are not searched");
    v("max_ssd_per_sample", max_ssd_per_sample, "grey levels^2 per sample, worst accepted match");
    v("uniqueness_ratio", uniqueness_ratio, "best / second best SSD must be below this");
    v("min_epipolar_gradient", min_epipolar_gradient,
      "grey levels, seed gradient along the epipolar line");
    v("min_inlier_ratio", min_inlier_ratio, "seeds with a lower inlier probability are dropped");
    v("min_baseline_ratio", min_baseline_ratio,
      "frames with baseline / depth below this are not used");
    v("max_queue", max_queue, "real time: frames waiting beyond this are skipped");
    v("young_map_points", young_map_points,
      "keyframes of a map with fewer converged seeds take its map points (0: never)");
    v("sparse_depth_std", sparse_depth_std, "depth std of those points, share of their distance");
    v("young_convergence_ratio", young_convergence_ratio,
      "their seeds are also published, provisionally, once sigma < inverse-depth range / this (<= "
      "0: off)");
  }
};

/// What the process publishes besides poses.
struct OutputOptions {
  double full_map_period_s = 5.0;  ///< s of sequence time between full SLAM_MAP messages
  /// A keyframe is published (incremental) when its seeds are finished. Before that, a keyframe
  /// of the active map has its points so far published once they number live_cloud_min_points,
  /// and again whenever they have grown by this share since (0: finished keyframes only): a young
  /// map shows its first objects while its first keyframes' seeds are still converging.
  double live_cloud_growth = 0.5;
  int live_cloud_min_points = 200;

  template <class V>
  void visit(V& v) {
    v("full_map_period_s", full_map_period_s, "s of sequence time between full maps");
    v("live_cloud_growth", live_cloud_growth,
      "unfinished keyframes are republished after growing by this share (0: off)");
    v("live_cloud_min_points", live_cloud_min_points,
      "points an unfinished keyframe needs to be published");
  }
};

struct SlamOptions {
  uint64_t seed = 1;  ///< seeds every random generator (RANSAC)
  OrbOptions orb;
  InitOptions init;
  TrackingOptions tracking;
  MappingOptions mapping;
  RelocOptions reloc;
  DepthFilterOptions depth;
  OutputOptions output;

  template <class V>
  void visit(V& v) {
    v("seed", seed, "seed of every random generator");
    v.section("orb", orb);
    v.section("init", init);
    v.section("tracking", tracking);
    v.section("mapping", mapping);
    v.section("reloc", reloc);
    v.section("depth", depth);
    v.section("output", output);
  }
};

}  // namespace slamaware::slam
