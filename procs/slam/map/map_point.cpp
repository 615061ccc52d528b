#include "procs/slam/map/map_point.h"

#include <algorithm>
#include <vector>

#include "procs/slam/features/orb_extractor.h"
#include "procs/slam/map/keyframe.h"

namespace slamaware::slam {

MapPoint::MapPoint(int64_t id_, int map_id_, const Eigen::Vector3d& p,
                   const std::shared_ptr<KeyFrame>& ref)
    : id(id_), map_id(map_id_), p_world(p), reference(ref), first_keyframe_id(ref ? ref->id : -1) {}

int MapPoint::featureIn(int64_t keyframe_id) const {
  auto it = observations.find(keyframe_id);
  return it == observations.end() ? -1 : it->second.feature;
}

void MapPoint::addObservation(const std::shared_ptr<KeyFrame>& kf, int feature) {
  observations[kf->id] = Observation{kf, feature};
}

bool MapPoint::eraseObservation(int64_t keyframe_id) {
  observations.erase(keyframe_id);
  if (reference && reference->id == keyframe_id)
    reference = observations.empty() ? nullptr : observations.begin()->second.keyframe;
  return observations.size() < 2;
}

void MapPoint::computeDistinctiveDescriptor() {
  std::vector<const uint8_t*> descs;
  for (const auto& [kf_id, obs] : observations)
    if (!obs.keyframe->bad) descs.push_back(obs.keyframe->features->descriptor(obs.feature));
  if (descs.empty()) return;
  const size_t n = descs.size();
  std::vector<int> dist(n * n, 0);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j)
      dist[i * n + j] = dist[j * n + i] = descriptorDistance(descs[i], descs[j]);
  size_t best = 0;
  int best_median = 1 << 30;
  std::vector<int> row(n);
  for (size_t i = 0; i < n; ++i) {
    std::copy(dist.begin() + i * n, dist.begin() + (i + 1) * n, row.begin());
    std::nth_element(row.begin(), row.begin() + (n - 1) / 2, row.end());
    const int median = row[(n - 1) / 2];
    if (median < best_median) {
      best_median = median;
      best = i;
    }
  }
  std::copy(descs[best], descs[best] + 32, descriptor.begin());
}

void MapPoint::updateNormalAndDepth() {
  if (observations.empty()) return;
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (const auto& [kf_id, obs] : observations)
    n += (p_world - obs.keyframe->center()).normalized();
  normal = n.normalized();
  std::shared_ptr<KeyFrame> ref =
      reference && !reference->bad ? reference : observations.begin()->second.keyframe;
  const int feature = featureIn(ref->id);
  if (feature < 0) return;
  const ScalePyramid& pyr = ref->features->intrinsics->pyramid;
  const double distance = (p_world - ref->center()).norm();
  const int level = ref->features->level(feature);
  // Seen at `level` from `distance`: it would appear at level 0 from up to distance * scale[level]
  // and at the coarsest level from as close as that / scale[last].
  max_distance = distance * pyr.scale[level];
  min_distance = max_distance / pyr.scale[pyr.levels() - 1];
}

int MapPoint::predictLevel(double distance, const ScalePyramid& pyramid) const {
  return pyramid.predictLevel(max_distance, distance);
}

std::shared_ptr<MapPoint> MapPoint::resolve(std::shared_ptr<MapPoint> p) {
  for (int i = 0; p && p->replaced_by && i < 64; ++i) p = p->replaced_by;
  return p;
}

bool redundantView(const std::vector<std::shared_ptr<MapPoint>>& points,
                   const FrameFeatures& features, double share, int64_t except) {
  constexpr int kNeeded = 3;
  int total = 0, redundant = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const auto& p = points[i];
    if (!p || p->bad) continue;
    ++total;
    if (p->numObservations() < kNeeded) continue;
    const int level = features.level(static_cast<int>(i));
    int seen = 0;
    for (const auto& [kf_id, obs] : p->observations)
      if (kf_id != except && obs.keyframe->features->level(obs.feature) <= level + 1 &&
          ++seen >= kNeeded)
        break;
    if (seen >= kNeeded) ++redundant;
  }
  return total > 0 && redundant > share * total;
}

}  // namespace slamaware::slam
