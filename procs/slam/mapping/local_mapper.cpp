#include "procs/slam/mapping/local_mapper.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>
#include <shared_mutex>

#include "common/thread_priority.h"
#include "procs/slam/geometry/triangulation.h"
#include "procs/slam/matching/matcher.h"
#include "procs/slam/optimization/bundle_adjustment.h"

namespace slamaware::slam {

LocalMapper::LocalMapper(const SlamOptions& options, IdSource& ids, bool allow_abort, int nice)
    : options_(options),
      ids_(ids),
      threaded_(options.mapping.threaded),
      allow_abort_(allow_abort),
      nice_(nice) {
  if (threaded_) thread_ = std::thread([this] { run(); });
}

LocalMapper::~LocalMapper() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
    abort_ba_ = true;
  }
  work_cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void LocalMapper::insert(const std::shared_ptr<Map>& map, const std::shared_ptr<KeyFrame>& kf) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back({map, kf});
    if (allow_abort_ && busy_) abort_ba_ = true;
  }
  work_cv_.notify_one();
}

bool LocalMapper::idle() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return queue_.empty() && !busy_;
}

void LocalMapper::waitIdle() {
  if (!threaded_) {
    while (true) {
      Job job;
      bool more = false;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (queue_.empty()) return;
        job = queue_.front();
        queue_.pop_front();
        more = !queue_.empty();
      }
      process(job, more);
    }
  }
  std::unique_lock<std::mutex> lock(mutex_);
  idle_cv_.wait(lock, [this] { return (queue_.empty() && !busy_) || stop_; });
}

MappingEvents LocalMapper::takeEvents() {
  std::lock_guard<std::mutex> lock(mutex_);
  MappingEvents out = std::move(events_);
  events_ = MappingEvents();
  return out;
}

void LocalMapper::run() {
  nameThisThread("slam-mapping");
  lowerThreadPriority(nice_, "the slam-mapping thread");
  while (true) {
    Job job;
    bool more = false;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      work_cv_.wait(lock, [this] { return stop_ || !queue_.empty(); });
      if (stop_) break;
      job = queue_.front();
      queue_.pop_front();
      more = !queue_.empty();
      busy_ = true;
      abort_ba_ = false;
    }
    try {
      process(job, more);
    } catch (const std::exception& e) {
      spdlog::error("local mapping: keyframe {}: {}", job.second->id, e.what());
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      busy_ = false;
    }
    idle_cv_.notify_all();
  }
  idle_cv_.notify_all();
}

void LocalMapper::process(const Job& job, bool more_waiting) {
  const auto start = std::chrono::steady_clock::now();
  auto micros = [](std::chrono::steady_clock::time_point since) {
    return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() -
                                                                 since)
        .count();
  };
  Map& map = *job.first;
  const auto& kf = job.second;
  if (recent_map_id_ != map.id) {
    recent_points_.clear();
    recent_map_id_ = map.id;
  }
  MappingEvents events;
  {
    std::unique_lock<std::shared_mutex> lock(map.mutex);
    if (kf->bad) {
      mapping_us_ += micros(start);
      return;
    }
    linkKeyFrame(map, kf);
    cullRecentPoints(map, kf);
  }
  createNewPoints(map, kf);
  if (!more_waiting) {
    {
      std::unique_lock<std::shared_mutex> lock(map.mutex);
      fuseNeighbors(map, kf);
    }
    const auto ba_start = std::chrono::steady_clock::now();
    localBundleAdjustment(map, kf, &events);
    ba_us_ += micros(ba_start);
    std::unique_lock<std::shared_mutex> lock(map.mutex);
    cullKeyFrames(map, kf, &events);
  }
  mapping_us_ += micros(start);
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto& k : events.moved) events_.moved.push_back(k);
  for (auto& k : events.culled) events_.culled.push_back(k);
}

