#pragma once
// A camera frame as tracking sees it: ORB features with their undistorted positions in a search
// grid, the frame's pose, and the map points its features were matched to.
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "common/camera_model.h"
#include "common/geometry.h"
#include "procs/slam/features/orb_extractor.h"

namespace slamaware::slam {

class MapPoint;
class KeyFrame;

/// The pinhole camera of the images SLAM works on (a camera with lens distortion has its images
/// undistorted first, see SlamSystem), with the image bounds and the feature pyramid's scales.
struct Intrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  double min_x = 0, max_x = 0, min_y = 0, max_y = 0;  ///< px, bounds of the image
  ScalePyramid pyramid;

  Intrinsics() = default;
  /// From the pinhole part of `camera` (its distortion is ignored here).
  Intrinsics(const CameraModel& camera, const ScalePyramid& pyramid);
  Eigen::Matrix3d K() const;
  /// Undistorted pixel of a point in the camera frame (z > 0 required).
  Eigen::Vector2d project(const Eigen::Vector3d& p_camera) const {
    return {fx * p_camera.x() / p_camera.z() + cx, fy * p_camera.y() / p_camera.z() + cy};
  }
  /// Ray (x, y, 1) through an undistorted pixel.
  Eigen::Vector3d ray(const Eigen::Vector2d& px) const {
    return {(px.x() - cx) / fx, (px.y() - cy) / fy, 1.0};
  }
  bool inBounds(const Eigen::Vector2d& px) const {
    return px.x() >= min_x && px.x() < max_x && px.y() >= min_y && px.y() < max_y;
  }
};

/// Immutable features of one image, shared by the frame and the keyframe made from it.
class FrameFeatures {
 public:
  FrameFeatures(OrbFeatures orb, std::shared_ptr<const Intrinsics> intrinsics);

  int size() const { return static_cast<int>(keypoints.size()); }
  int level(int i) const { return keypoints[i].octave; }
  const uint8_t* descriptor(int i) const { return descriptors.ptr<uint8_t>(i); }
  /// Indices of features within r px (square window) of (x, y) whose level is in [min_level,
  /// max_level] (-1: any), in a fixed order.
  std::vector<int> inArea(double x, double y, double r, int min_level = -1,
                          int max_level = -1) const;

  std::vector<cv::KeyPoint> keypoints;  ///< as detected, level-0 px, octave = level
  std::vector<Eigen::Vector2d> px;      ///< the keypoints' positions as vectors
  cv::Mat descriptors;                  ///< 32 bytes per feature
  std::shared_ptr<const Intrinsics> intrinsics;

 private:
  static constexpr double kCellPx = 10.0;
  int grid_cols_ = 0, grid_rows_ = 0;
  std::vector<std::vector<int>> grid_;  ///< feature indices per cell (row-major)
};

/// The frame being tracked.
struct Frame {
  int64_t id = -1;    ///< sequential number of frames handled by SLAM
  int64_t utime = 0;  ///< µs, capture time
  int32_t seq = -1;   ///< the camera's frame number
  std::shared_ptr<const FrameFeatures> features;
  cv::Mat grey;  ///< 8-bit grey image (undistorted)
  cv::Mat bgr;   ///< 8-bit colour image, same geometry as grey
  SE3 T_camera_world = SE3::Identity();
  bool has_pose = false;
  std::vector<std::shared_ptr<MapPoint>> points;  ///< matched map point per feature (null: none)
  std::vector<bool> outlier;                      ///< per feature, rejected by pose optimisation
  std::shared_ptr<KeyFrame> reference;            ///< keyframe sharing most points

  int size() const { return features ? features->size() : 0; }
  /// Clears matches (keeps the features).
  void resetMatches();
  /// Matched features that are not outliers.
  int countInliers() const;
  Eigen::Vector3d center() const {
    return -(T_camera_world.linear().transpose() * T_camera_world.translation());
  }
};

}  // namespace slamaware::slam
