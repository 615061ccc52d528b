// Two-view initialisation recovers the relative pose (up to scale) and the structure from
// synthetic correspondences, chooses F for a 3D scene and H for a plane, and refuses views
// without parallax.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "procs/slam/geometry/two_view.h"
#include "tests/slam/synthetic_scene.h"

using namespace slamaware;
using namespace slamaware::slam;

namespace {

struct Correspondences {
  std::vector<Eigen::Vector2d> ref, cur;
  std::vector<Eigen::Vector3d> points_ref;
};

Correspondences observe(const std::vector<Eigen::Vector3d>& points, const SE3& T_cur_ref,
                        double noise_px, double outlier_ratio, uint64_t seed) {
  const test::PinholeCamera cam;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0, noise_px);
  std::uniform_real_distribution<double> u01(0, 1), ux(0, cam.width), uy(0, cam.height);
  Correspondences c;
  for (const auto& p : points) {
    const Eigen::Vector3d q = T_cur_ref * p;
    if (p.z() <= 0 || q.z() <= 0) continue;
    Eigen::Vector2d a = cam.project(p), b = cam.project(q);
    if (!cam.inImage(a) || !cam.inImage(b)) continue;
    a += Eigen::Vector2d(noise(rng), noise(rng));
    b += Eigen::Vector2d(noise(rng), noise(rng));
    if (u01(rng) < outlier_ratio) b = {ux(rng), uy(rng)};
    c.ref.push_back(a);
    c.cur.push_back(b);
    c.points_ref.push_back(p);
  }
  return c;
}

double translationAngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180 / M_PI;
}

}  // namespace

TEST(TwoView, RecoversPoseAndStructureOfA3dScene) {
  const auto points = test::randomPoints(300, 1.5, 1.0, 3.0, 6.0, 11);
  // The second camera moved 0.4 m sideways and forward and turned 5 degrees.
  const SE3 T_cur_ref = test::cameraAt({0.3, 0.05, 0.25}, {0.01, -0.08, 0.02});
  const Correspondences c = observe(points, T_cur_ref, 0.5, 0.1, 3);
  ASSERT_GT(c.ref.size(), 200u);
  InitOptions opt;
  const TwoViewResult r = reconstructTwoView(c.ref, c.cur, test::PinholeCamera().K(), opt, 42);
  ASSERT_TRUE(r.ok) << r.reason;
  EXPECT_EQ(r.model, 'F');
  EXPECT_LT(rotationAngle(r.T_cur_ref.linear().transpose() * T_cur_ref.linear()) * 180 / M_PI, 0.5);
  EXPECT_LT(translationAngleDeg(r.T_cur_ref.translation(), T_cur_ref.translation()), 3.0);
  // Structure up to the unknown scale: one ratio of true to estimated depth fits every point.
  std::vector<double> ratios;
  for (size_t i = 0; i < c.ref.size(); ++i)
    if (r.triangulated[i]) ratios.push_back(c.points_ref[i].z() / r.p_ref[i].z());
  ASSERT_FALSE(ratios.empty());
  std::nth_element(ratios.begin(), ratios.begin() + ratios.size() / 2, ratios.end());
  const double s = ratios[ratios.size() / 2];
  int good = 0, checked = 0;
  for (size_t i = 0; i < c.ref.size(); ++i) {
    if (!r.triangulated[i]) continue;
    ++checked;
    good += (r.p_ref[i] * s - c.points_ref[i]).norm() < 0.05 * c.points_ref[i].z();
  }
  EXPECT_GT(checked, 200);
  EXPECT_GT(good, 0.9 * checked);
}

// The candidate poses are refined on several threads; the result must be the one of a single
// thread, bit for bit, whatever the number of threads.
TEST(TwoView, TheResultDoesNotDependOnTheThreads) {
  const auto points = test::randomPoints(300, 1.5, 1.0, 3.0, 6.0, 11);
  const SE3 T_cur_ref = test::cameraAt({0.3, 0.05, 0.25}, {0.01, -0.08, 0.02});
  const Correspondences c = observe(points, T_cur_ref, 0.5, 0.1, 3);
  InitOptions opt;
  opt.threads = 1;
  const TwoViewResult one = reconstructTwoView(c.ref, c.cur, test::PinholeCamera().K(), opt, 42);
  ASSERT_TRUE(one.ok) << one.reason;
  for (int threads : {2, 3, 16}) {
    opt.threads = threads;
    const TwoViewResult r = reconstructTwoView(c.ref, c.cur, test::PinholeCamera().K(), opt, 42);
    ASSERT_TRUE(r.ok) << r.reason;
    EXPECT_TRUE(r.T_cur_ref.isApprox(one.T_cur_ref, 0)) << threads << " threads";
    EXPECT_EQ(r.triangulated, one.triangulated) << threads << " threads";
    EXPECT_EQ(r.p_ref, one.p_ref) << threads << " threads";
    EXPECT_EQ(r.model, one.model);
  }
}

TEST(TwoView, ChoosesTheHomographyForAPlane) {
  auto points = test::randomPoints(300, 1.5, 1.0, 4.0, 4.0, 5);  // all on the plane z = 4
  const SE3 T_cur_ref = test::cameraAt({0.5, 0.0, 0.1}, {0.0, -0.1, 0.0});
  const Correspondences c = observe(points, T_cur_ref, 0.5, 0.0, 4);
  InitOptions opt;
  const TwoViewResult r = reconstructTwoView(c.ref, c.cur, test::PinholeCamera().K(), opt, 7);
  ASSERT_TRUE(r.ok) << r.reason;
  EXPECT_EQ(r.model, 'H');
  EXPECT_LT(rotationAngle(r.T_cur_ref.linear().transpose() * T_cur_ref.linear()) * 180 / M_PI, 0.5);
  EXPECT_LT(translationAngleDeg(r.T_cur_ref.translation(), T_cur_ref.translation()), 3.0);
}

TEST(TwoView, RefusesAPureRotation) {
  const auto points = test::randomPoints(300, 1.5, 1.0, 3.0, 6.0, 8);
  const SE3 T_cur_ref = test::cameraAt({0.0, 0.0, 0.0}, {0.0, 0.1, 0.0});
  const Correspondences c = observe(points, T_cur_ref, 0.5, 0.0, 9);
  const TwoViewResult r =
      reconstructTwoView(c.ref, c.cur, test::PinholeCamera().K(), InitOptions(), 1);
  EXPECT_FALSE(r.ok);
}
