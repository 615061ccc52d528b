#include "procs/slam/tracking/tracker.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <mutex>
#include <set>
#include <shared_mutex>

#include "procs/slam/geometry/pnp.h"
#include "procs/slam/optimization/pose_optimizer.h"

namespace slamaware::slam {

namespace {

constexpr int kMinPoseInliers =
    10;  // fewer inliers after a pose optimisation: the pose is not trusted

// Collects the frame's matched points as pose-optimisation observations.
struct FrameObservations {
  std::vector<PoseObservation> obs;
  std::vector<int> feature;
};

FrameObservations gather(const Frame& frame) {
  FrameObservations g;
  const ScalePyramid& pyr = frame.features->intrinsics->pyramid;
  for (int i = 0; i < frame.size(); ++i) {
    const auto& p = frame.points[i];
    if (!p || p->bad) continue;
    g.obs.push_back(
        {p->p_world, frame.features->px[i], pyr.inv_sigma2[frame.features->level(i)], false});
    g.feature.push_back(i);
  }
  return g;
}

}  // namespace

Tracker::Tracker(const SlamOptions& options, IdSource& ids)
    : options_(options), ids_(ids), initializer_(options) {}

void Tracker::reset() {
  state_ = State::kNoMap;
  maps_.clear();
  map_.reset();
  last_frame_.reset();
  reference_kf_.reset();
  velocity_valid_ = false;
  initializer_.reset();
}

uint64_t Tracker::rngSeed(const Frame& frame, int salt) const {
  return options_.seed * 0x9E3779B97F4A7C15ull + static_cast<uint64_t>(frame.id) * 131 +
         static_cast<uint64_t>(salt);
}

int Tracker::optimizeFramePose(Frame& frame, bool drop_outliers) {
  FrameObservations g = gather(frame);
  if (g.obs.size() < 4) return 0;
  const Intrinsics& in = *frame.features->intrinsics;
  const int inliers = optimizePose(&frame.T_camera_world, g.obs, in.fx, in.fy, in.cx, in.cy);
  for (size_t k = 0; k < g.obs.size(); ++k) {
    const int i = g.feature[k];
    frame.outlier[i] = g.obs[k].outlier;
    if (drop_outliers && g.obs[k].outlier) {
      frame.points[i] = nullptr;
      frame.outlier[i] = false;
    }
  }
  return inliers;
}

void Tracker::updateVelocity(const Frame& frame) {
  if (!last_frame_ || !last_frame_->has_pose) {
    velocity_valid_ = false;
    return;
  }
  const double dt = (frame.utime - last_frame_->utime) * 1e-6;
  if (dt <= 0) {
    velocity_valid_ = false;
    return;
  }
  velocity_per_s_ = logSE3(frame.T_camera_world * last_frame_->T_camera_world.inverse()) / dt;
  velocity_valid_ = true;
}

bool Tracker::trackMotionModel(Frame& frame) {
  if (!velocity_valid_ || !last_frame_) return false;
  const double dt = (frame.utime - last_frame_->utime) * 1e-6;
  if (dt <= 0 || dt > options_.tracking.max_velocity_age_s) return false;
  // Points of the previous frame may have been fused into others since.
  for (auto& p : last_frame_->points) p = MapPoint::resolve(p);
  frame.T_camera_world = expSE3(velocity_per_s_ * dt) * last_frame_->T_camera_world;
  frame.resetMatches();
  const double r = options_.tracking.motion_search_radius_px;
  int n = searchByProjection(frame, *last_frame_, r);
  if (n < options_.tracking.min_motion_matches) {
    frame.resetMatches();
    n = searchByProjection(frame, *last_frame_, 2 * r);
  }
  if (n < options_.tracking.min_motion_matches) return false;
  return optimizeFramePose(frame, true) >= kMinPoseInliers;
}

Matches Tracker::matchKeyFrame(const Frame& frame, const KeyFrame& kf) const {
  std::vector<int> with_points;
  for (int i = 0; i < kf.size(); ++i)
    if (kf.points[i] && !kf.points[i]->bad) with_points.push_back(i);
  return matchBruteForce(*kf.features, with_points, *frame.features,
                         options_.tracking.reference_match_ratio, kMatchDistanceHigh, true);
}

PnpResult Tracker::pnpFromMatches(const Frame& frame, const KeyFrame& kf, const Matches& matches,
                                  int salt) const {
  std::vector<Eigen::Vector3d> pw;
  std::vector<Eigen::Vector2d> px;
  std::vector<double> sigma2;
  const Intrinsics& in = *frame.features->intrinsics;
  for (const auto& [i, j] : matches) {
    pw.push_back(kf.points[i]->p_world);
    px.push_back(frame.features->px[j]);
    sigma2.push_back(in.pyramid.sigma2[frame.features->level(j)]);
  }
  PnpOptions po;
  po.iterations = options_.reloc.pnp_iterations;
  po.chi2 = options_.reloc.pnp_threshold_px;
  po.min_inliers = options_.reloc.min_pnp_inliers;
  return solvePnpRansac(pw, px, sigma2, in.fx, in.fy, in.cx, in.cy, po, rngSeed(frame, salt));
}

bool Tracker::trackReferenceKeyFrame(Frame& frame) {
  std::shared_ptr<KeyFrame> kf = reference_kf_;
  if (!kf || kf->bad) kf = map_->keyframes.empty() ? nullptr : map_->keyframes.rbegin()->second;
  if (!kf) return false;
  const Matches matches = matchKeyFrame(frame, *kf);
  if (matches.size() < 15) return false;
  frame.resetMatches();
  for (const auto& [i, j] : matches) frame.points[j] = kf->points[i];
  // Views far apart (slow frame rates) defeat a local optimisation from the last pose: start from
  // PnP when it finds a pose.
  const PnpResult pnp = pnpFromMatches(frame, *kf, matches, 1);
  if (pnp.ok)
    frame.T_camera_world = pnp.T_camera_world;
  else if (last_frame_)
    frame.T_camera_world = last_frame_->T_camera_world;
  else
    return false;
  frame.reference = kf;
  return optimizeFramePose(frame, true) >= kMinPoseInliers;
}

bool Tracker::trackLocalMap(Frame& frame, bool just_relocalized, int* inliers_out) {
  *inliers_out = 0;
  // Local keyframes: those observing the frame's points, most shared first, plus a covisible
  // neighbour of each.
  std::map<int64_t, std::pair<int, std::shared_ptr<KeyFrame>>> counts;
  for (int i = 0; i < frame.size(); ++i) {
    auto& p = frame.points[i];
    if (!p) continue;
    if (p->bad) {
      p = nullptr;
      continue;
    }
    for (const auto& [kf_id, obs] : p->observations) {
      auto& c = counts[kf_id];
      ++c.first;
      c.second = obs.keyframe;
    }
  }
  std::vector<std::pair<int, std::shared_ptr<KeyFrame>>> ranked;
  for (const auto& [id, c] : counts)
    if (!c.second->bad) ranked.push_back(c);
  // The frame's own reference keyframe (the one it was matched against) may have no
  // observations yet if local mapping has not processed it.
  if (frame.reference && !frame.reference->bad && !counts.count(frame.reference->id))
    ranked.push_back({0, frame.reference});
  if (reference_kf_ && !reference_kf_->bad && reference_kf_->map_id == map_->id &&
      !counts.count(reference_kf_->id) && reference_kf_ != frame.reference)
    ranked.push_back({0, reference_kf_});
  if (ranked.empty()) return false;
  std::stable_sort(ranked.begin(), ranked.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<std::shared_ptr<KeyFrame>> local;
  std::set<int64_t> included;
  for (const auto& [w, kf] : ranked) {
    if (static_cast<int>(local.size()) >= options_.tracking.max_local_keyframes) break;
    if (included.insert(kf->id).second) local.push_back(kf);
  }
  if (ranked.front().first > 0) frame.reference = ranked.front().second;
  const size_t direct = local.size();
  for (size_t k = 0;
       k < direct && static_cast<int>(local.size()) < options_.tracking.max_local_keyframes; ++k) {
    for (const auto& nb : local[k]->bestCovisible(10)) {
      if (included.insert(nb->id).second) {
        local.push_back(nb);
        break;
      }
    }
  }

  // Local points not yet matched, projected into the frame.
  for (int i = 0; i < frame.size(); ++i) {
    if (!frame.points[i]) continue;
    frame.points[i]->last_seen_frame = frame.id;
    ++frame.points[i]->visible;
  }
  std::vector<std::shared_ptr<MapPoint>> candidates;
  std::vector<Projection> projections;
  const Intrinsics& in = *frame.features->intrinsics;
  const Eigen::Vector3d center = frame.center();
  for (const auto& kf : local) {
    for (const auto& p : kf->points) {
      if (!p || p->bad || p->local_map_frame == frame.id) continue;
      p->local_map_frame = frame.id;
      if (p->last_seen_frame == frame.id) continue;
      Projection pr;
      if (!projectMapPoint(*p, frame.T_camera_world, center, in, &pr)) continue;
      ++p->visible;
      candidates.push_back(p);
      projections.push_back(pr);
    }
  }
  const double radius = just_relocalized ? 5.0 : options_.tracking.local_search_radius;
  searchLocalPoints(frame, candidates, projections, radius, 0.8);

  const int inliers = optimizeFramePose(frame, true);
  for (int i = 0; i < frame.size(); ++i)
    if (frame.points[i]) ++frame.points[i]->found;
  *inliers_out = inliers;
  const int needed =
      just_relocalized ? options_.tracking.min_inliers_relocalized : options_.tracking.min_inliers;
  return inliers >= needed;
}

bool Tracker::relocalizeAgainst(Frame& frame, const std::shared_ptr<KeyFrame>& kf) {
  const Matches matches = matchKeyFrame(frame, *kf);
  if (static_cast<int>(matches.size()) < options_.reloc.min_matches) return false;
  const PnpResult pnp = pnpFromMatches(frame, *kf, matches, 2);
  if (!pnp.ok) return false;
  frame.resetMatches();
  for (size_t k = 0; k < matches.size(); ++k)
    if (pnp.inliers[k]) frame.points[matches[k].second] = kf->points[matches[k].first];
  frame.T_camera_world = pnp.T_camera_world;
  int inliers = optimizeFramePose(frame, true);
  if (inliers < kMinPoseInliers) return false;
  // Few inliers: look for more of the keyframe's points by projection (ORB-SLAM's second pass).
  if (inliers < 50) {
    const int added = searchKeyFramePoints(frame, *kf, 10, kMatchDistanceHigh);
    if (inliers + added >= 50) inliers = optimizeFramePose(frame, true);
  }
  frame.reference = kf;
  return inliers >= options_.tracking.min_inliers;
}

bool Tracker::relocalize(Frame& frame, std::shared_ptr<KeyFrame>* matched) {
  const cv::Mat thumb = KeyFrame::makeThumbnail(frame.grey);
  struct Candidate {
    double score;
    std::shared_ptr<Map> map;
    std::shared_ptr<KeyFrame> kf;
  };
  std::vector<Candidate> candidates;
  std::vector<std::shared_ptr<Map>> order;
  if (map_) order.push_back(map_);
  if (options_.reloc.search_all_maps)
    for (auto it = maps_.rbegin(); it != maps_.rend(); ++it)
      if (*it != map_) order.push_back(*it);
  for (const auto& m : order) {
    std::shared_lock<std::shared_mutex> lock(m->mutex);
    for (const auto& [id, kf] : m->keyframes)
      candidates.push_back({KeyFrame::thumbnailSimilarity(thumb, kf->thumbnail), m, kf});
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
  if (static_cast<int>(candidates.size()) > options_.reloc.candidates)
    candidates.resize(options_.reloc.candidates);
  for (const auto& c : candidates) {
    std::shared_lock<std::shared_mutex> lock(c.map->mutex);
    if (c.kf->bad) continue;
    if (relocalizeAgainst(frame, c.kf)) {
      *matched = c.kf;
      return true;
    }
  }
  frame.resetMatches();
  return false;
}

bool Tracker::needNewKeyFrame(const Frame& frame, int inliers, bool mapper_idle) const {
  if (!reference_kf_) return true;
  if (inliers <= options_.tracking.min_keyframe_points) return false;
  const TrackingOptions& o = options_.tracking;
  const int min_obs = map_->keyframes.size() <= 2 ? 2 : 3;
  const int ref_points = reference_kf_->trackedPoints(min_obs);
  // ORB-SLAM's test (fewer points than the reference keyframe tracks), gated by how far the
  // camera moved: a keyframe every few frames of a slow camera adds cost and no parallax.
  const bool weak = inliers < o.weak_tracking_ratio * ref_points;
  const bool fewer = inliers < o.keyframe_ratio * ref_points;
  // Parallax is measured from the last keyframe made and, when the frame tracks against an older
  // one (the reference: the keyframe sharing the most points with it), from that one too: a camera
  // going over ground it has mapped already gains nothing from a keyframe beside the one it tracks
  // against.
  const double depth = reference_kf_->medianDepth();
  double from_keyframes = (frame.center() - last_keyframe_center_).norm();
  if (reference_kf_->id != last_keyframe_id_)
    from_keyframes = std::min(from_keyframes, (frame.center() - reference_kf_->center()).norm());
  const bool moved = depth > 0 && from_keyframes >= o.min_keyframe_baseline * depth;
  const bool waited = frame.utime - last_keyframe_utime_ >= o.max_keyframe_interval_s * 1e6;
  if (weak) return true;
  if (!(fewer && mapper_idle && (moved || waited))) return false;
  // A frame whose tracked points local mapping would find redundant (seen by three other
  // keyframes at its scale) would only replace keyframes that culling then removes: on ground
  // mapped before this churns the map (new keyframes, old ones and their points culled) without
  // adding to it.
  return !redundantView(frame.points, *frame.features, options_.mapping.keyframe_redundancy);
}

std::shared_ptr<KeyFrame> Tracker::createKeyFrame(Frame& frame) {
  std::unique_lock<std::shared_mutex> lock(map_->mutex);
  auto kf = std::make_shared<KeyFrame>(ids_.next_keyframe++, map_->id, frame);
  map_->addKeyFrame(kf);
  reference_kf_ = kf;
  frame.reference = kf;
  last_keyframe_utime_ = frame.utime;
  last_keyframe_center_ = frame.center();
  last_keyframe_id_ = kf->id;
  return kf;
}

TrackResult Tracker::initialize(Frame& frame, bool after_loss) {
  TrackResult r;
  r.outcome = after_loss ? TrackOutcome::kLost : TrackOutcome::kNoMap;
  std::string why;
  const int map_id = ids_.next_map.load();
  std::shared_ptr<Map> map = initializer_.tryInitialize(frame, map_id, ids_, &why);
  if (!map) {
    spdlog::debug("seq {}: no initialisation: {}", frame.seq, why);
    return r;
  }
  ++ids_.next_map;
  maps_.push_back(map);
  map_ = map;
  state_ = State::kTracking;
  std::shared_lock<std::shared_mutex> lock(map->mutex);
  for (const auto& [id, kf] : map->keyframes) r.new_keyframes.push_back(kf);
  reference_kf_ = r.new_keyframes.back();
  last_keyframe_utime_ = frame.utime;
  last_keyframe_center_ = frame.center();
  last_keyframe_id_ = reference_kf_->id;
  // Velocity from the two initial views.
  const auto& kf0 = r.new_keyframes.front();
  const double dt = (frame.utime - kf0->utime) * 1e-6;
  velocity_valid_ = dt > 0 && dt <= options_.tracking.max_velocity_age_s;
  if (velocity_valid_)
    velocity_per_s_ = logSE3(frame.T_camera_world * kf0->T_camera_world.inverse()) / dt;
  frame.has_pose = true;
  last_frame_ = frame;
  r.outcome = TrackOutcome::kNewMap;
  r.T_camera_world = frame.T_camera_world;
  r.map = map;
  r.num_tracked = frame.countInliers();
  r.reference_keyframe_id = reference_kf_->id;
  r.event = "initialised " + why;
  return r;
}

TrackResult Tracker::track(Frame& frame, bool continuous, bool mapper_idle) {
  frame.resetMatches();
  if (state_ == State::kNoMap) return initialize(frame, false);

  TrackResult r;
  if (!continuous && state_ == State::kTracking) {
    state_ = State::kLost;
    lost_since_utime_ = frame.utime;
    velocity_valid_ = false;
    r.event = "input discontinuity at seq " + std::to_string(frame.seq) + ": relocalising";
  }
  bool located = false;
  int inliers = 0;
  if (state_ == State::kTracking) {
    std::shared_lock<std::shared_mutex> lock(map_->mutex);
    located = trackMotionModel(frame) || trackReferenceKeyFrame(frame);
    if (located) located = trackLocalMap(frame, false, &inliers);
    if (located) {
      updateVelocity(frame);
      r.outcome = TrackOutcome::kTracked;
    } else {
      state_ = State::kLost;
      lost_since_utime_ = frame.utime;
      velocity_valid_ = false;
      r.event =
          "lost at seq " + std::to_string(frame.seq) + " (" + std::to_string(inliers) + " inliers)";
    }
  }
  if (!located && state_ == State::kLost) {
    frame.resetMatches();
    std::shared_ptr<KeyFrame> kf;
    if (relocalize(frame, &kf)) {
      for (const auto& m : maps_)
        if (m->id == kf->map_id) map_ = m;
      std::shared_lock<std::shared_mutex> lock(map_->mutex);
      reference_kf_ = kf;
      last_keyframe_center_ = kf->center();  // the keyframe policy's baseline, in this map
      last_keyframe_id_ = kf->id;
      located = trackLocalMap(frame, true, &inliers);
    }
    if (located) {
      state_ = State::kTracking;
      velocity_valid_ = false;
      initializer_.reset();
      r.outcome = TrackOutcome::kRelocalized;
      r.event = "relocalised at seq " + std::to_string(frame.seq) + " in map " +
                std::to_string(map_->id) + " against keyframe " + std::to_string(kf->id) + " (" +
                std::to_string(inliers) + " inliers)";
    } else {
      frame.resetMatches();
      const double lost_s = (frame.utime - lost_since_utime_) * 1e-6;
      if (frame.utime < lost_since_utime_) lost_since_utime_ = frame.utime;  // time went backwards
      if (lost_s >= options_.reloc.reinit_after_s) {
        TrackResult init = initialize(frame, true);
        if (init.outcome == TrackOutcome::kNewMap) return init;
      } else if (!initializer_.hasReference()) {
        // Remember this frame as the reference of a possible new map.
        std::string why;
        initializer_.tryInitialize(frame, ids_.next_map.load(), ids_, &why);
      }
      r.outcome = TrackOutcome::kLost;
      return r;
    }
  }

  frame.has_pose = true;
  if (frame.reference && !frame.reference->bad) reference_kf_ = frame.reference;
  r.T_camera_world = frame.T_camera_world;
  r.map = map_;
  r.num_tracked = inliers;
  bool make_keyframe = false;
  {
    std::shared_lock<std::shared_mutex> lock(map_->mutex);
    make_keyframe = needNewKeyFrame(frame, inliers, mapper_idle);
  }
  if (make_keyframe) r.new_keyframes.push_back(createKeyFrame(frame));
  r.reference_keyframe_id = reference_kf_ ? reference_kf_->id : -1;
  last_frame_ = frame;
  return r;
}

}  // namespace slamaware::slam
