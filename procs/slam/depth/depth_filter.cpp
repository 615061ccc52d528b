#include "procs/slam/depth/depth_filter.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace slamaware::slam {

namespace {
constexpr int kSeedBorder = 8;  // px: host samples along the epipolar line need room

// The colour of pixel px of an 8-bit BGR image, as RGB.
void rgbAt(const cv::Mat& bgr, const Eigen::Vector2i& px, uint8_t rgb[3]) {
  const uint8_t* c = bgr.ptr<uint8_t>(px.y()) + 3 * px.x();
  rgb[0] = c[2];
  rgb[1] = c[1];
  rgb[2] = c[0];
}

// The point of a seed at its posterior mean, in its keyframe's camera frame.
SemiDensePoint pointOfSeed(const DepthSeed& s, bool provisional) {
  SemiDensePoint p;
  p.p_camera = s.f / s.mu;
  p.depth_std = std::sqrt(s.sigma2) / (s.mu * s.mu);
  std::copy(s.rgb, s.rgb + 3, p.rgb);
  p.provisional = provisional;
  return p;
}

bool isProvisional(const SemiDensePoint& p) { return p.provisional; }

}  // namespace

DepthFilter::DepthFilter(const DepthFilterOptions& options, int width, int height, double fx,
                         double fy, double cx, double cy)
    : options_(options), width_(width), height_(height), fx_(fx), fy_(fy), cx_(cx), cy_(cy) {
  search_.fx = static_cast<float>(fx);
  search_.fy = static_cast<float>(fy);
  search_.cx = static_cast<float>(cx);
  search_.cy = static_cast<float>(cy);
  search_.max_search_px = static_cast<float>(options.max_search_px);
  search_.max_ssd_per_sample = static_cast<float>(options.max_ssd_per_sample);
  search_.uniqueness_ratio = static_cast<float>(options.uniqueness_ratio);
  search_.min_epipolar_gradient = static_cast<float>(options.min_epipolar_gradient);
  // Angle subtended by the matching noise (SVO: twice the half-pixel angle).
  px_error_angle_ = 2.0 * std::atan(options.pixel_noise / (2.0 * fx));
}

std::vector<Eigen::Vector2i> DepthFilter::selectSeedPixels(const cv::Mat& grey) const {
  const int cell = std::max(1, options_.seed_cell_px);
  const float min_g2 = static_cast<float>(options_.min_gradient * options_.min_gradient);
  struct Candidate {
    float g2;
    Eigen::Vector2i px;
  };
  std::vector<Candidate> candidates;
  for (int y0 = kSeedBorder; y0 + cell <= grey.rows - kSeedBorder; y0 += cell) {
    for (int x0 = kSeedBorder; x0 + cell <= grey.cols - kSeedBorder; x0 += cell) {
      float best = -1;
      Eigen::Vector2i best_px(0, 0);
      for (int y = y0; y < y0 + cell; ++y) {
        const uint8_t* row = grey.ptr<uint8_t>(y);
        const uint8_t* up = grey.ptr<uint8_t>(y - 1);
        const uint8_t* down = grey.ptr<uint8_t>(y + 1);
        for (int x = x0; x < x0 + cell; ++x) {
          const float gx = 0.5f * (float(row[x + 1]) - float(row[x - 1]));
          const float gy = 0.5f * (float(down[x]) - float(up[x]));
          const float g2 = gx * gx + gy * gy;
          if (g2 > best) {
            best = g2;
            best_px = {x, y};
          }
        }
      }
      if (best >= min_g2) candidates.push_back({best, best_px});
    }
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.g2 > b.g2; });
  if (static_cast<int>(candidates.size()) > options_.max_seeds_per_keyframe)
    candidates.resize(std::max(0, options_.max_seeds_per_keyframe));
  std::vector<Eigen::Vector2i> out;
  out.reserve(candidates.size());
  for (const auto& c : candidates) out.push_back(c.px);
  return out;
}

