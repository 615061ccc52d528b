#include "procs/proposals/proposal_engine.h"

#include <algorithm>
#include <chrono>
#include <optional>

#include "common/bus/box_msg.h"
#include "common/bus/image_msg.h"
#include "common/thread_priority.h"

namespace slamaware::proposals {

CandidateMap& ProposalEngine::mapOf(int32_t map_id) {
  auto it = maps_.find(map_id);
  if (it == maps_.end())
    it = maps_.emplace(map_id, CandidateMap(options_, &next_candidate_id_)).first;
  recent_.erase(std::remove(recent_.begin(), recent_.end(), map_id), recent_.end());
  recent_.push_back(map_id);
  while (static_cast<int>(recent_.size()) > std::max(1, options_.max_maps)) {
    maps_.erase(recent_.front());
    reclustered_.erase(recent_.front());
    recent_.erase(recent_.begin());
  }
  return it->second;
}

const CandidateMap& ProposalEngine::map() const {
  return recent_.empty() ? empty_ : maps_.at(recent_.back());
}

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
  CandidateMap& map = mapOf(c.map_id);
  map.update(c.map_id, c.full, c.keyframe_id, keyframes, points);
  const size_t k = static_cast<size_t>(std::max(0, c.num_keyframes));
  if (c.kf_ids.size() == k && c.kf_x.size() == k && c.kf_y.size() == k && c.kf_z.size() == k)
    for (size_t i = 0; i < k; ++i)
      map.setKeyframeCentre(c.map_id, c.kf_ids[i],
                            Eigen::Vector3f(c.kf_x[i], c.kf_y[i], c.kf_z[i]));
  return true;
}

ProposalEngine::~ProposalEngine() {
  if (job_.valid()) job_.wait();
}

bool ProposalEngine::recluster(CandidateMap& map, const pose_t& pose) {
  // A growing map is clustered again at most every recluster_interval_s of frame time (the
  // message clock: lockstep replays stay deterministic), or sooner once it holds recluster_growth
  // times the points of its last clustering: a young map grows many times over in its first
  // frames, and candidates of a fraction of it miss most objects (a bounded number of extra
  // clusterings: the growth is geometric). In between, the last candidates are projected. A map's
  // first points are clustered at once, and a clock that goes back (a replay started again) is
  // due at once.
  const auto last = reclustered_.find(pose.map_id);
  const size_t points = map.points();
  const bool due =
      last == reclustered_.end() || pose.utime < last->second.utime ||
      static_cast<double>(pose.utime - last->second.utime) >= 1e6 * options_.recluster_interval_s ||
      (options_.recluster_growth > 1 &&
       static_cast<double>(points) >=
           options_.recluster_growth * static_cast<double>(last->second.points));
  if (!background_) {
    if (!due || !map.recluster(pose.utime)) return false;
    reclustered_[pose.map_id] = {pose.utime, points};
    return true;
  }
  bool taken = false;
  if (job_.valid() && job_.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
    Clustering done = job_.get();
    // Its map may have been dropped or started over (another map id) meanwhile.
    const auto it = maps_.find(done.map_id);
    taken = it != maps_.end() && it->second.adopt(std::move(done), pose.utime);
  }
  if (!job_.valid() && due) {
    if (std::optional<ClusterInput> input = map.takeClusterInput()) {
      reclustered_[pose.map_id] = {pose.utime, points};
      job_ = std::async(std::launch::async, [in = std::move(*input)] {
        enterBackground("the proposals' clustering");  // the frames' projection goes first
        return clusterMap(in);
      });
    }
  }
  return taken;
}

