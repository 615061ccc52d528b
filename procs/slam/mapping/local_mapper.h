#pragma once
// Local mapping (after ORB-SLAM's LocalMapping, Mur-Artal et al. 2015, section VI), on its own
// thread: for each new keyframe it links the keyframe's matched points, culls recent points that
// tracking rarely finds, triangulates new points with covisible keyframes, fuses duplicates,
// runs a local bundle adjustment (Ceres) over the keyframe and its covisible neighbours, and
// culls keyframes whose points are seen by enough others.
//
// Locking: searches and the bundle adjustment's set-up run under the map's shared lock, the
// optimisation itself under no lock, and every change under the exclusive lock, held briefly —
// tracking, which holds the shared lock while it handles a frame, never waits for an optimisation.
#include <atomic>
#include <condition_variable>
#include <deque>
#include <list>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "procs/slam/map/map.h"
#include "procs/slam/slam_options.h"

namespace slamaware::slam {

/// Keyframes whose pose local mapping changed or that it removed.
struct MappingEvents {
  std::vector<std::shared_ptr<KeyFrame>> moved;
  std::vector<std::shared_ptr<KeyFrame>> culled;
};

class LocalMapper {
 public:
  /// threaded = options.mapping.threaded; allow_abort: a new keyframe may cut a bundle adjustment
  /// short (real time; never in lockstep, where results must not depend on timing); `nice`: the
  /// increment its thread lowers its priority by (common/thread_priority.h).
  LocalMapper(const SlamOptions& options, IdSource& ids, bool allow_abort, int nice);
  ~LocalMapper();
  LocalMapper(const LocalMapper&) = delete;
  LocalMapper& operator=(const LocalMapper&) = delete;

  /// Queues a new keyframe of `map`.
  void insert(const std::shared_ptr<Map>& map, const std::shared_ptr<KeyFrame>& kf);
  /// Processes everything queued, on the calling thread when not threaded; waits for the worker
  /// to finish it otherwise. Returns when nothing is queued or running.
  void waitIdle();
  bool idle() const;
  /// Keyframes moved or culled since the last call.
  MappingEvents takeEvents();

  int64_t bundleAdjustments() const { return bundle_adjustments_.load(); }
  int64_t culledKeyFrames() const { return culled_keyframes_.load(); }
  /// Time spent so far (wall clock, microseconds) mapping keyframes, and of it in local bundle
  /// adjustment (both passes).
  int64_t mappingMicros() const { return mapping_us_.load(); }
  int64_t bundleAdjustmentMicros() const { return ba_us_.load(); }

 private:
  using Job = std::pair<std::shared_ptr<Map>, std::shared_ptr<KeyFrame>>;
  void run();
  void process(const Job& job, bool more_waiting);
  void linkKeyFrame(Map& map, const std::shared_ptr<KeyFrame>& kf);
  void cullRecentPoints(Map& map, const std::shared_ptr<KeyFrame>& kf);
  void createNewPoints(Map& map, const std::shared_ptr<KeyFrame>& kf);
  void fuseNeighbors(Map& map, const std::shared_ptr<KeyFrame>& kf);
  void localBundleAdjustment(Map& map, const std::shared_ptr<KeyFrame>& kf, MappingEvents* events);
  void cullKeyFrames(Map& map, const std::shared_ptr<KeyFrame>& kf, MappingEvents* events);

  SlamOptions options_;
  IdSource& ids_;
  const bool threaded_, allow_abort_;
  const int nice_;
  mutable std::mutex mutex_;
  std::condition_variable work_cv_, idle_cv_;
  std::deque<Job> queue_;
  bool busy_ = false, stop_ = false;
  MappingEvents events_;
  std::atomic<bool> abort_ba_{false};
  std::list<std::shared_ptr<MapPoint>> recent_points_;  ///< points created lately (worker only)
  int recent_map_id_ = -1;
  std::atomic<int64_t> bundle_adjustments_{0}, culled_keyframes_{0}, mapping_us_{0}, ba_us_{0};
  std::thread thread_;
};

}  // namespace slamaware::slam
