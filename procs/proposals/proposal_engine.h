#pragma once
// The proposals stage without the bus: CAMERA_INFO, SLAM_MAP and SLAM_POSE messages in, one
// PROPOSALS message per pose out. The node feeds it from LCM; the evaluator feeds it from a
// recorded log to re-run proposals with other options.
#include <map>
#include <string>
#include <vector>

#include "common/camera_model.h"
#include "procs/proposals/candidate_map.h"
#include "procs/proposals/projector.h"
#include "slamaware/camera_info_t.hpp"
#include "slamaware/point_cloud_t.hpp"
#include "slamaware/pose_t.hpp"
#include "slamaware/proposals_t.hpp"

namespace slamaware {

class ProposalEngine {
 public:
  explicit ProposalEngine(const ProposalOptions& options) : options_(options) {}

  /// False (and *why naming the message) for a camera that cannot be used.
  bool onCameraInfo(const camera_info_t& info, std::string* why);
  /// False (and *why) for a cloud whose arrays disagree with num_points.
  bool onMap(const point_cloud_t& cloud, std::string* why);
  /// The proposals of one frame: empty when the frame is not localised, its pose is not finite
  /// (*why is set), no camera is known yet, or nothing is in view. Re-clusters first when the
  /// map changed (*reclustered = true).
  proposals_t onPose(const pose_t& pose, std::string* why, bool* reclustered = nullptr);

  /// The candidates of the map the last pose was in (SLAM may go back to an older map: the
  /// `max_maps` most recently used maps are kept).
  const CandidateMap& map() const;
  const ProjectionStats& lastProjection() const { return last_; }

 private:
  ProposalOptions options_;
  CandidateMap& mapOf(int32_t map_id);

  std::map<int32_t, CandidateMap> maps_;
  std::vector<int32_t> recent_;  ///< map ids, most recently used last
  std::map<int32_t, int64_t> reclustered_utime_;  ///< map id -> frame time of its last re-clustering
  int32_t next_candidate_id_ = 1;  ///< shared by the maps: ids are unique across maps
  CandidateMap empty_{options_};
  CameraModel camera_;
  bool have_camera_ = false;
  ProjectionStats last_;
};

}  // namespace slamaware
