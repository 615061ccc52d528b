#pragma once
// A map (keyframes and points in one world frame and scale) and the atlas of maps: a new map is
// started when SLAM re-initialises, and earlier maps are kept so that it can relocalise in them.
#include <atomic>
#include <map>
#include <memory>
#include <shared_mutex>
#include <vector>

#include "procs/slam/map/keyframe.h"
#include "procs/slam/map/map_point.h"

namespace slamaware::slam {

class Map {
 public:
  explicit Map(int id) : id(id) {}
  /// Breaks the keyframe <-> point reference cycles so that everything is freed.
  ~Map();
  Map(const Map&) = delete;
  Map& operator=(const Map&) = delete;

  const int id;
  /// Guards every keyframe and point of this map (see map_point.h, keyframe.h).
  mutable std::shared_mutex mutex;

  std::map<int64_t, std::shared_ptr<KeyFrame>> keyframes;  ///< live keyframes by id
  std::map<int64_t, std::shared_ptr<MapPoint>> points;     ///< live points by id
  int64_t first_keyframe_id = -1;
  int64_t last_keyframe_id = -1;

  void addKeyFrame(const std::shared_ptr<KeyFrame>& kf);
  void addPoint(const std::shared_ptr<MapPoint>& p);
  /// Marks a point bad and removes it from its keyframes and from the map.
  void erasePoint(const std::shared_ptr<MapPoint>& p);
  /// Marks a keyframe bad, removes its observations and edges, and drops it from the map.
  void eraseKeyFrame(const std::shared_ptr<KeyFrame>& kf);
  /// Replaces point `a` by `b` in every keyframe that observes `a` (fusion of duplicates).
  void replacePoint(const std::shared_ptr<MapPoint>& a, const std::shared_ptr<MapPoint>& b);
};

/// Ids shared by all maps of a SLAM run (keyframe ids and point ids never repeat).
struct IdSource {
  std::atomic<int64_t> next_keyframe{0};
  std::atomic<int64_t> next_point{0};
  std::atomic<int> next_map{1};
};

}  // namespace slamaware::slam
