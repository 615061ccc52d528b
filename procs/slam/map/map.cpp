#include "procs/slam/map/map.h"

namespace slamaware::slam {

Map::~Map() {
  for (auto& [id, kf] : keyframes) {
    kf->points.clear();
    kf->clearConnections();
  }
  for (auto& [id, p] : points) {
    p->observations.clear();
    p->reference.reset();
    p->replaced_by.reset();
  }
}

void Map::addKeyFrame(const std::shared_ptr<KeyFrame>& kf) {
  keyframes[kf->id] = kf;
  if (first_keyframe_id < 0) first_keyframe_id = kf->id;
  last_keyframe_id = std::max(last_keyframe_id, kf->id);
}

void Map::addPoint(const std::shared_ptr<MapPoint>& p) { points[p->id] = p; }

void Map::erasePoint(const std::shared_ptr<MapPoint>& p) {
  p->bad = true;
  for (auto& [kf_id, obs] : p->observations) {
    auto& slot = obs.keyframe->points[obs.feature];
    if (slot == p) slot = nullptr;
  }
  p->observations.clear();
  p->reference.reset();
  points.erase(p->id);
}

void Map::eraseKeyFrame(const std::shared_ptr<KeyFrame>& kf) {
  kf->bad = true;
  for (auto& p : kf->points) {
    if (!p || p->bad) continue;
    if (p->eraseObservation(kf->id))
      erasePoint(p);
    else
      p->updateNormalAndDepth();
  }
  kf->points.assign(kf->points.size(), nullptr);
  kf->clearConnections();
  keyframes.erase(kf->id);
}

void Map::replacePoint(const std::shared_ptr<MapPoint>& a, const std::shared_ptr<MapPoint>& b) {
  if (a == b || a->bad || b->bad) return;
  for (auto& [kf_id, obs] : a->observations) {
    auto& kf = obs.keyframe;
    if (!b->observedBy(kf_id)) {
      kf->points[obs.feature] = b;
      b->addObservation(kf, obs.feature);
    } else if (kf->points[obs.feature] == a) {
      kf->points[obs.feature] = nullptr;
    }
  }
  b->found += a->found.load();
  b->visible += a->visible.load();
  b->computeDistinctiveDescriptor();
  b->updateNormalAndDepth();
  a->bad = true;
  a->replaced_by = b;
  a->observations.clear();
  a->reference.reset();
  points.erase(a->id);
}

}  // namespace slamaware::slam
