#include "procs/slam/slam_system.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <opencv2/imgproc.hpp>
#include <set>
#include <shared_mutex>

#include "common/serial_worker.h"
#include "procs/slam/depth/depth_filter.h"
#include "procs/slam/features/orb_extractor.h"
#include "procs/slam/map/map.h"
#include "procs/slam/mapping/local_mapper.h"
#include "procs/slam/tracking/tracker.h"

namespace slamaware::slam {

const char* poseStateName(PoseState s) {
  switch (s) {
    case PoseState::kInitializing:
      return "INITIALIZING";
    case PoseState::kTracking:
      return "TRACKING";
    case PoseState::kLost:
      return "LOST";
    case PoseState::kRelocalized:
      return "RELOCALIZED";
  }
  return "?";
}

SlamSystem::SlamSystem(const SlamOptions& options, bool lockstep, SlamThreadNice nice)
    : options_(options),
      lockstep_(lockstep),
      nice_(nice),
      extractor_(std::make_unique<OrbExtractor>(options.orb)),
      ids_(std::make_unique<IdSource>()) {}

SlamSystem::~SlamSystem() {
  // Workers first: they hold references into the maps.
  depth_worker_.reset();
  mapper_.reset();
}

bool SlamSystem::hasCamera() const { return intrinsics_ != nullptr; }

bool SlamSystem::setCamera(const CameraModel& camera) {
  if (intrinsics_ && camera == camera_) return false;
  const bool had = intrinsics_ != nullptr;
  camera_ = camera;
  intrinsics_ = std::make_shared<const Intrinsics>(camera.pinhole(), extractor_->pyramid());
  restart();
  return had;
}

void SlamSystem::restart() {
  depth_worker_.reset();
  mapper_.reset();
  tracker_ = std::make_unique<Tracker>(options_, *ids_);
  mapper_ = std::make_unique<LocalMapper>(options_, *ids_, !lockstep_, nice_.mapping);
  depth_ = std::make_unique<DepthFilter>(options_.depth, camera_.width(), camera_.height(),
                                         intrinsics_->fx, intrinsics_->fy, intrinsics_->cx,
                                         intrinsics_->cy);
  depth_worker_ =
      std::make_unique<SerialWorker>(options_.depth.threaded, "slam-depth", nice_.depth);
  {
    std::lock_guard<std::mutex> lock(finished_mutex_);
    depth_finished_.clear();
  }
  have_last_ = false;
  have_valid_ = false;
  last_state_ = PoseState::kInitializing;
  first_map_id_ = -1;
  last_full_map_id_ = -1;
  culled_for_depth_.clear();
  live_published_.clear();
}

SlamOutput SlamSystem::skipFrame(int64_t utime, int32_t seq) {
  SlamOutput out;
  out.has_pose = true;
  out.pose.utime = utime;
  out.pose.seq = seq;
  if (have_valid_) {
    out.pose.state = PoseState::kLost;
    out.pose.T_world_camera = last_valid_.T_world_camera;
    out.pose.map_id = last_valid_.map_id;
    out.pose.reference_keyframe_id = last_valid_.reference_keyframe_id;
    last_state_ = PoseState::kLost;
    ++stats_.frames_lost;
  }
  ++stats_.frames_unusable;
  return out;
}

void SlamSystem::postDepthWork(const TrackResult& r, const Frame& frame) {
  if (!options_.depth.enabled) return;
  const bool located = r.outcome == TrackOutcome::kTracked ||
                       r.outcome == TrackOutcome::kRelocalized ||
                       r.outcome == TrackOutcome::kNewMap;
  if (!located) return;
  // Real time: a filter that falls behind skips plain frames (never keyframes).
  if (!lockstep_ && r.new_keyframes.empty() &&
      depth_worker_->pending() > static_cast<size_t>(options_.depth.max_queue)) {
    ++stats_.depth_frames_skipped;
    return;
  }
  auto input = std::make_shared<DepthFrameInput>();
  input->utime = frame.utime;
  input->seq = frame.seq;
  input->map_id = r.map->id;
  input->located = true;
  input->grey = frame.grey;
  input->T_world_camera = frame.T_camera_world.inverse();
  input->culled_keyframes.swap(culled_for_depth_);
  {
    // Snapshot of keyframe poses now, so that the filter never reads the live map.
    std::shared_lock<std::shared_mutex> lock(r.map->mutex);
    for (const auto& [id, kf] : r.map->keyframes)
      input->keyframe_poses.push_back({id, kf->T_world_camera()});
    for (const auto& kf : r.new_keyframes) {
      DepthKeyframeInput k;
      k.id = kf->id;
      k.map_id = kf->map_id;
      k.utime = kf->utime;
      k.seq = kf->seq;
      k.grey = kf->grey;
      k.bgr = kf->bgr;
      k.T_world_camera = kf->T_world_camera();
      if (!kf->depthRange(&k.min_depth, &k.mean_depth)) continue;
      if (options_.depth.young_map_points > 0) {
        for (size_t i = 0; i < kf->points.size(); ++i) {
          const auto& p = kf->points[i];
          if (!p || p->bad) continue;
          const Eigen::Vector2d& px = kf->features->px[i];
          k.sparse.push_back({Eigen::Vector2i(static_cast<int>(std::lround(px.x())),
                                              static_cast<int>(std::lround(px.y()))),
                              (kf->T_camera_world * p->p_world).cast<float>()});
        }
      }
      input->new_keyframes.push_back(k);
    }
  }
  // (A new map brings two keyframes; both are seeded after this frame's updates, so the first is
  // updated from the next frame on, like every other keyframe.)
  depth_worker_->post([this, input]() {
    const std::vector<int64_t> finished = depth_->process(*input);
    if (finished.empty()) return;
    std::lock_guard<std::mutex> lock(finished_mutex_);
    depth_finished_.insert(depth_finished_.end(), finished.begin(), finished.end());
  });
}

SlamOutput SlamSystem::processFrame(int64_t utime, int32_t seq, const cv::Mat& bgr_in) {
  if (!intrinsics_) throw std::logic_error("SlamSystem::processFrame before setCamera");
  if (have_last_ && utime == last_utime_ && seq == last_seq_) {
    ++stats_.frames_duplicate;
    SlamOutput again;
    again.has_pose = true;
    again.pose = last_pose_;
    return again;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const bool continuous = !have_last_ || utime > last_utime_;
  SlamOutput out;
  if (!continuous) {
    ++stats_.discontinuities;
    out.events.push_back("time went from " + std::to_string(last_utime_) + " to " +
                         std::to_string(utime) + " us at seq " + std::to_string(seq) +
                         ": relocalising");
  }
  have_last_ = true;
  last_utime_ = utime;
  last_seq_ = seq;
  ++stats_.frames;

  Frame frame;
  frame.id = next_frame_id_++;
  frame.utime = utime;
  frame.seq = seq;
  frame.bgr = camera_.isDistorted() ? camera_.undistortImage(bgr_in) : bgr_in;
  cv::cvtColor(frame.bgr, frame.grey, cv::COLOR_BGR2GRAY);
  frame.features = std::make_shared<FrameFeatures>(extractor_->extract(frame.grey), intrinsics_);
  frame.resetMatches();
  stats_.extract_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const TrackResult r = tracker_->track(frame, continuous, mapper_->idle());
  stats_.track_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (!r.event.empty()) out.events.push_back(r.event);

  PoseOutput& pose = out.pose;
  out.has_pose = true;
  pose.utime = utime;
  pose.seq = seq;
  switch (r.outcome) {
    case TrackOutcome::kNoMap:
      pose.state = PoseState::kInitializing;
      break;
    case TrackOutcome::kLost:
      pose.state = have_valid_ ? PoseState::kLost : PoseState::kInitializing;
      if (have_valid_) {
        pose.T_world_camera = last_valid_.T_world_camera;
        pose.map_id = last_valid_.map_id;
        pose.reference_keyframe_id = last_valid_.reference_keyframe_id;
      }
      break;
    case TrackOutcome::kNewMap:
      pose.state = PoseState::kTracking;  // a new map id: its poses are unrelated to earlier ones
      if (first_map_id_ < 0)
        first_map_id_ = r.map->id;
      else
        ++stats_.reinitializations;
      break;
    case TrackOutcome::kTracked:
      pose.state = last_state_ == PoseState::kLost ? PoseState::kRelocalized : PoseState::kTracking;
      break;
    case TrackOutcome::kRelocalized:
      pose.state = PoseState::kRelocalized;
      ++stats_.relocalizations;
      break;
  }
  if (r.map && r.outcome != TrackOutcome::kLost) {
    pose.T_world_camera = r.T_camera_world.inverse();
    pose.map_id = r.map->id;
    pose.num_tracked = r.num_tracked;
    pose.reference_keyframe_id = r.reference_keyframe_id;
    last_valid_ = pose;
    have_valid_ = true;
    ++stats_.frames_located;
  } else if (have_valid_) {
    ++stats_.frames_lost;
  }
  last_state_ = pose.state;

  // The depth filter's snapshot of keyframe poses is taken before local mapping may move them.
  postDepthWork(r, frame);
  for (const auto& kf : r.new_keyframes) mapper_->insert(r.map, kf);
  if (lockstep_) {
    mapper_->waitIdle();
    depth_worker_->waitIdle();
  } else if (!options_.mapping.threaded) {
    mapper_->waitIdle();  // no thread: mapping runs here
  }
  // New keyframes are announced with this frame: in lockstep after mapping has linked them.
  collect(utime, seq, r.new_keyframes, &out);
  last_pose_ = out.pose;
  return out;
}

KeyframeOutput SlamSystem::describeKeyframe(const KeyFrame& kf) const {
  KeyframeOutput k;
  k.utime = kf.utime;
  k.seq = kf.seq;
  k.id = kf.id;
  k.map_id = kf.map_id;
  k.T_world_camera = kf.T_world_camera();
  k.num_points = kf.trackedPoints(1);
  for (const auto& [w, other] : kf.covisible())
    if (!other->bad) k.covisible.push_back({other->id, w});
  k.culled = kf.bad;
  return k;
}

std::shared_ptr<Map> SlamSystem::mapById(int map_id) const {
  for (const auto& m : tracker_->maps())
    if (m->id == map_id) return m;
  return nullptr;
}

void SlamSystem::appendPoints(const SemiDenseKeyframe& s, const SE3& T_world_camera,
                              CloudOutput* c) {
  const Eigen::Isometry3f T = T_world_camera.cast<float>();
  for (const auto& p : s.points) {
    CloudPoint q;
    q.p_world = T * p.p_camera;
    std::copy(p.rgb, p.rgb + 3, q.rgb);
    q.depth_std = p.depth_std;
    q.keyframe_id = s.id;
    c->points.push_back(q);
  }
  c->keyframe_centers.push_back({s.id, T.translation()});
}

CloudOutput SlamSystem::keyframeCloud(int64_t keyframe_id, int64_t utime, int32_t seq) const {
  return keyframeCloud(depth_->keyframe(keyframe_id), utime, seq);
}

CloudOutput SlamSystem::keyframeCloud(const SemiDenseKeyframe& s, int64_t utime,
                                      int32_t seq) const {
  CloudOutput c;
  c.utime = utime;
  c.seq = seq;
  c.keyframe_id = s.id;
  c.map_id = s.map_id;
  SE3 T_world_camera = s.T_world_camera;
  if (std::shared_ptr<Map> map = mapById(s.map_id)) {
    std::shared_lock<std::shared_mutex> lock(map->mutex);
    auto live = map->keyframes.find(s.id);
    if (live != map->keyframes.end()) T_world_camera = live->second->T_world_camera();
  }
  appendPoints(s, T_world_camera, &c);
  return c;
}

CloudOutput SlamSystem::fullCloud(const std::shared_ptr<Map>& map, int64_t utime,
                                  int32_t seq) const {
  CloudOutput c;
  c.utime = utime;
  c.seq = seq;
  c.map_id = map->id;
  c.full = true;
  const std::vector<SemiDenseKeyframe> kfs = depth_->mapKeyframes(map->id);
  std::shared_lock<std::shared_mutex> lock(map->mutex);
  std::set<int64_t> listed;
  for (const auto& s : kfs) {
    // Points move with their keyframe: use its current pose while it is in the map (a culled
    // keyframe keeps its last one).
    auto live = map->keyframes.find(s.id);
    appendPoints(
        s, live != map->keyframes.end() ? live->second->T_world_camera() : s.T_world_camera, &c);
    listed.insert(s.id);
  }
  for (const auto& [id, kf] : map->keyframes)
    if (!listed.count(id)) c.keyframe_centers.push_back({id, kf->center().cast<float>()});
  return c;
}

void SlamSystem::collect(int64_t utime, int32_t seq,
                         const std::vector<std::shared_ptr<KeyFrame>>& created, SlamOutput* out) {
  const MappingEvents events = mapper_->takeEvents();
  std::vector<std::shared_ptr<KeyFrame>> touched = created;
  touched.insert(touched.end(), events.moved.begin(), events.moved.end());
  std::set<int64_t> described;
  for (const auto& kf : touched) {
    if (kf->bad || !described.insert(kf->id).second) continue;
    std::shared_ptr<Map> map = mapById(kf->map_id);
    if (!map) continue;
    std::shared_lock<std::shared_mutex> lock(map->mutex);
    out->keyframes.push_back(describeKeyframe(*kf));
  }
  for (const auto& kf : events.culled) {
    KeyframeOutput k = describeKeyframe(*kf);
    k.culled = true;
    out->keyframes.push_back(k);
    // Its semi-dense points go too; consumers lose them with the next full map.
    culled_for_depth_.push_back(kf->id);
    live_published_.erase(kf->id);
  }

  std::vector<int64_t> finished;
  {
    std::lock_guard<std::mutex> lock(finished_mutex_);
    finished.swap(depth_finished_);
  }
  // A keyframe that dropped its map points (DepthFilter) lost points published before: its map
  // goes out whole instead (a full cloud replaces all that consumers hold of the map).
  std::set<int> maps_to_resend;
  for (int64_t id : finished) {
    live_published_.erase(id);
    const SemiDenseKeyframe s = depth_->keyframe(id);
    if (s.features_dropped)
      maps_to_resend.insert(s.map_id);
    else if (!s.points.empty())
      out->clouds.push_back(keyframeCloud(s, utime, seq));
  }
  for (int map_id : maps_to_resend) {
    if (std::shared_ptr<Map> m = mapById(map_id)) out->clouds.push_back(fullCloud(m, utime, seq));
  }

  std::shared_ptr<Map> map = tracker_->activeMap();
  if (!map || !options_.depth.enabled) return;
  publishLiveClouds(map->id, utime, seq, out);
  if (map->id != last_full_map_id_ || utime < last_full_utime_) {
    last_full_map_id_ = map->id;  // a new map (or a restarted clock) starts the period
    last_full_utime_ = utime;
  } else if (utime - last_full_utime_ >=
             static_cast<int64_t>(options_.output.full_map_period_s * 1e6)) {
    out->clouds.push_back(fullCloud(map, utime, seq));
    last_full_utime_ = utime;
  }
}

void SlamSystem::publishLiveClouds(int map_id, int64_t utime, int32_t seq, SlamOutput* out) {
  const double growth = options_.output.live_cloud_growth;
  if (growth <= 0) return;
  const auto min_points = static_cast<size_t>(std::max(1, options_.output.live_cloud_min_points));
  for (const auto& kf : depth_->liveKeyframes(map_id)) {
    // Published once its converged points (provisional ones included) number min_points, and again
    // whenever they have grown by `growth`; a young map's keyframe also at once, with its map
    // points (however few).
    auto& [published, any] = live_published_[kf.id];
    const size_t converged = kf.points - kf.from_features;
    bool due = false;
    if (converged >= min_points)
      due = published == 0 ||
            static_cast<double>(converged) >= (1.0 + growth) * static_cast<double>(published);
    else
      due = !any && kf.from_features > 0;
    if (!due) continue;
    any = true;
    if (converged >= min_points) published = converged;
    out->clouds.push_back(keyframeCloud(kf.id, utime, seq));
  }
}

SlamOutput SlamSystem::collectBackground(int64_t utime, int32_t seq) {
  SlamOutput out;
  if (tracker_) collect(utime, seq, {}, &out);
  return out;
}

void SlamSystem::flush() {
  if (mapper_) mapper_->waitIdle();
  if (depth_worker_) depth_worker_->waitIdle();
}

SlamStats SlamSystem::stats() const {
  SlamStats s = stats_;
  s.state = poseStateName(last_state_);
  if (tracker_) {
    s.maps = static_cast<int64_t>(tracker_->maps().size());
    if (auto map = tracker_->activeMap()) {
      std::shared_lock<std::shared_mutex> lock(map->mutex);
      s.map_id = map->id;
      s.keyframes = static_cast<int64_t>(map->keyframes.size());
      s.points = static_cast<int64_t>(map->points.size());
    }
  }
  if (mapper_) {
    s.bundle_adjustments = mapper_->bundleAdjustments();
    s.keyframes_culled = mapper_->culledKeyFrames();
    s.mapping_ms = mapper_->mappingMicros() / 1000.0;
    s.bundle_adjustment_ms = mapper_->bundleAdjustmentMicros() / 1000.0;
  }
  if (depth_) {
    const DepthFilterStats d = depth_->stats();
    s.depth_seeds = d.active_seeds;
    s.depth_points = d.points;
    s.depth_update_ms = d.last_update_ms;
    s.depth_updates = d.calls;
  }
  return s;
}

}  // namespace slamaware::slam
