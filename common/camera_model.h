#pragma once
// Pinhole camera with radial-tangential (Brown-Conrady, OpenCV order k1 k2 p1 p2 k3) distortion.
// Pixel coordinates have their origin at the centre of the top-left pixel (OpenCV convention).
// Camera frame: x right, y down, z forward.
#include <Eigen/Core>
#include <array>
#include <opencv2/core/mat.hpp>

namespace slamaware {

class CameraModel {
 public:
  CameraModel() = default;
  CameraModel(int width, int height, double fx, double fy, double cx, double cy,
              const std::array<double, 5>& distortion = {0, 0, 0, 0, 0});

  int width() const { return width_; }
  int height() const { return height_; }
  double fx() const { return fx_; }
  double fy() const { return fy_; }
  double cx() const { return cx_; }
  double cy() const { return cy_; }
  const std::array<double, 5>& distortion() const { return dist_; }
  bool isDistorted() const { return distorted_; }
  bool valid() const { return width_ > 0 && height_ > 0 && fx_ > 0 && fy_ > 0; }
  Eigen::Matrix3d K() const;

  /// Pixel of a point in the camera frame (distortion applied). Requires p_camera.z() > 0.
  Eigen::Vector2d project(const Eigen::Vector3d& p_camera) const;
  /// Like project(), false when the point is behind the camera (z <= min_depth).
  bool project(const Eigen::Vector3d& p_camera, Eigen::Vector2d* pixel,
               double min_depth = 1e-6) const;
  /// Ray through a pixel, as (x, y, 1) in the camera frame (distortion removed).
  Eigen::Vector3d unproject(const Eigen::Vector2d& pixel) const;

  /// Normalised coordinates (x/z, y/z) -> distorted normalised coordinates.
  Eigen::Vector2d distort(const Eigen::Vector2d& normalized) const;
  /// Inverse of distort() by fixed-point iteration (exact to ~1e-10 within the image).
  Eigen::Vector2d undistort(const Eigen::Vector2d& distorted) const;
  /// Pixel of the same ray in the undistorted (pinhole) image with the same K.
  Eigen::Vector2d undistortPixel(const Eigen::Vector2d& pixel) const;

  /// The image as the pinhole camera K (same size) would have seen it. Uses cached maps.
  cv::Mat undistortImage(const cv::Mat& image) const;

  bool inImage(const Eigen::Vector2d& pixel, double border = 0) const {
    return pixel.x() >= border && pixel.y() >= border && pixel.x() <= width_ - 1 - border &&
           pixel.y() <= height_ - 1 - border;
  }
  /// The same camera for an image scaled by `s` (pyramid levels: s = 0.5, 0.25, ...).
  CameraModel scaled(double s) const;
  /// The pinhole camera with the same K and no distortion.
  CameraModel pinhole() const;

  bool operator==(const CameraModel& o) const;

 private:
  int width_ = 0, height_ = 0;
  double fx_ = 0, fy_ = 0, cx_ = 0, cy_ = 0;
  std::array<double, 5> dist_{0, 0, 0, 0, 0};
  bool distorted_ = false;
  mutable cv::Mat map1_, map2_;  // undistortImage cache
};

}  // namespace slamaware
