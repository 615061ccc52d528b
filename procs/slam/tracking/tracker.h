#pragma once
// Tracking (after ORB-SLAM's Tracking, Mur-Artal et al. 2015, section V): each frame is located
// against the map by a constant-velocity prediction and a projection search of the previous
// frame's points, or, when that fails, by matching the reference keyframe's features; the pose is
// then refined against the local map (points of the keyframes that share points with the frame
// and their covisible neighbours) by motion-only optimisation with a robust loss. Keyframes are
// taken by the covisibility policy. When lost, the tracker relocalises against keyframes of this
// and earlier maps (descriptor matches + PnP RANSAC), and after a configured time lost it starts
// a new map from two views.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "procs/slam/geometry/pnp.h"
#include "procs/slam/initialization/initializer.h"
#include "procs/slam/map/frame.h"
#include "procs/slam/map/map.h"
#include "procs/slam/matching/matcher.h"
#include "procs/slam/slam_options.h"

namespace slamaware::slam {

/// What the tracker concluded about one frame.
enum class TrackOutcome {
  kNoMap,        ///< no map yet (initialising)
  kTracked,      ///< located in the current map, continuous with the previous frame
  kRelocalized,  ///< located again after being lost (possibly in an earlier map)
  kNewMap,       ///< a new map was initialised with this frame
  kLost,         ///< not located
};

struct TrackResult {
  TrackOutcome outcome = TrackOutcome::kNoMap;
  SE3 T_camera_world = SE3::Identity();  ///< valid for tracked / relocalised / new map
  std::shared_ptr<Map> map;              ///< the map the pose is in (null without a map)
  int num_tracked = 0;                   ///< map points matched (inliers)
  int64_t reference_keyframe_id = -1;
  /// Keyframes created with this frame (two when a map was initialised), for local mapping and
  /// the depth filter.
  std::vector<std::shared_ptr<KeyFrame>> new_keyframes;
  std::string event;  ///< a sentence for the log when something changed
};

class Tracker {
 public:
  Tracker(const SlamOptions& options, IdSource& ids);

  /// Locates `frame` (features extracted, id/utime/seq set). `continuous` = false says the input
  /// broke continuity (time went backwards, frames are missing): the motion model is not used and
  /// the frame is relocalised. `mapper_idle` feeds the keyframe policy.
  TrackResult track(Frame& frame, bool continuous, bool mapper_idle);

  /// Every map created so far (the current one last), for relocalisation and output.
  const std::vector<std::shared_ptr<Map>>& maps() const { return maps_; }
  std::shared_ptr<Map> activeMap() const { return map_; }
  /// Drops every map and starts over (a new camera).
  void reset();

 private:
  enum class State { kNoMap, kTracking, kLost };

  TrackResult initialize(Frame& frame, bool after_loss);
  bool trackMotionModel(Frame& frame);
  bool trackReferenceKeyFrame(Frame& frame);
  /// Descriptor matches (keyframe feature, frame feature) of the keyframe's map points.
  Matches matchKeyFrame(const Frame& frame, const KeyFrame& kf) const;
  /// PnP RANSAC on those matches (salt varies the random stream per use).
  PnpResult pnpFromMatches(const Frame& frame, const KeyFrame& kf, const Matches& matches,
                           int salt) const;
  bool trackLocalMap(Frame& frame, bool just_relocalized, int* inliers);
  bool relocalize(Frame& frame, std::shared_ptr<KeyFrame>* matched_kf);
  bool relocalizeAgainst(Frame& frame, const std::shared_ptr<KeyFrame>& kf);
  int optimizeFramePose(Frame& frame, bool drop_outliers);
  bool needNewKeyFrame(const Frame& frame, int inliers, bool mapper_idle) const;
  std::shared_ptr<KeyFrame> createKeyFrame(Frame& frame);
  void updateVelocity(const Frame& frame);
  uint64_t rngSeed(const Frame& frame, int salt) const;

  SlamOptions options_;
  IdSource& ids_;
  Initializer initializer_;
  State state_ = State::kNoMap;
  std::vector<std::shared_ptr<Map>> maps_;
  std::shared_ptr<Map> map_;
  std::optional<Frame> last_frame_;  ///< the last frame that was located
  std::shared_ptr<KeyFrame> reference_kf_;
  bool velocity_valid_ = false;
  Vector6d velocity_per_s_ = Vector6d::Zero();  ///< log(T_cur * T_last^-1) / dt, 1/s
  int64_t last_keyframe_utime_ = 0;
  Eigen::Vector3d last_keyframe_center_ = Eigen::Vector3d::Zero();
  int64_t last_keyframe_id_ = -1;  ///< the keyframe last_keyframe_center_ belongs to
  int64_t lost_since_utime_ = 0;
};

}  // namespace slamaware::slam
