#pragma once
// Semi-dense depth (docs/architecture.md §3): each keyframe's high-gradient pixels become
// depth-filter seeds (seed.h), updated by epipolar search (epipolar_search.h) in every later
// located frame of the same map; seeds that converge become coloured points with a depth standard
// deviation, stored in their keyframe's camera frame so that they move with it when bundle
// adjustment moves the keyframe. A keyframe's seeds live until max_keyframes newer keyframes exist
// and they were searched in min_frames frames (at low frame rates, when every frame is a keyframe,
// max_keyframes alone would give each seed too few measurements to converge); then the keyframe is
// finished and its points are final. A keyframe that local mapping culls (its view is redundant:
// other keyframes see what it sees) takes its seeds and points with it, so that the semi-dense map
// grows with the surfaces seen, not with the time spent looking at them (a robot driving the same
// path again makes new keyframes there that are culled again).
//
// The filter works only on the data handed to process() (images, poses snapshotted by the
// caller), never on the live map, so that it can run on its own thread deterministically.
#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <mutex>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "common/geometry.h"
#include "procs/slam/depth/epipolar_search.h"
#include "procs/slam/depth/seed.h"
#include "procs/slam/slam_options.h"

namespace slamaware::slam {

/// A new keyframe to seed.
struct DepthKeyframeInput {
  int64_t id = -1;
  int map_id = 0;
  int64_t utime = 0;
  int32_t seq = -1;
  cv::Mat grey, bgr;  ///< 8-bit, undistorted
  SE3 T_world_camera = SE3::Identity();
  double min_depth = 0.5, mean_depth = 1.0;  ///< map units, from the keyframe's map points
  /// The keyframe's map points (sparse features): undistorted pixel and position in its camera
  /// frame. A keyframe of a young map takes them as its first points (young_map_points).
  std::vector<std::pair<Eigen::Vector2i, Eigen::Vector3f>> sparse;
};

/// One frame's worth of work.
struct DepthFrameInput {
  int64_t utime = 0;
  int32_t seq = -1;
  int map_id = 0;
  bool located = false;  ///< false: the frame only carries keyframes / pose updates
  cv::Mat grey;          ///< 8-bit, undistorted
  SE3 T_world_camera = SE3::Identity();
  std::vector<DepthKeyframeInput> new_keyframes;  ///< created with this frame
  std::vector<std::pair<int64_t, SE3>>
      keyframe_poses;  ///< current T_world_camera of live keyframes
  /// Keyframes that local mapping culled since the previous input: their seeds stop and their
  /// points are dropped (DepthFilter::process).
  std::vector<int64_t> culled_keyframes;
};

/// A converged seed.
struct SemiDensePoint {
  Eigen::Vector3f p_camera;  ///< map units, host keyframe's camera frame
  float depth_std = 0;       ///< map units, along the host ray
  uint8_t rgb[3] = {0, 0, 0};
  /// A young map's seed, converged at young_convergence_ratio only: it stands in for the map's
  /// converged points, like the keyframe's map points, and is dropped with them.
  bool provisional = false;
};

/// The semi-dense points of one keyframe.
struct SemiDenseKeyframe {
  int64_t id = -1;
  int map_id = 0;
  int64_t utime = 0;
  int32_t seq = -1;
  SE3 T_world_camera = SE3::Identity();  ///< last known pose of the keyframe
  std::vector<SemiDensePoint> points;
  size_t from_features = 0;  ///< the first points are its map points (a young map's keyframe)
  size_t provisional = 0;    ///< points of provisional seeds (SemiDensePoint::provisional)
  bool features_dropped =
      false;  ///< ...which it dropped, and those, when it finished (DepthFilter::process)
  bool finished = false;  ///< no seeds left: the points are final
};

struct DepthFilterStats {
  int64_t active_seeds = 0;
  int64_t points = 0;  ///< converged points stored
  int64_t frames = 0;  ///< frames used for updates
  int64_t measurements = 0, failures = 0;
  int64_t calls = 0;          ///< process() calls
  double last_update_ms = 0;  ///< time of the last process() call
};

class DepthFilter {
 public:
  /// width/height and the pinhole intrinsics of the (undistorted) images.
  DepthFilter(const DepthFilterOptions& options, int width, int height, double fx, double fy,
              double cx, double cy);

  /// Drops the culled keyframes, updates the seeds with the frame, finishes keyframes that are too
  /// old (or of another map), then seeds the new keyframes. Returns the ids of keyframes finished
  /// by this call.
  std::vector<int64_t> process(const DepthFrameInput& input);

  /// A copy of a keyframe's points (empty when unknown). Thread-safe.
  SemiDenseKeyframe keyframe(int64_t id) const;
  /// Copies of all stored keyframes of a map, by id. Thread-safe.
  std::vector<SemiDenseKeyframe> mapKeyframes(int map_id) const;
  /// A keyframe whose seeds are still converging.
  struct LiveKeyframe {
    int64_t id = -1;
    size_t points = 0;         ///< points so far
    size_t from_features = 0;  ///< of which its map points (SemiDenseKeyframe::from_features)
  };
  /// A map's keyframes whose seeds are still converging, by id. Thread-safe.
  std::vector<LiveKeyframe> liveKeyframes(int map_id) const;
  DepthFilterStats stats() const;

 private:
  /// Seeds of a keyframe image: the strongest-gradient pixel of each cell, strongest first, at
  /// most max_seeds_per_keyframe.
  std::vector<Eigen::Vector2i> selectSeedPixels(const cv::Mat& grey) const;

  struct Host {
    SemiDenseKeyframe* store = nullptr;
    cv::Mat grey, bgr;
    SE3 T_world_camera;
    std::vector<DepthSeed> seeds;
    int newer_keyframes = 0;
    int frames_searched = 0;  ///< frames whose baseline sufficed to search the seeds
    bool young = false;       ///< a young map's keyframe (its seeds also converge provisionally)
  };
  void updateHost(Host& host, const DepthFrameInput& input, std::vector<SemiDensePoint>* converged);
  /// A new keyframe becomes a host: its store entry (with its features while the map is young)
  /// and its seeds.
  void addHost(const DepthKeyframeInput& kf);
  /// A culled keyframe: its seeds and stored points go (nothing is published for it).
  void dropKeyframe(int64_t id);

  DepthFilterOptions options_;
  EpipolarSearchParams search_;
  int width_, height_;
  double fx_, fy_, cx_, cy_;
  double px_error_angle_;
  std::map<int64_t, Host> hosts_;  ///< keyframes with live seeds (worker only)
  int64_t frames_ = 0, measurements_ = 0, failures_ = 0;  ///< worker only; copied into stats_
  std::map<int, int64_t> converged_per_map_;  ///< converged seeds per SLAM map (worker only)
  mutable std::mutex store_mutex_;
  std::map<int64_t, SemiDenseKeyframe> store_;  ///< every keyframe's points (guarded)
  DepthFilterStats stats_;                      ///< guarded by store_mutex_
};

}  // namespace slamaware::slam
