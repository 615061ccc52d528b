#include "common/camera_model.h"

#include <Eigen/LU>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace slamaware {

CameraModel::CameraModel(int width, int height, double fx, double fy, double cx, double cy,
                         const std::array<double, 5>& distortion)
    : width_(width), height_(height), fx_(fx), fy_(fy), cx_(cx), cy_(cy), dist_(distortion) {
  distorted_ = false;
  for (double d : dist_) distorted_ = distorted_ || d != 0.0;
}

Eigen::Matrix3d CameraModel::K() const {
  Eigen::Matrix3d K;
  K << fx_, 0, cx_, 0, fy_, cy_, 0, 0, 1;
  return K;
}

Eigen::Vector2d CameraModel::distort(const Eigen::Vector2d& n) const {
  if (!distorted_) return n;
  const double k1 = dist_[0], k2 = dist_[1], p1 = dist_[2], p2 = dist_[3], k3 = dist_[4];
  const double x = n.x(), y = n.y();
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
  return {x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
          y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y};
}

Eigen::Vector2d CameraModel::undistort(const Eigen::Vector2d& d) const {
  if (!distorted_) return d;
  // Newton iterations on distort(n) = d with a numeric Jacobian: converges in a few steps for
  // the distortions of real lenses inside the image.
  Eigen::Vector2d n = d;
  for (int it = 0; it < 20; ++it) {
    const Eigen::Vector2d f = distort(n) - d;
    if (f.squaredNorm() < 1e-24) break;
    const double h = 1e-7;
    Eigen::Matrix2d J;
    J.col(0) = (distort(n + Eigen::Vector2d(h, 0)) - distort(n - Eigen::Vector2d(h, 0))) / (2 * h);
    J.col(1) = (distort(n + Eigen::Vector2d(0, h)) - distort(n - Eigen::Vector2d(0, h))) / (2 * h);
    n -= J.inverse() * f;
  }
  return n;
}

Eigen::Vector2d CameraModel::project(const Eigen::Vector3d& p) const {
  const Eigen::Vector2d d = distort(Eigen::Vector2d(p.x() / p.z(), p.y() / p.z()));
  return {fx_ * d.x() + cx_, fy_ * d.y() + cy_};
}

bool CameraModel::project(const Eigen::Vector3d& p, Eigen::Vector2d* pixel,
                          double min_depth) const {
  if (!(p.z() > min_depth)) return false;
  *pixel = project(p);
  return true;
}

Eigen::Vector3d CameraModel::unproject(const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d d((pixel.x() - cx_) / fx_, (pixel.y() - cy_) / fy_);
  const Eigen::Vector2d n = undistort(d);
  return {n.x(), n.y(), 1.0};
}

Eigen::Vector2d CameraModel::undistortPixel(const Eigen::Vector2d& pixel) const {
  if (!distorted_) return pixel;
  const Eigen::Vector3d ray = unproject(pixel);
  return {fx_ * ray.x() + cx_, fy_ * ray.y() + cy_};
}

cv::Mat CameraModel::undistortImage(const cv::Mat& image) const {
  if (!distorted_) return image;
  if (map1_.empty() || map1_.cols != image.cols || map1_.rows != image.rows) {
    cv::Mat K = (cv::Mat_<double>(3, 3) << fx_, 0, cx_, 0, fy_, cy_, 0, 0, 1);
    cv::Mat D = (cv::Mat_<double>(1, 5) << dist_[0], dist_[1], dist_[2], dist_[3], dist_[4]);
    cv::initUndistortRectifyMap(K, D, cv::Mat(), K, image.size(), CV_16SC2, map1_, map2_);
  }
  cv::Mat out;
  cv::remap(image, out, map1_, map2_, cv::INTER_LINEAR);
  return out;
}

CameraModel CameraModel::scaled(double s) const {
  // Pixel centres: u' + 0.5 = s (u + 0.5).
  return CameraModel(static_cast<int>(std::lround(width_ * s)),
                     static_cast<int>(std::lround(height_ * s)), fx_ * s, fy_ * s,
                     (cx_ + 0.5) * s - 0.5, (cy_ + 0.5) * s - 0.5, dist_);
}

CameraModel CameraModel::pinhole() const {
  return CameraModel(width_, height_, fx_, fy_, cx_, cy_);
}

bool CameraModel::operator==(const CameraModel& o) const {
  return width_ == o.width_ && height_ == o.height_ && fx_ == o.fx_ && fy_ == o.fy_ &&
         cx_ == o.cx_ && cy_ == o.cy_ && dist_ == o.dist_;
}

}  // namespace slamaware
