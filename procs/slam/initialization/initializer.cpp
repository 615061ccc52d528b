#include "procs/slam/initialization/initializer.h"

#include <algorithm>
#include <mutex>
#include <shared_mutex>

#include "procs/slam/geometry/two_view.h"
#include "procs/slam/matching/matcher.h"
#include "procs/slam/optimization/bundle_adjustment.h"

namespace slamaware::slam {

namespace {
constexpr int kInitMatchDistance = 64;  // bits: looser than tracking, views may be far apart
}

std::shared_ptr<Map> Initializer::tryInitialize(Frame& frame, int map_id, IdSource& ids,
                                                std::string* why) {
  const int min_features = options_.init.min_matches;
  if (frame.size() < min_features) {
    *why = "only " + std::to_string(frame.size()) + " features";
    reference_.reset();
    return nullptr;
  }
  if (!reference_ || frame.utime - reference_->utime > options_.init.max_reference_age_s * 1e6 ||
      frame.utime <= reference_->utime) {
    reference_ = frame;
    attempts_ = 0;
    *why = "new reference frame";
    return nullptr;
  }
  const Frame& ref = *reference_;
  std::vector<int> all(ref.size());
  for (int i = 0; i < ref.size(); ++i) all[i] = i;
  const Matches matches = matchBruteForce(*ref.features, all, *frame.features,
                                          options_.init.match_ratio, kInitMatchDistance, true);
  if (static_cast<int>(matches.size()) < options_.init.min_matches) {
    *why = "only " + std::to_string(matches.size()) + " matches to the reference; new reference";
    reference_ = frame;
    attempts_ = 0;
    return nullptr;
  }
  std::vector<Eigen::Vector2d> p_ref, p_cur;
  for (const auto& [i, j] : matches) {
    p_ref.push_back(ref.features->px[i]);
    p_cur.push_back(frame.features->px[j]);
  }
  const uint64_t seed = options_.seed * 1000003ull + static_cast<uint64_t>(frame.id);
  const TwoViewResult tv =
      reconstructTwoView(p_ref, p_cur, frame.features->intrinsics->K(), options_.init, seed);
  ++attempts_;
  if (!tv.ok) {
    *why = std::string("two-view (") + tv.model + "): " + tv.reason;
    return nullptr;
  }
  std::shared_ptr<Map> map = buildMap(ref, frame, tv, matches, map_id, ids, why);
  if (map) reference_.reset();
  return map;
}

std::shared_ptr<Map> Initializer::buildMap(const Frame& reference, Frame& frame,
                                           const TwoViewResult& tv, const Matches& matches,
                                           int map_id, IdSource& ids, std::string* why) {
  auto map = std::make_shared<Map>(map_id);
  std::unique_lock<std::shared_mutex> lock(map->mutex);
  Frame ref = reference;
  ref.resetMatches();
  ref.T_camera_world = SE3::Identity();
  ref.has_pose = true;
  frame.resetMatches();
  frame.T_camera_world = tv.T_cur_ref;
  frame.has_pose = true;
  auto kf0 = std::make_shared<KeyFrame>(ids.next_keyframe++, map_id, ref);
  auto kf1 = std::make_shared<KeyFrame>(ids.next_keyframe++, map_id, frame);
  map->addKeyFrame(kf0);
  map->addKeyFrame(kf1);
  for (size_t k = 0; k < matches.size(); ++k) {
    if (!tv.triangulated[k]) continue;
    const auto [i, j] = matches[k];
    auto p = std::make_shared<MapPoint>(ids.next_point++, map_id, tv.p_ref[k], kf0);
    p->addObservation(kf0, i);
    p->addObservation(kf1, j);
    kf0->points[i] = p;
    kf1->points[j] = p;
    p->computeDistinctiveDescriptor();
    p->updateNormalAndDepth();
    map->addPoint(p);
  }

  // Full bundle adjustment of the two-view map, the first keyframe fixed.
  const Intrinsics& in = *frame.features->intrinsics;
  BaProblem ba;
  ba.fx = in.fx;
  ba.fy = in.fy;
  ba.cx = in.cx;
  ba.cy = in.cy;
  ba.cameras = {{kf0->T_camera_world, true}, {kf1->T_camera_world, false}};
  std::vector<std::shared_ptr<MapPoint>> pts;
  for (const auto& [id, p] : map->points) {
    const int index = static_cast<int>(ba.points.size());
    ba.points.push_back({p->p_world, false});
    pts.push_back(p);
    int cam = 0;
    for (const auto& [kf_id, obs] : p->observations) {
      const int level = obs.keyframe->features->level(obs.feature);
      ba.observations.push_back(
          {cam++, index, obs.keyframe->features->px[obs.feature], in.pyramid.inv_sigma2[level]});
    }
  }
  BaOptions bo;
  bo.iterations = options_.init.ba_iterations;
  bundleAdjust(&ba, bo);
  kf1->T_camera_world = ba.cameras[1].T_camera_world;
  for (size_t k = 0; k < pts.size(); ++k) pts[k]->p_world = ba.points[k].p_world;
  // Points that bundle adjustment could not explain are dropped.
  for (const auto& o : ba.observations) {
    bool front = true;
    if (observationChi2(ba, o, &front) > 5.991 || !front) {
      if (!pts[o.point]->bad) map->erasePoint(pts[o.point]);
    }
  }

  const double median_depth = kf0->medianDepth();
  const int tracked = kf1->trackedPoints(1);
  if (median_depth <= 0 || tracked < options_.init.min_triangulated) {
    *why = "after bundle adjustment: median depth " + std::to_string(median_depth) + ", " +
           std::to_string(tracked) + " points";
    return nullptr;
  }
  // Monocular scale is free: the map unit is the median scene depth of the first keyframe.
  const double s = 1.0 / median_depth;
  kf1->T_camera_world.translation() *= s;
  for (auto& [id, p] : map->points) {
    p->p_world *= s;
    p->updateNormalAndDepth();
  }
  kf0->updateConnections(options_.mapping.min_covisibility_weight);
  kf1->updateConnections(options_.mapping.min_covisibility_weight);

  frame.T_camera_world = kf1->T_camera_world;
  frame.points = kf1->points;
  frame.outlier.assign(frame.size(), false);
  frame.reference = kf1;
  *why = std::string("map ") + std::to_string(map_id) + " from frames " +
         std::to_string(reference.seq) + " and " + std::to_string(frame.seq) + " (" + tv.model +
         ", " + std::to_string(map->points.size()) + " points, parallax " +
         std::to_string(tv.parallax_deg).substr(0, 4) + " deg)";
  return map;
}

}  // namespace slamaware::slam
