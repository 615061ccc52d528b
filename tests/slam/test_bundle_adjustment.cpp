// Bundle adjustment (Ceres): from perturbed cameras and points it lowers the reprojection error
// to the noise level and brings a perturbed camera back to its true pose; fixed cameras stay put.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "procs/slam/optimization/bundle_adjustment.h"
#include "tests/slam/synthetic_scene.h"

using namespace slamaware;
using namespace slamaware::slam;

TEST(BundleAdjustment, LowersTheErrorAndRecoversAPerturbedPose) {
  const test::PinholeCamera cam;
  const auto points = test::randomPoints(250, 2.0, 1.5, 4.0, 8.0, 17);
  std::vector<SE3> truth;
  for (int k = 0; k < 5; ++k)
    truth.push_back(test::cameraAt({0.25 * k, 0.02 * k, 0.1 * k}, {0, -0.03 * k, 0.01 * k}));
  std::mt19937_64 rng(4);
  std::normal_distribution<double> noise(0, 0.5), wobble(0, 0.05);
  BaProblem ba;
  ba.fx = cam.fx;
  ba.fy = cam.fy;
  ba.cx = cam.cx;
  ba.cy = cam.cy;
  // Two fixed cameras fix the gauge (position, orientation and scale).
  for (int k = 0; k < 5; ++k) ba.cameras.push_back({truth[k], k < 2});
  for (const auto& p : points) {
    const int index = static_cast<int>(ba.points.size());
    ba.points.push_back({p + Eigen::Vector3d(wobble(rng), wobble(rng), wobble(rng)), false});
    for (int k = 0; k < 5; ++k) {
      const Eigen::Vector3d pc = truth[k] * p;
      const Eigen::Vector2d px = cam.project(pc) + Eigen::Vector2d(noise(rng), noise(rng));
      if (pc.z() > 0 && cam.inImage(px)) ba.observations.push_back({k, index, px, 1.0});
    }
  }
  Vector6d xi;
  xi << 0.08, -0.05, 0.04, 0.02, 0.015, -0.02;
  ba.cameras[3].T_camera_world = expSE3(xi) * truth[3];
  ba.cameras[4].T_camera_world = expSE3(-0.5 * xi) * truth[4];
  const SE3 fixed_before = ba.cameras[0].T_camera_world;

  BaOptions options;
  options.iterations = 30;
  const BaSummary s = bundleAdjust(&ba, options);
  ASSERT_TRUE(s.usable);
  EXPECT_GT(s.initial_rms_px, 5.0);
  EXPECT_LT(s.final_rms_px, 0.6);  // the pixel noise (0.5 px per axis) and no more
  EXPECT_TRUE(ba.cameras[0].T_camera_world.isApprox(fixed_before, 0));
  for (int k : {3, 4}) {
    EXPECT_LT(
        (ba.cameras[k].T_camera_world.inverse().translation() - truth[k].inverse().translation())
            .norm(),
        0.01)
        << "camera " << k;
    EXPECT_LT(angleBetween(ba.cameras[k].T_camera_world, truth[k]) * 180 / M_PI, 0.1)
        << "camera " << k;
  }
}

TEST(BundleAdjustment, AnOutlierDoesNotDragTheSolutionWithTheRobustLoss) {
  const test::PinholeCamera cam;
  const auto points = test::randomPoints(150, 2.0, 1.5, 4.0, 8.0, 3);
  const SE3 a = test::cameraAt({0, 0, 0}, {0, 0, 0}),
            b = test::cameraAt({0.5, 0, 0}, {0, -0.05, 0});
  BaProblem ba;
  ba.fx = cam.fx;
  ba.fy = cam.fy;
  ba.cx = cam.cx;
  ba.cy = cam.cy;
  ba.cameras = {{a, true}, {b, false}};
  for (size_t i = 0; i < points.size(); ++i) {
    ba.points.push_back({points[i], true});  // known structure: only camera b is estimated
    ba.observations.push_back({0, static_cast<int>(i), cam.project(a * points[i]), 1.0});
    Eigen::Vector2d px = cam.project(b * points[i]);
    if (i % 10 == 0) px += Eigen::Vector2d(40, -30);  // 10% gross outliers
    ba.observations.push_back({1, static_cast<int>(i), px, 1.0});
  }
  Vector6d xi;
  xi << 0.03, 0.02, -0.02, 0.01, 0.01, 0.0;
  ba.cameras[1].T_camera_world = expSE3(xi) * b;
  BaOptions options;
  options.iterations = 30;
  ASSERT_TRUE(bundleAdjust(&ba, options).usable);
  EXPECT_LT(
      (ba.cameras[1].T_camera_world.inverse().translation() - b.inverse().translation()).norm(),
      0.005);
}

// The cost function's analytic derivatives are those of its residual: central differences in
// every coordinate of the quaternion (not normalised: Ceres evaluates off the unit sphere too),
// the translation and the point, in front of the camera and with the point behind it (clamped
// depth: its derivative along z is zero).
TEST(BundleAdjustment, AnalyticJacobiansMatchFiniteDifferences) {
  BaProblem ba;
  ba.fx = 520;
  ba.fy = 515;
  ba.cx = 319.5;
  ba.cy = 239.5;
  BaObservation obs{0, 0, Eigen::Vector2d(300.0, 200.0), 1.0 / 1.44};
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 40; ++trial) {
    double q[4] = {0.3 * u(rng), 0.3 * u(rng), 0.3 * u(rng), 1 + 0.1 * u(rng)};
    double t[3] = {0.2 * u(rng), 0.2 * u(rng), 0.3 * u(rng)};
    double p[3] = {u(rng), u(rng), trial < 30 ? 3 + u(rng) : -3 + u(rng)};
    double r[2], jq[8], jt[6], jp[6];
    reprojectionResidual(ba, obs, q, t, p, r, jq, jt, jp);
    struct Block {
      double* x;
      int n;
      const double* j;
    } blocks[3] = {{q, 4, jq}, {t, 3, jt}, {p, 3, jp}};
    for (const Block& b : blocks) {
      for (int k = 0; k < b.n; ++k) {
        const double h = 1e-6, x0 = b.x[k];
        double rp[2], rm[2];
        b.x[k] = x0 + h;
        reprojectionResidual(ba, obs, q, t, p, rp, nullptr, nullptr, nullptr);
        b.x[k] = x0 - h;
        reprojectionResidual(ba, obs, q, t, p, rm, nullptr, nullptr, nullptr);
        b.x[k] = x0;
        for (int row = 0; row < 2; ++row) {
          const double numeric = (rp[row] - rm[row]) / (2 * h);
          EXPECT_NEAR(b.j[row * b.n + k], numeric, 1e-4 * (1 + std::abs(numeric)))
              << "trial " << trial << ", block of " << b.n << ", coordinate " << k << ", row "
              << row;
        }
      }
    }
  }
}
