#pragma once
// The proposals stage without the bus: CAMERA_INFO, SLAM_MAP and SLAM_POSE messages in, one
// PROPOSALS message per pose out. The node feeds it from LCM; the evaluator feeds it from a
// recorded log to re-run proposals with other options.
//
// Clustering a grown map takes 50-200 ms. In lockstep it runs before the frame's boxes are
// projected (deterministic). With background clustering (the node in real time) it runs on a
// worker thread from a copy of the map while the frames go on with the last candidates; a finished
// clustering is taken at the next pose. Boxes then never wait for a clustering.
#include <future>
#include <map>
#include <string>
#include <vector>

#include "common/camera_model.h"
#include "procs/proposals/candidate_map.h"
#include "procs/proposals/projector.h"
#include "slamaware/camera_info_t.hpp"
#include "slamaware/keyframe_t.hpp"
#include "slamaware/point_cloud_t.hpp"
#include "slamaware/pose_t.hpp"
#include "slamaware/proposals_t.hpp"

namespace slamaware::proposals {

class ProposalEngine {
 public:
  /// background_clustering: cluster on a worker thread (real time); false: in onPose (lockstep,
  /// the evaluator, tests).
  explicit ProposalEngine(const ProposalOptions& options, bool background_clustering = false)
      : options_(options), background_(background_clustering) {}
  ~ProposalEngine();

  /// False (and *why naming the message) for a camera that cannot be used.
  bool onCameraInfo(const camera_info_t& info, std::string* why);
  /// False (and *why) for a cloud whose arrays disagree with num_points.
  bool onMap(const point_cloud_t& cloud, std::string* why);
  /// The proposals of one frame: empty when the frame is not localised, its pose is not finite
  /// (*why is set), no camera is known yet, or nothing is in view. Re-clusters first when the
  /// map changed (*reclustered = true; with background clustering: a clustering finished and was
  /// taken).
  proposals_t onPose(const pose_t& pose, std::string* why, bool* reclustered = nullptr);
  /// A SLAM_KEYFRAME. A keyframe whose frame got no proposals when its pose came (not located
  /// yet: the reference frame a map is initialised from; or its map had no points yet) is kept
  /// with its pose (the latest, bundle adjustment moves it); once a pose of its map is
  /// `late_keyframe_delay_s` of frame time later, that onPose projects the candidates into it as
  /// well (takeLateProposals). A culled keyframe is forgotten.
  void onKeyframe(const keyframe_t& keyframe);
  /// The late proposals of keyframes (onKeyframe) that the last onPose projected, oldest first;
  /// empty when none came due. Their utime and seq are their own frame's, older than the pose's.
  std::vector<proposals_t> takeLateProposals();

  /// The candidates of the map the last pose was in (SLAM may go back to an older map: the
  /// `max_maps` most recently used maps are kept).
  const CandidateMap& map() const;
  const ProjectionStats& lastProjection() const { return last_; }
  /// The camera of CAMERA_INFO, nullptr before one arrived.
  const CameraModel* camera() const { return have_camera_ ? &camera_ : nullptr; }

 private:
  ProposalOptions options_;
  CandidateMap& mapOf(int32_t map_id);
  /// Clusters `map` when due: at once, or (background) takes a finished clustering and starts the
  /// next one. True when new candidates were taken.
  bool recluster(CandidateMap& map, const pose_t& pose);
  /// The message of the candidates of `map` projected with T_world_camera into frame (utime, seq).
  proposals_t project(const CandidateMap& map, int64_t utime, int32_t seq, int32_t map_id,
                      const SE3& T_world_camera, ProjectionStats* stats) const;
  /// Projects the keyframes waiting for late proposals in map_id that are due at `utime`; forgets
  /// those too old to be due.
  void projectLateKeyframes(const CandidateMap& map, int32_t map_id, int64_t utime);

  std::map<int32_t, CandidateMap> maps_;
  std::vector<int32_t> recent_;  ///< map ids, most recently used last
  struct LastClustering {
    int64_t utime = 0;  ///< frame time
    size_t points = 0;  ///< the map's points then
  };
  std::map<int32_t, LastClustering> reclustered_;  ///< map id -> its last re-clustering
  int32_t next_candidate_id_ = 1;  ///< shared by the maps: ids are unique across maps
  CandidateMap empty_{options_};
  CameraModel camera_;
  bool have_camera_ = false;
  ProjectionStats last_;
  bool background_ = false;
  std::future<Clustering> job_;  ///< the clustering running on the worker thread (background)
  static constexpr size_t kUnproposedKept =
      64;                                    ///< frames without proposals remembered (the newest)
  static constexpr double kLateGiveUpS = 2;  ///< s past the delay after which a keyframe whose map
                                             ///< did not come back is forgotten (its frame is long
                                             ///< gone from the recognizer's buffer)
  std::map<int32_t, int64_t>
      unproposed_;  ///< seq -> utime of the latest frames that got no proposals
  int64_t last_pose_utime_ = 0;
  struct LateKeyframe {
    int64_t utime = 0;
    int32_t map_id = -1;
    SE3 T_world_camera;
  };
  std::map<int32_t, LateKeyframe> late_;  ///< seq -> keyframe waiting for its proposals
  std::vector<proposals_t> late_out_;
};

}  // namespace slamaware::proposals