void LocalMapper::linkKeyFrame(Map& map, const std::shared_ptr<KeyFrame>& kf) {
  (void)map;
  for (int i = 0; i < kf->size(); ++i) {
    auto& p = kf->points[i];
    if (!p) continue;
    if (p->bad) {
      p = nullptr;
      continue;
    }
    if (!p->observedBy(kf->id)) {
      // The same point matched to two features of one keyframe: keep the first.
      p->addObservation(kf, i);
      p->updateNormalAndDepth();
      p->computeDistinctiveDescriptor();
    } else if (p->featureIn(kf->id) == i) {
      recent_points_.push_back(p);  // created with this keyframe (initial map)
    } else {
      p = nullptr;
    }
  }
  kf->updateConnections(options_.mapping.min_covisibility_weight);
}

void LocalMapper::cullRecentPoints(Map& map, const std::shared_ptr<KeyFrame>& kf) {
  for (auto it = recent_points_.begin(); it != recent_points_.end();) {
    const auto& p = *it;
    const int64_t age = kf->id - p->first_keyframe_id;
    if (p->bad) {
      it = recent_points_.erase(it);
    } else if (p->foundRatio() < options_.mapping.point_found_ratio) {
      map.erasePoint(p);
      it = recent_points_.erase(it);
    } else if (age >= 2 && p->numObservations() <= 2) {
      map.erasePoint(p);
      it = recent_points_.erase(it);
    } else if (age >= 3) {
      it = recent_points_.erase(it);  // survived its probation
    } else {
      ++it;
    }
  }
}

void LocalMapper::createNewPoints(Map& map, const std::shared_ptr<KeyFrame>& kf) {
  struct NewPoint {
    Eigen::Vector3d p_world;
    int feature1;
    std::shared_ptr<KeyFrame> kf2;
    int feature2;
  };
  std::vector<NewPoint> created;
  {
    std::shared_lock<std::shared_mutex> lock(map.mutex);
    if (kf->bad) return;
    const Intrinsics& in = *kf->features->intrinsics;
    const ScalePyramid& pyr = in.pyramid;
    const Eigen::Matrix3d K = in.K();
    const double cos_min_parallax = std::cos(options_.mapping.min_parallax_deg * M_PI / 180.0);
    const double ratio_factor = 1.5 * pyr.scale_factor;
    const SE3 T1 = kf->T_camera_world;
    const Eigen::Matrix3d R1wc = T1.linear().transpose();
    const Eigen::Vector3d c1 = kf->center();
    std::vector<bool> used(kf->size(), false);
    for (const auto& kf2 : kf->bestCovisible(options_.mapping.triangulation_neighbors)) {
      const Eigen::Vector3d c2 = kf2->center();
      const double median_depth2 = kf2->medianDepth();
      if (median_depth2 <= 0 || (c2 - c1).norm() / median_depth2 < 0.01)
        continue;  // baseline too short
      const SE3 T2 = kf2->T_camera_world;
      const Eigen::Matrix3d R2wc = T2.linear().transpose();
      const Matches matches =
          searchForTriangulation(*kf, *kf2, fundamentalFromPoses(T1, T2, K), &used);
      for (const auto& [i, j] : matches) {
        if (kf2->points[j]) continue;
        const Eigen::Vector3d ray1 = in.ray(kf->features->px[i]),
                              ray2 = in.ray(kf2->features->px[j]);
        const double cos_rays = (R1wc * ray1).normalized().dot((R2wc * ray2).normalized());
        if (cos_rays <= 0 || cos_rays > cos_min_parallax) continue;
        Eigen::Vector3d p;
        if (!triangulateDlt(T1, T2, ray1, ray2, &p)) continue;
        const Eigen::Vector3d q1 = T1 * p, q2 = T2 * p;
        if (q1.z() <= 0 || q2.z() <= 0) continue;
        const int l1 = kf->features->level(i), l2 = kf2->features->level(j);
        if ((in.project(q1) - kf->features->px[i]).squaredNorm() > 5.991 * pyr.sigma2[l1]) continue;
        if ((in.project(q2) - kf2->features->px[j]).squaredNorm() > 5.991 * pyr.sigma2[l2])
          continue;
        // Scale consistency: the distance ratio must agree with the pyramid levels.
        const double d1 = (p - c1).norm(), d2 = (p - c2).norm();
        if (d1 <= 0 || d2 <= 0) continue;
        const double ratio_dist = d2 / d1, ratio_octave = pyr.scale[l1] / pyr.scale[l2];
        if (ratio_dist * ratio_factor < ratio_octave || ratio_dist > ratio_octave * ratio_factor)
          continue;
        used[i] = true;
        created.push_back({p, i, kf2, j});
      }
    }
  }
  if (created.empty()) return;
  std::unique_lock<std::shared_mutex> lock(map.mutex);
  if (kf->bad) return;
  for (const auto& c : created) {
    if (c.kf2->bad || kf->points[c.feature1] || c.kf2->points[c.feature2]) continue;
    auto p = std::make_shared<MapPoint>(ids_.next_point++, map.id, c.p_world, kf);
    p->addObservation(kf, c.feature1);
    p->addObservation(c.kf2, c.feature2);
    kf->points[c.feature1] = p;
    c.kf2->points[c.feature2] = p;
    p->computeDistinctiveDescriptor();
    p->updateNormalAndDepth();
    map.addPoint(p);
    recent_points_.push_back(p);
  }
}