void DepthFilter::updateHost(Host& host, const DepthFrameInput& input,
                             std::vector<SemiDensePoint>* converged) {
  const SE3 T_cur_host = input.T_world_camera.inverse() * host.T_world_camera;
  const Eigen::Matrix3f R = T_cur_host.linear().cast<float>();
  const Eigen::Vector3f t = T_cur_host.translation().cast<float>();
  const Eigen::Vector3d t_host_cur = -(T_cur_host.linear().transpose() * T_cur_host.translation());
  // A frame too close to the keyframe gives only weak measurements: skip it.
  float mean_inverse = 0;
  for (const auto& s : host.seeds) mean_inverse += s.mu;
  mean_inverse /= std::max<size_t>(1, host.seeds.size());
  if (t.norm() * mean_inverse < options_.min_baseline_ratio) return;
  ++host.frames_searched;

  size_t kept = 0;
  for (size_t i = 0; i < host.seeds.size(); ++i) {
    DepthSeed& s = host.seeds[i];
    const EpipolarMatch m = searchEpipolar(host.grey, input.grey, R, t, s, search_);
    if (m.result == EpipolarMatch::kNoMatch) {
      s.b += 1;  // a failed search is evidence of an outlier (SVO)
      ++failures_;
    } else if (m.result == EpipolarMatch::kFound) {
      const double z = m.distance;
      const double tau = depthUncertainty(t_host_cur, s.f.cast<double>(), z, px_error_angle_);
      const double tau_inverse = 0.5 * (1.0 / std::max(1e-7, z - tau) - 1.0 / (z + tau));
      updateSeed(&s, static_cast<float>(1.0 / z), static_cast<float>(tau_inverse * tau_inverse));
      ++measurements_;
    }
    if (s.inlierRatio() < options_.min_inlier_ratio) continue;  // dropped: mostly outliers
    if (s.updates >= 2 && std::sqrt(s.sigma2) < s.z_range / options_.convergence_ratio) {
      converged->push_back(pointOfSeed(s, false));
      continue;
    }
    // A young map's seed: published once it is as certain as young_convergence_ratio asks, and
    // filtered on (converged, it adds its point as any seed; the provisional one goes when the
    // keyframe finishes).
    if (host.young && !s.provisional && s.updates >= 2 &&
        std::sqrt(s.sigma2) < s.z_range / options_.young_convergence_ratio) {
      s.provisional = true;
      converged->push_back(pointOfSeed(s, true));
    }
    host.seeds[kept++] = s;
  }
  host.seeds.resize(kept);
}

void DepthFilter::addHost(const DepthKeyframeInput& kf) {
  Host host;
  host.grey = kf.grey;
  host.bgr = kf.bgr;
  host.T_world_camera = kf.T_world_camera;
  {
    std::lock_guard<std::mutex> lock(store_mutex_);
    SemiDenseKeyframe& s = store_[kf.id];
    s.id = kf.id;
    s.map_id = kf.map_id;
    s.utime = kf.utime;
    s.seq = kf.seq;
    s.T_world_camera = kf.T_world_camera;
    host.store = &s;
    // A young map (no seed of it converged yet to speak of) starts from the keyframe's
    // triangulated features, so that its objects are there before the seeds converge.
    if (options_.enabled && converged_per_map_[kf.map_id] < options_.young_map_points) {
      for (const auto& [px, p_camera] : kf.sparse) {
        if (!(p_camera.z() > 0) || px.x() < 0 || px.y() < 0 || px.x() >= kf.bgr.cols ||
            px.y() >= kf.bgr.rows)
          continue;
        SemiDensePoint p;
        p.p_camera = p_camera;
        p.depth_std = static_cast<float>(options_.sparse_depth_std * p_camera.norm());
        rgbAt(kf.bgr, px, p.rgb);
        s.points.push_back(p);
      }
      s.from_features = s.points.size();
      host.young = options_.young_convergence_ratio > 0;
      stats_.points += static_cast<int64_t>(s.points.size());
    }
  }
  const float mean_depth = static_cast<float>(kf.mean_depth),
              min_depth = static_cast<float>(kf.min_depth);
  for (const Eigen::Vector2i& px : selectSeedPixels(kf.grey)) {
    const Eigen::Vector3f f =
        Eigen::Vector3f(float((px.x() - cx_) / fx_), float((px.y() - cy_) / fy_), 1.f).normalized();
    DepthSeed seed = makeSeed(float(px.x()), float(px.y()), f, mean_depth, min_depth);
    if (!kf.bgr.empty()) rgbAt(kf.bgr, px, seed.rgb);
    host.seeds.push_back(seed);
  }
  if (options_.enabled) hosts_[kf.id] = std::move(host);
}

void DepthFilter::dropKeyframe(int64_t id) {
  hosts_.erase(id);
  std::lock_guard<std::mutex> lock(store_mutex_);
  auto it = store_.find(id);
  if (it == store_.end()) return;
  stats_.points -= static_cast<int64_t>(it->second.points.size());
  store_.erase(it);
}

