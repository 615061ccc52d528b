#include "procs/proposals/free_space.h"

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace slamaware::proposals {

namespace {

// Shifted as unsigned: a left shift of a negative bin was undefined behaviour (UBSan).
int64_t binKey(int64_t u, int64_t v) {
  return static_cast<int64_t>((static_cast<uint64_t>(u) << 32) ^
                              (static_cast<uint64_t>(v) & 0xFFFFFFFFu));
}

// A keyframe's rays: per angular bin, the nearest point it seeded in that direction.
struct Rays {
  Eigen::Vector3f centre;
  Eigen::Matrix3f R_camera_world;  // any orientation near the keyframe's: a parametrisation only
  std::unordered_map<int64_t, float> nearest;

  bool bin(const Eigen::Vector3f& p, float bin_rad, int64_t* key, float* range) const {
    const Eigen::Vector3f q = R_camera_world * (p - centre);
    if (!(q.z() > 1e-6f * q.norm())) return false;
    *key = binKey(static_cast<int64_t>(std::floor(q.x() / q.z() / bin_rad)),
                  static_cast<int64_t>(std::floor(q.y() / q.z() / bin_rad)));
    *range = q.norm();
    return true;
  }
};

}  // namespace

std::vector<MapPoint> removeSeenThrough(const std::vector<MapPoint>& test,
                                        const std::map<int32_t, std::vector<MapPoint>>& by_keyframe,
                                        const std::map<int32_t, Eigen::Vector3f>& centres,
                                        const std::vector<View>& views, const FreeSpaceOptions& o,
                                        int64_t* removed) {
  if (removed) *removed = 0;
  if (views.empty() || o.min_violations <= 0) return test;
  const float bin_rad = static_cast<float>(o.bin_rad);
  std::vector<Rays> rays;
  for (const auto& [kf, pts] : by_keyframe) {
    const auto c = centres.find(kf);
    if (c == centres.end() || pts.empty()) continue;
    const View* nearest = &views.front();
    for (const View& w : views)
      if ((w.centre - c->second).squaredNorm() < (nearest->centre - c->second).squaredNorm())
        nearest = &w;
    Rays r;
    r.centre = c->second;
    r.R_camera_world.row(0) = nearest->right.transpose();
    r.R_camera_world.row(1) = -nearest->up.transpose();
    r.R_camera_world.row(2) = nearest->forward.transpose();
    r.nearest.reserve(pts.size());
    for (const auto& m : pts) {
      int64_t key;
      float range;
      if (!r.bin(m.p, bin_rad, &key, &range)) continue;
      auto [it, inserted] = r.nearest.emplace(key, range);
      if (!inserted) it->second = std::min(it->second, range);
    }
    rays.push_back(std::move(r));
  }
  std::vector<MapPoint> kept;
  kept.reserve(test.size());
  const float keep_ratio = static_cast<float>(1.0 - o.margin);
  for (const auto& m : test) {
    int seen = 0, through = 0;
    for (const Rays& r : rays) {
      int64_t key;
      float range;
      if (!r.bin(m.p, bin_rad, &key, &range)) continue;
      const auto it = r.nearest.find(key);
      if (it == r.nearest.end()) continue;
      ++seen;
      if (range < keep_ratio * it->second) ++through;
    }
    if (through >= o.min_violations && through >= o.min_share * seen) {
      if (removed) ++*removed;
      continue;
    }
    kept.push_back(m);
  }
  return kept;
}

}  // namespace slamaware::proposals
