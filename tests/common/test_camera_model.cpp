// Camera model: projection and unprojection are inverse; distortion matches OpenCV's.
#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
#include <random>

#include "common/camera_model.h"

using namespace slamaware;

namespace {
CameraModel distorted() {
  return CameraModel(640, 480, 525.0, 523.0, 319.5, 239.5, {-0.28, 0.07, 0.001, -0.0005, 0.01});
}
}  // namespace

TEST(CameraModel, ProjectUnprojectRoundTripPinhole) {
  const CameraModel cam(640, 480, 525, 525, 319.5, 239.5);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0, 640), v(0, 480), d(0.3, 10);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector2d px(u(rng), v(rng));
    const Eigen::Vector3d p = cam.unproject(px) * d(rng);
    EXPECT_LT((cam.project(p) - px).norm(), 1e-9);
  }
}

TEST(CameraModel, ProjectUnprojectRoundTripDistorted) {
  const CameraModel cam = distorted();
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(0, 639), v(0, 479);
  double worst = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector2d px(u(rng), v(rng));
    const Eigen::Vector3d ray = cam.unproject(px);
    EXPECT_DOUBLE_EQ(ray.z(), 1.0);
    worst = std::max(worst, (cam.project(ray * 2.5) - px).norm());
  }
  EXPECT_LT(worst, 1e-6) << "unproject must invert the distortion inside the image";
}

TEST(CameraModel, DistortionAgreesWithOpenCV) {
  const CameraModel cam = distorted();
  cv::Mat K = (cv::Mat_<double>(3, 3) << cam.fx(), 0, cam.cx(), 0, cam.fy(), cam.cy(), 0, 0, 1);
  cv::Mat D = (cv::Mat_<double>(1, 5) << -0.28, 0.07, 0.001, -0.0005, 0.01);
  std::vector<cv::Point3d> pts;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> xy(-0.5, 0.5);
  for (int i = 0; i < 200; ++i) pts.emplace_back(xy(rng), xy(rng), 1.0 + std::abs(xy(rng)));
  std::vector<cv::Point2d> cv_px;
  cv::projectPoints(pts, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, D, cv_px);
  for (size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector2d ours = cam.project(Eigen::Vector3d(pts[i].x, pts[i].y, pts[i].z));
    EXPECT_NEAR(ours.x(), cv_px[i].x, 1e-9);
    EXPECT_NEAR(ours.y(), cv_px[i].y, 1e-9);
  }
}

TEST(CameraModel, UndistortPixelAgreesWithOpenCV) {
  const CameraModel cam = distorted();
  cv::Mat K = (cv::Mat_<double>(3, 3) << cam.fx(), 0, cam.cx(), 0, cam.fy(), cam.cy(), 0, 0, 1);
  cv::Mat D = (cv::Mat_<double>(1, 5) << -0.28, 0.07, 0.001, -0.0005, 0.01);
  std::vector<cv::Point2d> in = {{10, 10}, {630, 20}, {320, 240}, {600, 470}, {100, 400}}, out;
  cv::undistortPoints(
      in, out, K, D, cv::noArray(), K,
      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-12));
  for (size_t i = 0; i < in.size(); ++i) {
    const Eigen::Vector2d ours = cam.undistortPixel(Eigen::Vector2d(in[i].x, in[i].y));
    EXPECT_NEAR(ours.x(), out[i].x, 1e-3);
    EXPECT_NEAR(ours.y(), out[i].y, 1e-3);
  }
}

TEST(CameraModel, BehindCameraIsNotProjected) {
  const CameraModel cam(640, 480, 500, 500, 320, 240);
  Eigen::Vector2d px;
  EXPECT_FALSE(cam.project(Eigen::Vector3d(0, 0, -1), &px));
  EXPECT_FALSE(cam.project(Eigen::Vector3d(0, 0, 0), &px));
  EXPECT_TRUE(cam.project(Eigen::Vector3d(0, 0, 1), &px));
  EXPECT_NEAR(px.x(), 320, 1e-12);
}

TEST(CameraModel, ScaledPyramidLevelKeepsRays) {
  const CameraModel cam(640, 480, 525, 525, 319.5, 239.5);
  const CameraModel half = cam.scaled(0.5);
  EXPECT_EQ(half.width(), 320);
  // The ray through a full-resolution pixel goes through (u + 0.5) / 2 - 0.5 at half size.
  const Eigen::Vector3d p(0.3, -0.2, 2.0);
  const Eigen::Vector2d full = cam.project(p), small = half.project(p);
  EXPECT_NEAR(small.x(), (full.x() + 0.5) * 0.5 - 0.5, 1e-9);
  EXPECT_NEAR(small.y(), (full.y() + 0.5) * 0.5 - 0.5, 1e-9);
}

TEST(CameraModel, UndistortImageStraightensLines) {
  // A straight line in the world is curved by barrel distortion; after undistortImage the
  // pixels of the rendered line lie on a straight line again.
  const CameraModel cam = distorted();
  cv::Mat img(480, 640, CV_8UC1, cv::Scalar(0));
  for (double x = -0.55; x <= 0.55; x += 0.0005) {
    const Eigen::Vector2d px = cam.project(Eigen::Vector3d(x, 0.3, 1.0));
    if (cam.inImage(px))
      img.at<uint8_t>(static_cast<int>(std::lround(px.y())),
                      static_cast<int>(std::lround(px.x()))) = 255;
  }
  const cv::Mat und = cam.undistortImage(img);
  const double y_expected = cam.fy() * 0.3 + cam.cy();
  int on_line = 0, total = 0;
  for (int c = 40; c < 600; c += 8) {
    for (int r = 0; r < 480; ++r) {
      if (und.at<uint8_t>(r, c) > 100) {
        ++total;
        on_line += std::abs(r - y_expected) <= 1.5;
      }
    }
  }
  ASSERT_GT(total, 20);
  EXPECT_GT(on_line, total * 0.95);
}