std::vector<int64_t> DepthFilter::process(const DepthFrameInput& input) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<int64_t> finished;
  for (int64_t id : input.culled_keyframes) dropKeyframe(id);
  {
    std::lock_guard<std::mutex> lock(store_mutex_);
    for (const auto& [id, T] : input.keyframe_poses) {
      auto it = store_.find(id);
      if (it != store_.end()) it->second.T_world_camera = T;
    }
  }
  for (const auto& [id, T] : input.keyframe_poses) {
    auto it = hosts_.find(id);
    if (it != hosts_.end()) it->second.T_world_camera = T;
  }

  if (input.located && !input.grey.empty()) {
    bool used = false;
    for (auto& [id, host] : hosts_) {
      if (host.store->map_id != input.map_id || host.seeds.empty()) continue;
      std::vector<SemiDensePoint> converged;
      updateHost(host, input, &converged);
      used = true;
      if (converged.empty()) continue;
      std::lock_guard<std::mutex> lock(store_mutex_);
      const auto provisional =
          static_cast<int64_t>(std::count_if(converged.begin(), converged.end(), isProvisional));
      converged_per_map_[input.map_id] += static_cast<int64_t>(converged.size()) - provisional;
      host.store->provisional += static_cast<size_t>(provisional);
      host.store->points.insert(host.store->points.end(), converged.begin(), converged.end());
      stats_.points += static_cast<int64_t>(converged.size());
    }
    if (used) ++frames_;
  }

  // Keyframes age with every newer keyframe of their map; a new map ends all older seeds.
  auto finish = [&](std::map<int64_t, Host>::iterator it) {
    {
      std::lock_guard<std::mutex> lock(store_mutex_);
      SemiDenseKeyframe& kf = *it->second.store;
      kf.finished = true;
      // Once the map's seeds have converged, a keyframe's map points were only stand-ins: they
      // are snapshots from before bundle adjustment, and copies of one map point in several
      // keyframes would pass for surfaces that many keyframes agree on.
      if ((kf.from_features > 0 || kf.provisional > 0) &&
          converged_per_map_[kf.map_id] >= options_.young_map_points) {
        kf.points.erase(kf.points.begin(), kf.points.begin() + static_cast<long>(kf.from_features));
        kf.points.erase(std::remove_if(kf.points.begin(), kf.points.end(), isProvisional),
                        kf.points.end());
        stats_.points -= static_cast<int64_t>(kf.from_features + kf.provisional);
        kf.from_features = kf.provisional = 0;
        kf.features_dropped = true;
      }
    }
    finished.push_back(it->first);
    return hosts_.erase(it);
  };
  for (const auto& kf : input.new_keyframes) {
    for (auto it = hosts_.begin(); it != hosts_.end();) {
      Host& h = it->second;
      ++h.newer_keyframes;
      const bool retired = h.newer_keyframes >= options_.max_keyframes &&
                           (h.frames_searched >= options_.min_frames ||
                            h.newer_keyframes >= options_.max_keyframes + options_.min_frames);
      if (h.store->map_id != kf.map_id || retired)
        it = finish(it);
      else
        ++it;
    }
  }
  for (auto it = hosts_.begin(); it != hosts_.end();) {
    if (it->second.seeds.empty() || it->second.store->map_id != input.map_id)
      it = finish(it);
    else
      ++it;
  }

  for (const auto& kf : input.new_keyframes) addHost(kf);

  int64_t active = 0;
  for (const auto& [id, h] : hosts_) active += static_cast<int64_t>(h.seeds.size());
  std::lock_guard<std::mutex> lock(store_mutex_);
  stats_.active_seeds = active;
  ++stats_.calls;
  stats_.frames = frames_;
  stats_.measurements = measurements_;
  stats_.failures = failures_;
  stats_.last_update_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return finished;
}

SemiDenseKeyframe DepthFilter::keyframe(int64_t id) const {
  std::lock_guard<std::mutex> lock(store_mutex_);
  auto it = store_.find(id);
  return it == store_.end() ? SemiDenseKeyframe() : it->second;
}

std::vector<SemiDenseKeyframe> DepthFilter::mapKeyframes(int map_id) const {
  std::lock_guard<std::mutex> lock(store_mutex_);
  std::vector<SemiDenseKeyframe> out;
  for (const auto& [id, kf] : store_)
    if (kf.map_id == map_id) out.push_back(kf);
  return out;
}

std::vector<DepthFilter::LiveKeyframe> DepthFilter::liveKeyframes(int map_id) const {
  std::lock_guard<std::mutex> lock(store_mutex_);
  std::vector<LiveKeyframe> out;
  for (const auto& [id, kf] : store_)
    if (kf.map_id == map_id && !kf.finished)
      out.push_back({id, kf.points.size(), kf.from_features});
  return out;
}

DepthFilterStats DepthFilter::stats() const {
  std::lock_guard<std::mutex> lock(store_mutex_);
  return stats_;
}

}  // namespace slamaware::slam
