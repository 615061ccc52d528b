#pragma once
// A 3D point of the sparse map, with the keyframe features that observe it.
//
// Thread safety: position, observations, descriptor, normal and the bad flag are guarded by the
// owning Map's mutex (shared for reading, exclusive for writing). The visible / found counters
// are atomics that tracking updates while holding only the shared lock.
#include <Eigen/Core>
#include <array>
#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <vector>

namespace slamaware::slam {

class FrameFeatures;
class KeyFrame;
struct ScalePyramid;

class MapPoint {
 public:
  struct Observation {
    std::shared_ptr<KeyFrame> keyframe;
    int feature = -1;  ///< index of the keyframe's feature
  };

  MapPoint(int64_t id, int map_id, const Eigen::Vector3d& p_world,
           const std::shared_ptr<KeyFrame>& reference);

  const int64_t id;
  const int map_id;
  Eigen::Vector3d p_world;
  std::map<int64_t, Observation> observations;  ///< by keyframe id (a fixed order)
  std::array<uint8_t, 32> descriptor{};  ///< the observation's descriptor closest to all others
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  ///< mean viewing direction (unit), world frame
  double min_distance = 0, max_distance = 0;  ///< map units, range where ORB's scales can see it
  std::shared_ptr<KeyFrame> reference;        ///< the keyframe that created it
  int64_t first_keyframe_id;
  bool bad = false;
  std::shared_ptr<MapPoint> replaced_by;  ///< set when fused into another point

  std::atomic<int> visible{1};  ///< frames where it was predicted in view
  std::atomic<int> found{1};    ///< frames where it was matched
  // Tracking's bookkeeping (only the tracking thread touches these).
  int64_t local_map_frame = -1;  ///< frame for which it was added to the local map
  int64_t last_seen_frame = -1;  ///< frame in which it was matched

  int numObservations() const { return static_cast<int>(observations.size()); }
  bool observedBy(int64_t keyframe_id) const { return observations.count(keyframe_id) > 0; }
  int featureIn(int64_t keyframe_id) const;
  void addObservation(const std::shared_ptr<KeyFrame>& kf, int feature);
  /// Removes an observation; returns true when the point is left with too few to exist.
  bool eraseObservation(int64_t keyframe_id);
  /// Re-selects the descriptor with the least median distance to the other observations.
  void computeDistinctiveDescriptor();
  /// Recomputes the mean viewing direction and the distance range of scale invariance.
  void updateNormalAndDepth();
  double foundRatio() const { return double(found.load()) / std::max(1, visible.load()); }
  /// Pyramid level at which a camera at `distance` is expected to see the point.
  int predictLevel(double distance, const ScalePyramid& pyramid) const;
  /// Follows replaced_by to the point that now stands for this one.
  static std::shared_ptr<MapPoint> resolve(std::shared_ptr<MapPoint> p);
};

/// Local mapping's test of a redundant view: more than `share` of `points` (one per feature of
/// `features`; null and bad ones left out) are seen by three keyframes other than `except` at
/// their feature's pyramid level + 1 or finer. Culling asks it of a keyframe (except: itself),
/// the keyframe decision of a frame (a redundant frame is not made a keyframe).
bool redundantView(const std::vector<std::shared_ptr<MapPoint>>& points,
                   const FrameFeatures& features, double share, int64_t except = -1);

}  // namespace slamaware::slam