void LocalMapper::fuseNeighbors(Map& map, const std::shared_ptr<KeyFrame>& kf) {
  if (kf->bad) return;
  std::vector<std::shared_ptr<KeyFrame>> targets;
  std::set<int64_t> seen{kf->id};
  for (const auto& n : kf->bestCovisible(options_.mapping.fuse_neighbors)) {
    if (!seen.insert(n->id).second) continue;
    targets.push_back(n);
    for (const auto& n2 : n->bestCovisible(5))
      if (seen.insert(n2->id).second) targets.push_back(n2);
  }
  const double radius = 3.0;
  std::vector<std::shared_ptr<MapPoint>> own;
  for (const auto& p : kf->points)
    if (p && !p->bad) own.push_back(p);
  for (const auto& t : targets) fuse(map, t, own, radius);
  std::vector<std::shared_ptr<MapPoint>> theirs;
  std::set<int64_t> added;
  for (const auto& t : targets)
    for (const auto& p : t->points)
      if (p && !p->bad && added.insert(p->id).second) theirs.push_back(p);
  fuse(map, kf, theirs, radius);
  for (const auto& p : kf->points) {
    if (!p || p->bad) continue;
    p->computeDistinctiveDescriptor();
    p->updateNormalAndDepth();
  }
  kf->updateConnections(options_.mapping.min_covisibility_weight);
}

