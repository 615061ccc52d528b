#pragma once
// The SLAM stage as a library (no LCM): frames in, poses, keyframes and semi-dense map updates
// out. Tracking runs on the caller's thread; local mapping and the depth filter on their own.
//
// Lockstep (docs/architecture.md §4): processFrame() waits for the mapping and depth work the frame
// caused before it returns, so that the outputs depend only on the input frames. Real time: it
// returns as soon as the frame is tracked; collectBackground() hands over what the workers produced
// since, and depth-filter frames are skipped (and counted) when the filter falls behind.
#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "common/camera_model.h"
#include "common/geometry.h"
#include "procs/slam/slam_options.h"

namespace slamaware {
class SerialWorker;
}  // namespace slamaware

namespace slamaware::slam {

class OrbExtractor;
class Tracker;
class LocalMapper;
class DepthFilter;
class Map;
class KeyFrame;
struct Frame;
struct Intrinsics;
struct IdSource;
struct TrackResult;
struct SemiDenseKeyframe;

/// Same values as pose_t's STATE_* constants.
enum class PoseState : int8_t { kInitializing = 0, kTracking = 1, kLost = 2, kRelocalized = 3 };
const char* poseStateName(PoseState s);

struct PoseOutput {
  int64_t utime = 0;
  int32_t seq = -1;
  PoseState state = PoseState::kInitializing;
  SE3 T_world_camera = SE3::Identity();  ///< INITIALIZING: identity; LOST: the last valid pose
  int map_id = 0;                        ///< 0 before the first map
  int num_tracked = 0;
  int64_t reference_keyframe_id = -1;
};

struct KeyframeOutput {
  int64_t utime = 0;
  int32_t seq = -1;
  int64_t id = -1;
  int map_id = 0;
  SE3 T_world_camera = SE3::Identity();
  int num_points = 0;
  std::vector<std::pair<int64_t, int>> covisible;  ///< (keyframe id, shared points), heaviest first
  bool culled = false;
};

struct CloudPoint {
  Eigen::Vector3f p_world;
  uint8_t rgb[3] = {0, 0, 0};
  float depth_std = 0;  ///< map units along the keyframe ray
  int64_t keyframe_id = -1;
};

struct CloudOutput {
  int64_t utime = 0;  ///< the frame whose processing produced it
  int32_t seq = -1;
  int map_id = 0;
  int64_t keyframe_id = -1;  ///< incremental: the keyframe; full: -1
  bool full = false;
  std::vector<CloudPoint> points;
  std::vector<std::pair<int64_t, Eigen::Vector3f>> keyframe_centers;  ///< world frame
};

/// Everything one call produced. Publish keyframes and clouds before the pose (a stage that acts
/// on the pose then already has the map).
struct SlamOutput {
  bool has_pose = false;
  PoseOutput pose;
  std::vector<KeyframeOutput> keyframes;
  std::vector<CloudOutput> clouds;
  std::vector<std::string> events;  ///< what changed (for the log and the status message)
};

struct SlamStats {
  std::string state = "INITIALIZING";
  int map_id = 0;
  int64_t maps = 0, keyframes = 0, points = 0;  ///< keyframes and points of the current map
  int64_t frames = 0, frames_located = 0, frames_lost = 0, frames_unusable = 0;
  int64_t frames_duplicate = 0, discontinuities = 0;
  int64_t relocalizations = 0, reinitializations = 0;
  int64_t depth_seeds = 0, depth_points = 0, depth_frames_skipped = 0;
  int64_t bundle_adjustments = 0, keyframes_culled = 0;
  double track_ms = 0;              ///< last frame: features and tracking
  double extract_ms = 0;            ///< last frame: features
  double depth_update_ms = 0;       ///< last depth-filter update
  int64_t depth_updates = 0;        ///< depth-filter updates so far
  double mapping_ms = 0;            ///< local mapping of every keyframe so far (wall clock)
  double bundle_adjustment_ms = 0;  ///< of it, local bundle adjustment
};

/// Nice increments of SLAM's background threads (system.yaml `scheduling`); tracking, on every
/// frame's path, stays at the process's priority. Only timing depends on them.
struct SlamThreadNice {
  int mapping = 0;
  int depth = 0;
};

class SlamSystem {
 public:
  SlamSystem(const SlamOptions& options, bool lockstep, SlamThreadNice nice = {});
  ~SlamSystem();
  SlamSystem(const SlamSystem&) = delete;
  SlamSystem& operator=(const SlamSystem&) = delete;

