#pragma once
// A keyframe: a frame kept in the map, with its features, its images (for relocalisation and the
// depth filter), its pose and its covisibility edges.
//
// Thread safety: pose, points, covisibility and the bad flag are guarded by the owning Map's
// mutex; everything const is immutable after construction.
#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "procs/slam/map/frame.h"

namespace slamaware::slam {

class MapPoint;

class KeyFrame : public std::enable_shared_from_this<KeyFrame> {
 public:
  KeyFrame(int64_t id, int map_id, const Frame& frame);

  const int64_t id;
  const int map_id;
  const int64_t frame_id;
  const int64_t utime;
  const int32_t seq;
  const std::shared_ptr<const FrameFeatures> features;
  const cv::Mat grey, bgr;
  const cv::Mat
      thumbnail;  ///< small blurred zero-mean image for relocalisation candidates (PTAM's SBI)

  SE3 T_camera_world;
  std::vector<std::shared_ptr<MapPoint>> points;  ///< map point per feature (null: none)
  bool bad = false;

  int size() const { return features->size(); }
  SE3 T_world_camera() const { return T_camera_world.inverse(); }
  Eigen::Vector3d center() const {
    return -(T_camera_world.linear().transpose() * T_camera_world.translation());
  }

  /// Map points (not bad) seen by at least min_observations keyframes.
  int trackedPoints(int min_observations) const;
  /// Median depth of its map points in its camera frame (-1 if none).
  double medianDepth() const;
  /// Minimum, mean (of inverse depth, as a depth) and count of its map points' depths.
  bool depthRange(double* min_depth, double* mean_depth) const;

  /// Covisibility: keyframes sharing map points, by weight (shared points), heaviest first.
  const std::vector<std::pair<int, std::shared_ptr<KeyFrame>>>& covisible() const {
    return ordered_;
  }
  std::vector<std::shared_ptr<KeyFrame>> bestCovisible(int n) const;
  /// Recomputes this keyframe's edges from its points' observations and mirrors them into the
  /// other keyframes (edges need min_weight shared points; the heaviest edge is always kept).
  void updateConnections(int min_weight);
  void addConnection(const std::shared_ptr<KeyFrame>& kf, int weight);
  void eraseConnection(int64_t keyframe_id);
  /// Removes every edge of this keyframe (both directions).
  void clearConnections();

  /// Score of the thumbnail against another (zero-mean normalised cross-correlation, -1..1).
  static double thumbnailSimilarity(const cv::Mat& a, const cv::Mat& b);
  static cv::Mat makeThumbnail(const cv::Mat& grey);

 private:
  void sortConnections();
  std::map<int64_t, std::pair<int, std::shared_ptr<KeyFrame>>>
      connections_;  ///< by id: weight, keyframe
  std::vector<std::pair<int, std::shared_ptr<KeyFrame>>> ordered_;
};

}  // namespace slamaware::slam
