#include "procs/proposals/proposal_engine.h"

#include "common/bus/image_msg.h"

namespace slamaware {

bool ProposalEngine::onCameraInfo(const camera_info_t& info, std::string* why) {
  CameraModel c;
  if (!cameraFromMessage(info, &c, why)) return false;
  camera_ = c;
  have_camera_ = true;
  return true;
}

bool ProposalEngine::onMap(const point_cloud_t& c, std::string* why) {
  const size_t n = static_cast<size_t>(std::max(0, c.num_points));
  if (c.x.size() != n || c.y.size() != n || c.z.size() != n || c.r.size() != n || c.g.size() != n ||
      c.b.size() != n || c.keyframe_ids.size() != n || c.depth_std.size() != n) {
    *why = "SLAM_MAP seq " + std::to_string(c.seq) + ": arrays do not match num_points";
    return false;
  }
  std::vector<MapPoint> points;
  std::vector<int32_t> keyframes;
  points.reserve(n);
  keyframes.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    if (options_.max_depth_std > 0 && !(c.depth_std[i] <= options_.max_depth_std)) continue;
    points.push_back({Eigen::Vector3f(c.x[i], c.y[i], c.z[i]), static_cast<uint8_t>(c.r[i]),
                      static_cast<uint8_t>(c.g[i]), static_cast<uint8_t>(c.b[i])});
    keyframes.push_back(c.keyframe_ids[i]);
  }
  map_.update(c.map_id, c.full, c.keyframe_id, keyframes, points);
  return true;
}

proposals_t ProposalEngine::onPose(const pose_t& pose, std::string* why, bool* reclustered) {
  proposals_t m{};
  m.utime = pose.utime;
  m.seq = pose.seq;
  m.map_id = pose.map_id;
  m.num_boxes = 0;
  last_ = ProjectionStats{};
  if (reclustered) *reclustered = false;
  const bool located = pose.state == pose_t::STATE_TRACKING || pose.state == pose_t::STATE_RELOCALIZED;
  const SE3 T_wc = se3FromArrays(pose.position, pose.orientation);
  if (!T_wc.matrix().allFinite()) {
    *why = "SLAM_POSE seq " + std::to_string(pose.seq) + ": pose is not finite";
    return m;
  }
  if (!located || !have_camera_) return m;
  const bool ran = map_.recluster(T_wc.translation().cast<float>());
  if (reclustered) *reclustered = ran;
  if (pose.map_id != map_.mapId()) return m;
  for (const auto& b : projectCandidates(map_.candidates(), camera_, T_wc, options_, &last_)) {
    box_t bx{};
    bx.x = b.x;
    bx.y = b.y;
    bx.w = b.w;
    bx.h = b.h;
    m.boxes.push_back(bx);
    m.candidate_ids.push_back(b.candidate_id);
    m.median_depth.push_back(b.median_depth);
  }
  m.num_boxes = static_cast<int32_t>(m.boxes.size());
  return m;
}

}  // namespace slamaware