  /// Sets the camera. A camera different from the current one restarts SLAM from scratch (the
  /// maps are dropped; the next map gets a new id); returns true when that happened.
  bool setCamera(const CameraModel& camera);
  bool hasCamera() const;
  const CameraModel& camera() const { return camera_; }

  /// Tracks one 8-bit BGR frame of the camera's size. A frame with the same utime and seq as the
  /// previous one repeats the previous answer; a utime that does not advance breaks continuity
  /// (the frame is relocalised rather than tracked).
  SlamOutput processFrame(int64_t utime, int32_t seq, const cv::Mat& bgr);
  /// A frame that could not be used (corrupt, wrong size): its pose says LOST (INITIALIZING before
  /// the first map) and the next located frame says RELOCALIZED.
  SlamOutput skipFrame(int64_t utime, int32_t seq);
  /// Real time: keyframe and map updates the workers produced since the last call; `utime`/`seq`
  /// stamp the clouds (the latest frame handled).
  SlamOutput collectBackground(int64_t utime, int32_t seq);
  /// Waits until mapping and depth work are done.
  void flush();

  SlamStats stats() const;

 private:
  void restart();
  void collect(int64_t utime, int32_t seq, const std::vector<std::shared_ptr<KeyFrame>>& created,
               SlamOutput* out);
  std::shared_ptr<Map> mapById(int map_id) const;
  static void appendPoints(const SemiDenseKeyframe& s, const SE3& T_world_camera, CloudOutput* c);
  KeyframeOutput describeKeyframe(const KeyFrame& kf) const;
  CloudOutput fullCloud(const std::shared_ptr<Map>& map, int64_t utime, int32_t seq) const;
  CloudOutput keyframeCloud(int64_t keyframe_id, int64_t utime, int32_t seq) const;
  /// The same, of a keyframe's points already copied from the depth filter.
  CloudOutput keyframeCloud(const SemiDenseKeyframe& s, int64_t utime, int32_t seq) const;
  /// Incremental clouds of the map's unfinished keyframes that grew enough (OutputOptions).
  void publishLiveClouds(int map_id, int64_t utime, int32_t seq, SlamOutput* out);
  void postDepthWork(const TrackResult& r, const Frame& frame);

  SlamOptions options_;
  bool lockstep_;
  SlamThreadNice nice_;
  CameraModel camera_;
  std::shared_ptr<const Intrinsics> intrinsics_;
  std::unique_ptr<OrbExtractor> extractor_;
  std::unique_ptr<IdSource> ids_;
  std::unique_ptr<Tracker> tracker_;
  std::unique_ptr<LocalMapper> mapper_;
  std::unique_ptr<DepthFilter> depth_;
  std::unique_ptr<SerialWorker> depth_worker_;

  int64_t next_frame_id_ = 0;
  bool have_last_ = false;
  int64_t last_utime_ = 0;
  int32_t last_seq_ = -1;
  PoseOutput last_pose_;   ///< the answer to the last frame processed (for a repeat)
  PoseOutput last_valid_;  ///< the last located pose (state TRACKING or RELOCALIZED)
  bool have_valid_ = false;
  PoseState last_state_ = PoseState::kInitializing;
  int first_map_id_ = -1;
  int last_full_map_id_ = -1;
  int64_t last_full_utime_ = 0;
  /// Unfinished keyframe -> its converged points when last published (0: not yet), and whether
  /// it was published at all (a young map's keyframe is, with its map points alone).
  std::map<int64_t, std::pair<size_t, bool>> live_published_;
  /// Keyframes culled since the depth filter's last input (they go with its next one).
  std::vector<int64_t> culled_for_depth_;

  mutable std::mutex finished_mutex_;
  std::vector<int64_t>
      depth_finished_;  ///< keyframes whose semi-dense points are final (from the worker)

  SlamStats stats_;
};

}  // namespace slamaware::slam
