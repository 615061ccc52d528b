// SE(3)/Sim(3) helpers: exp/log inverse, message round trip, Umeyama alignment.
#include <gtest/gtest.h>

#include <random>

#include "common/geometry.h"

using namespace slamaware;

TEST(Geometry, ExpLogSE3RoundTrip) {
  std::mt19937 rng(4);
  std::normal_distribution<double> n(0, 0.8);
  for (int i = 0; i < 200; ++i) {
    Vector6d xi;
    for (int k = 0; k < 6; ++k) xi[k] = n(rng);
    if (xi.tail<3>().norm() > 3.0) continue;  // log is unique only for angles < pi
    EXPECT_LT((logSE3(expSE3(xi)) - xi).norm(), 1e-9);
  }
}

TEST(Geometry, SmallRotationExp) {
  const Eigen::Vector3d w(1e-14, -2e-14, 0);
  EXPECT_LT((expSO3(w) - Eigen::Matrix3d::Identity()).norm(), 1e-13);
}

TEST(Geometry, MessageArraysRoundTrip) {
  const SE3 T = expSE3((Vector6d() << 0.1, -2, 3, 0.4, -0.5, 2.0).finished());
  double pos[3], q[4];
  se3ToArrays(T, pos, q);
  EXPECT_GE(q[0], 0.0);
  EXPECT_NEAR(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1.0, 1e-12);
  const SE3 back = se3FromArrays(pos, q);
  EXPECT_LT((back.matrix() - T.matrix()).norm(), 1e-12);
}

TEST(Geometry, UmeyamaRecoversSimilarity) {
  Sim3 truth;
  truth.s = 2.7;
  truth.R = expSO3(Eigen::Vector3d(0.3, -1.1, 0.5));
  truth.t = Eigen::Vector3d(1, -4, 0.5);
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0, 1);
  std::vector<Eigen::Vector3d> src, dst;
  for (int i = 0; i < 50; ++i) {
    src.emplace_back(n(rng), n(rng), n(rng));
    dst.push_back(truth * src.back());
  }
  const Sim3 est = alignUmeyama(src, dst, true);
  EXPECT_NEAR(est.s, truth.s, 1e-9);
  EXPECT_LT((est.R - truth.R).norm(), 1e-9);
  EXPECT_LT((est.t - truth.t).norm(), 1e-9);
  const Sim3 rigid = alignUmeyama(src, dst, false);
  EXPECT_DOUBLE_EQ(rigid.s, 1.0);
  EXPECT_LT((est.inverse() * est).matrix().isApprox(Eigen::Matrix4d::Identity(), 1e-12) ? 0 : 1, 1);
}

TEST(Geometry, UmeyamaNeedsThreePoints) {
  const Sim3 s = alignUmeyama({Eigen::Vector3d(1, 2, 3)}, {Eigen::Vector3d(4, 5, 6)}, true);
  EXPECT_DOUBLE_EQ(s.s, 1.0);
  EXPECT_TRUE(s.R.isIdentity());
}

TEST(Geometry, Sim3AppliedToPose) {
  Sim3 S;
  S.s = 2;
  S.R = expSO3(Eigen::Vector3d(0, 0, M_PI / 2));
  S.t = Eigen::Vector3d(1, 0, 0);
  SE3 T = SE3::Identity();
  T.translation() = Eigen::Vector3d(1, 0, 0);
  const SE3 out = S.apply(T);
  EXPECT_LT((out.translation() - Eigen::Vector3d(1, 2, 0)).norm(), 1e-12);
  EXPECT_LT((out.linear() - S.R).norm(), 1e-12);
}
