// TUM trajectory IO.
#include <gtest/gtest.h>

#include <fstream>

#include "common/tum.h"
#include "tests/support/test_support.h"

using namespace slamaware;

TEST(Tum, WriteReadRoundTrip) {
  std::vector<TimedPose> poses;
  for (int i = 0; i < 20; ++i) {
    Vector6d xi;
    xi << 0.1 * i, -0.2, 0.3 * i, 0.05 * i, 0.3, -0.1 * i;
    poses.push_back({1341841278.8427 + i * 0.033, expSE3(xi)});
  }
  const std::string path = test::tempDir("tum") + "/traj.txt";
  writeTum(path, poses);
  const auto back = readTum(path);
  ASSERT_EQ(back.size(), poses.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    EXPECT_NEAR(back[i].t, poses[i].t, 1e-6);
    EXPECT_LT((back[i].T_world_camera.matrix() - poses[i].T_world_camera.matrix()).norm(), 1e-7);
  }
}

TEST(Tum, ReadsSharedGroundTruth) {
  const std::string path = test::sharedData("sequences/tum_fr3_cabinet_keyframes/groundtruth.txt");
  SKIP_WITHOUT_SHARED_DATA(path);
  const auto poses = readTum(path);
  ASSERT_EQ(poses.size(), 58u);
  EXPECT_NEAR(poses[0].t, 1341841278.8427, 1e-4);
  EXPECT_NEAR(poses[0].T_world_camera.translation().x(), -2.5508, 1e-9);
}

TEST(Tum, MalformedLineNamesFileAndLine) {
  const std::string path = test::tempDir("tum_bad") + "/bad.txt";
  std::ofstream(path) << "# comment\n1 2 3 4 0 0 0 1\n2 2 3 x 0 0 0 1\n";
  try {
    readTum(path);
    FAIL();
  } catch (const TumError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.txt:3"), std::string::npos) << e.what();
  }
  std::ofstream(path) << "1 2 3 4 0 0 0 3\n";
  EXPECT_THROW(readTum(path), TumError) << "non-unit quaternion";
}

TEST(Tum, ClosestPose) {
  std::vector<TimedPose> p(3);
  p[0].t = 1.0;
  p[1].t = 2.0;
  p[2].t = 3.0;
  EXPECT_EQ(closestPose(p, 2.1, 0.2), &p[1]);
  EXPECT_EQ(closestPose(p, 2.6, 0.2), nullptr);
  EXPECT_EQ(closestPose(p, 0.95, 0.1), &p[0]);
}