proposals_t ProposalEngine::project(const CandidateMap& map, int64_t utime, int32_t seq,
                                    int32_t map_id, const SE3& T_world_camera,
                                    ProjectionStats* stats) const {
  proposals_t m{};
  m.utime = utime;
  m.seq = seq;
  m.map_id = map_id;
  for (const auto& b :
       projectCandidates(map.candidates(), camera_, T_world_camera, options_, stats)) {
    m.boxes.push_back(boxMessage(b.x, b.y, b.w, b.h));
    m.candidate_ids.push_back(b.candidate_id);
    m.median_depth.push_back(b.median_depth);
    m.view_direction.push_back({b.view_direction.x(), b.view_direction.y(), b.view_direction.z()});
  }
  m.num_boxes = static_cast<int32_t>(m.boxes.size());
  return m;
}

void ProposalEngine::onKeyframe(const keyframe_t& k) {
  if (k.culled) {
    late_.erase(k.seq);
    return;
  }
  const auto it = unproposed_.find(k.seq);
  if (options_.late_keyframe_delay_s < 0 || it == unproposed_.end() || it->second != k.utime)
    return;
  const SE3 T_world_camera = se3FromArrays(k.position, k.orientation);
  if (!T_world_camera.matrix().allFinite()) return;
  late_[k.seq] = LateKeyframe{k.utime, k.map_id, T_world_camera};
}

std::vector<proposals_t> ProposalEngine::takeLateProposals() {
  std::vector<proposals_t> out;
  out.swap(late_out_);
  return out;
}

void ProposalEngine::projectLateKeyframes(const CandidateMap& map, int32_t map_id, int64_t utime) {
  const double delay_us = 1e6 * options_.late_keyframe_delay_s;
  for (auto it = late_.begin(); it != late_.end();) {
    const double age_us = static_cast<double>(utime - it->second.utime);
    if (it->second.map_id == map_id && age_us >= delay_us) {
      late_out_.push_back(
          project(map, it->second.utime, it->first, map_id, it->second.T_world_camera, nullptr));
      unproposed_.erase(
          it->first);  // it has its proposals now: later messages of the keyframe are moves
      it = late_.erase(it);
    } else if (age_us > delay_us + 1e6 * kLateGiveUpS) {
      it = late_.erase(
          it);  // its map did not come back in time: its frame is gone from the recognizer
    } else {
      ++it;
    }
  }
}

proposals_t ProposalEngine::onPose(const pose_t& pose, std::string* why, bool* reclustered) {
  proposals_t m{};
  m.utime = pose.utime;
  m.seq = pose.seq;
  m.map_id = pose.map_id;
  m.num_boxes = 0;
  last_ = ProjectionStats{};
  late_out_.clear();
  if (reclustered) *reclustered = false;
  if (pose.utime < last_pose_utime_) {  // a replay started again: earlier frames are other frames
    unproposed_.clear();
    late_.clear();
  }
  last_pose_utime_ = pose.utime;
  // A frame that gets no proposals here is remembered: a keyframe of it may get them late.
  const auto unproposed = [&] {
    unproposed_[pose.seq] = pose.utime;
    while (unproposed_.size() > kUnproposedKept) unproposed_.erase(unproposed_.begin());
    return m;
  };
  const bool located =
      pose.state == pose_t::STATE_TRACKING || pose.state == pose_t::STATE_RELOCALIZED;
  const SE3 T_world_camera = se3FromArrays(pose.position, pose.orientation);
  if (!T_world_camera.matrix().allFinite()) {
    *why = "SLAM_POSE seq " + std::to_string(pose.seq) + ": pose is not finite";
    return unproposed();
  }
  if (!located || !have_camera_) return unproposed();
  if (!maps_.count(pose.map_id)) return unproposed();  // no point of that map yet
  CandidateMap& map = mapOf(pose.map_id);
  map.addView(pose.map_id, T_world_camera);
  if (recluster(map, pose) && reclustered) *reclustered = true;
  projectLateKeyframes(map, pose.map_id, pose.utime);
  return project(map, pose.utime, pose.seq, pose.map_id, T_world_camera, &last_);
}

}  // namespace slamaware::proposals