void LocalMapper::localBundleAdjustment(Map& map, const std::shared_ptr<KeyFrame>& kf,
                                        MappingEvents* events) {
  BaProblem ba;
  std::vector<std::shared_ptr<KeyFrame>> cams;
  std::vector<std::shared_ptr<MapPoint>> pts;
  struct ObsRef {
    std::shared_ptr<KeyFrame> kf;
    std::shared_ptr<MapPoint> p;
  };
  std::vector<ObsRef> refs;
  {
    std::shared_lock<std::shared_mutex> lock(map.mutex);
    if (kf->bad || map.keyframes.size() < 3) return;
    const Intrinsics& in = *kf->features->intrinsics;
    ba.fx = in.fx;
    ba.fy = in.fy;
    ba.cx = in.cx;
    ba.cy = in.cy;
    std::map<int64_t, int> cam_index, point_index;
    auto addCamera = [&](const std::shared_ptr<KeyFrame>& k, bool fixed) {
      cam_index[k->id] = static_cast<int>(cams.size());
      cams.push_back(k);
      ba.cameras.push_back({k->T_camera_world, fixed || k->id == map.first_keyframe_id});
    };
    addCamera(kf, false);
    for (const auto& n : kf->bestCovisible(options_.mapping.ba_local_keyframes - 1))
      addCamera(n, false);
    const size_t local_count = cams.size();
    for (size_t c = 0; c < local_count; ++c) {
      for (const auto& p : cams[c]->points) {
        if (!p || p->bad || point_index.count(p->id)) continue;
        point_index[p->id] = static_cast<int>(pts.size());
        pts.push_back(p);
        ba.points.push_back({p->p_world, false});
      }
    }
    // Keyframes that see local points but are not local are fixed: they anchor the gauge.
    for (const auto& p : pts)
      for (const auto& [kf_id, obs] : p->observations)
        if (!cam_index.count(kf_id) && !obs.keyframe->bad) addCamera(obs.keyframe, true);
    bool any_fixed = false;
    for (const auto& c : ba.cameras) any_fixed = any_fixed || c.fixed;
    if (!any_fixed) ba.cameras.back().fixed = true;
    for (size_t k = 0; k < pts.size(); ++k) {
      for (const auto& [kf_id, obs] : pts[k]->observations) {
        auto it = cam_index.find(kf_id);
        if (it == cam_index.end()) continue;
        const int level = obs.keyframe->features->level(obs.feature);
        ba.observations.push_back({it->second, static_cast<int>(k),
                                   obs.keyframe->features->px[obs.feature],
                                   in.pyramid.inv_sigma2[level]});
        refs.push_back({obs.keyframe, pts[k]});
      }
    }
  }
  if (ba.observations.empty()) return;

  // Two passes as in ORB-SLAM: robust, then again without the outliers found by the first.
  BaOptions bo;
  bo.iterations = options_.mapping.ba_iterations_robust;
  bo.abort = allow_abort_ ? &abort_ba_ : nullptr;
  BaSummary s = bundleAdjust(&ba, bo);
  if (!s.usable) return;
  if (!s.aborted) {
    for (auto& o : ba.observations) {
      bool front = true;
      if (observationChi2(ba, o, &front) > 5.991 || !front) o.enabled = false;
    }
    bo.iterations = options_.mapping.ba_iterations_refine;
    const BaSummary s2 = bundleAdjust(&ba, bo);
    if (!s2.usable) return;
  }
  ++bundle_adjustments_;

  std::unique_lock<std::shared_mutex> lock(map.mutex);
  for (size_t k = 0; k < ba.observations.size(); ++k) {
    bool front = true;
    if (observationChi2(ba, ba.observations[k], &front) <= 5.991 && front) continue;
    const auto& r = refs[k];
    if (r.kf->bad || r.p->bad) continue;
    const int feature = r.p->featureIn(r.kf->id);
    if (feature >= 0 && r.kf->points[feature] == r.p) r.kf->points[feature] = nullptr;
    if (r.p->eraseObservation(r.kf->id)) map.erasePoint(r.p);
  }
  for (size_t c = 0; c < cams.size(); ++c) {
    if (ba.cameras[c].fixed || cams[c]->bad) continue;
    cams[c]->T_camera_world = ba.cameras[c].T_camera_world;
    events->moved.push_back(cams[c]);
  }
  for (size_t k = 0; k < pts.size(); ++k) {
    if (pts[k]->bad) continue;
    pts[k]->p_world = ba.points[k].p_world;
    pts[k]->updateNormalAndDepth();
  }
}

void LocalMapper::cullKeyFrames(Map& map, const std::shared_ptr<KeyFrame>& kf,
                                MappingEvents* events) {
  if (kf->bad) return;
  for (const auto& [w, n] :
       std::vector<std::pair<int, std::shared_ptr<KeyFrame>>>(kf->covisible())) {
    if (n->bad || n->id == map.first_keyframe_id || n == kf) continue;
    if (redundantView(n->points, *n->features, options_.mapping.keyframe_redundancy, n->id)) {
      map.eraseKeyFrame(n);
      events->culled.push_back(n);
      ++culled_keyframes_;
    }
  }
}

}  // namespace slamaware::slam
