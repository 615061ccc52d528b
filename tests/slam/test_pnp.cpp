// PnP: the pose of a camera from 3D points and their pixels, with outliers, by RANSAC over
// minimal samples and a robust refinement; and the motion-only optimiser that refines a pose
// from a poor start and flags wrong matches.
#include <gtest/gtest.h>

#include <random>

#include "procs/slam/geometry/pnp.h"
#include "procs/slam/optimization/pose_optimizer.h"
#include "tests/slam/synthetic_scene.h"

using namespace slamaware;
using namespace slamaware::slam;

namespace {

struct Observations {
  std::vector<Eigen::Vector3d> pw;
  std::vector<Eigen::Vector2d> px;
  std::vector<bool> outlier;
};

Observations observe(const SE3& T_camera_world, int n, double noise_px, double outlier_ratio,
                     uint64_t seed) {
  const test::PinholeCamera cam;
  const auto points = test::randomPoints(n, 2.0, 1.5, 2.0, 8.0, seed);
  std::mt19937_64 rng(seed + 1);
  std::normal_distribution<double> noise(0, noise_px);
  std::uniform_real_distribution<double> u01(0, 1), ux(0, cam.width), uy(0, cam.height);
  Observations o;
  for (const auto& p : points) {
    const Eigen::Vector3d pc = T_camera_world * p;
    if (pc.z() <= 0) continue;
    Eigen::Vector2d px = cam.project(pc) + Eigen::Vector2d(noise(rng), noise(rng));
    if (!cam.inImage(px)) continue;
    const bool out = u01(rng) < outlier_ratio;
    if (out) px = {ux(rng), uy(rng)};
    o.pw.push_back(p);
    o.px.push_back(px);
    o.outlier.push_back(out);
  }
  return o;
}

}  // namespace

TEST(Pnp, RecoversThePoseDespiteAThirdOfOutliers) {
  const SE3 T = test::cameraAt({0.4, -0.2, 0.3}, {0.05, 0.2, -0.1});
  const Observations o = observe(T, 300, 0.7, 0.3, 21);
  ASSERT_GT(o.pw.size(), 150u);
  const test::PinholeCamera cam;
  PnpOptions opt;
  const PnpResult r = solvePnpRansac(o.pw, o.px, std::vector<double>(o.pw.size(), 1.0), cam.fx,
                                     cam.fy, cam.cx, cam.cy, opt, 99);
  ASSERT_TRUE(r.ok);
  EXPECT_LT((r.T_camera_world.inverse().translation() - T.inverse().translation()).norm(), 0.02);
  EXPECT_LT(angleBetween(r.T_camera_world, T) * 180 / M_PI, 0.3);
  int agree = 0;
  for (size_t i = 0; i < o.pw.size(); ++i) agree += r.inliers[i] == !o.outlier[i];
  EXPECT_GT(agree, 0.97 * o.pw.size());
  // Deterministic for a seed.
  const PnpResult again = solvePnpRansac(o.pw, o.px, std::vector<double>(o.pw.size(), 1.0), cam.fx,
                                         cam.fy, cam.cx, cam.cy, opt, 99);
  EXPECT_TRUE(again.T_camera_world.isApprox(r.T_camera_world, 0));
}

TEST(Pnp, FailsWithoutEnoughSupport) {
  const SE3 T = test::cameraAt({0, 0, 0}, {0, 0, 0});
  const Observations o = observe(T, 60, 0.5, 1.0, 5);  // every match wrong
  const test::PinholeCamera cam;
  const PnpResult r = solvePnpRansac(o.pw, o.px, std::vector<double>(o.pw.size(), 1.0), cam.fx,
                                     cam.fy, cam.cx, cam.cy, PnpOptions(), 1);
  EXPECT_FALSE(r.ok);
}

TEST(PoseOptimizer, RefinesAPerturbedPoseAndFlagsOutliers) {
  const SE3 T = test::cameraAt({0.1, 0.2, -0.1}, {0.02, -0.05, 0.01});
  const Observations o = observe(T, 200, 0.5, 0.15, 8);
  std::vector<PoseObservation> obs;
  for (size_t i = 0; i < o.pw.size(); ++i) obs.push_back({o.pw[i], o.px[i], 1.0, false});
  Vector6d xi;
  xi << 0.05, -0.04, 0.06, 0.02, -0.03, 0.02;  // 5 cm and ~2.5 degrees off
  SE3 estimate = expSE3(xi) * T;
  const test::PinholeCamera cam;
  const int inliers = optimizePose(&estimate, obs, cam.fx, cam.fy, cam.cx, cam.cy);
  EXPECT_LT((estimate.inverse().translation() - T.inverse().translation()).norm(), 0.01);
  EXPECT_LT(angleBetween(estimate, T) * 180 / M_PI, 0.2);
  int agree = 0;
  for (size_t i = 0; i < obs.size(); ++i) agree += obs[i].outlier == o.outlier[i];
  EXPECT_GT(agree, 0.95 * obs.size());
  EXPECT_NEAR(inliers, std::count(o.outlier.begin(), o.outlier.end(), false), 0.05 * obs.size());
}
