// slamaware-annotate on a hand-made session: the annotated video and the top-down picture are
// written even when the object table holds an object the map has not localised yet (no voxels, a
// NaN centroid, as `slamaware-ctl query` shows "(not localised)"): such an object was drawn from
// NaN corners and OpenCV died of SIGFPE, failing `make demo`.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "common/bus/image_msg.h"
#include "common/bus/system_config.h"
#include "slamaware/object_map_t.hpp"
#include "slamaware/point_cloud_t.hpp"
#include "slamaware/pose_t.hpp"
#include "tests/support/test_support.h"

using namespace slamaware;
namespace fs = std::filesystem;

namespace {

object_t object(int32_t id, const std::string& label, double x, int32_t voxels) {
  object_t o;
  o.id = id;
  o.map_id = 1;
  o.label = label;
  o.num_classes = 0;
  o.num_candidates = 0;
  o.num_views = 5;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < 3; ++k) {
    o.centroid[k] = voxels > 0 ? (k == 0 ? x : 0.0) : nan;
    o.extent[k] = voxels > 0 ? 0.1 : nan;
  }
  o.num_voxels = voxels;
  o.first_seen_utime = o.last_seen_utime = 0;
  return o;
}

// A session of 5 frames: poses along x, a map of 400 points on a 1 m square, and an object table
// with a localised mug and a cereal box that is not localised.
std::string writeSession(const std::string& dir) {
  const Channels ch;
  const std::string path = dir + "/session.lcm";
  lcm::LogFile log(path, "w");
  int64_t n = 0;
  point_cloud_t cloud;
  cloud.utime = 0;
  cloud.seq = 0;
  cloud.map_id = 1;
  cloud.keyframe_id = -1;
  cloud.full = true;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) {
      cloud.x.push_back(0.05f * static_cast<float>(i));
      cloud.y.push_back(0.05f * static_cast<float>(j));
      cloud.z.push_back(0.01f * static_cast<float>((i * j) % 3));
      cloud.r.push_back(100), cloud.g.push_back(120), cloud.b.push_back(140);
      cloud.depth_std.push_back(0.001f);
      cloud.keyframe_ids.push_back(0);
    }
  cloud.num_points = static_cast<int32_t>(cloud.x.size());
  cloud.num_keyframes = 0;
  test::writeEvent(log, ch.slam_map, cloud, n++);
  for (int32_t seq = 0; seq < 5; ++seq) {
    const cv::Mat frame(120, 160, CV_8UC3, cv::Scalar(30 * seq, 90, 160));
    test::writeEvent(log, ch.camera,
                     makeImageMessage(frame, seq * 33333, seq, image_t::PIXEL_FORMAT_RGB8), n++);
    pose_t p{};
    p.utime = seq * 33333;
    p.seq = seq;
    p.state = pose_t::STATE_TRACKING;
    p.position[0] = 0.1 * seq;
    p.position[1] = -0.5;
    p.position[2] = 0.8;
    p.orientation[0] = 1;
    p.map_id = 1;
    p.reference_keyframe_id = 0;
    test::writeEvent(log, ch.slam_pose, p, n++);
  }
  object_map_t m;
  m.utime = 4 * 33333;
  m.seq = 4;
  m.map_id = 1;
  m.saved_utime = 0;
  m.num_classes = 0;
  m.objects = {object(1, "coffee_mug", 0.3, 40), object(2, "cereal_box", 0, 0)};
  m.num_objects = static_cast<int32_t>(m.objects.size());
  test::writeEvent(log, ch.object_map, m, n++);
  return path;
}

}  // namespace

TEST(Annotate, WritesTheVideoAndTheTopDownMapWithAnObjectNotLocalisedYet) {
  const std::string dir = test::tempDir("annotate_not_localised");
  const std::string log = writeSession(dir);
  test::ChildProcess annotate(
      {test::binPath("slamaware-annotate"), log, "--out-dir", dir + "/out", "--log-level", "info"},
      dir + "/annotate.log");
  ASSERT_EQ(annotate.wait(std::chrono::seconds(60)), 0) << annotate.log();
  const cv::Mat top = cv::imread(dir + "/out/topdown.png");
  ASSERT_FALSE(top.empty()) << annotate.log();
  EXPECT_EQ(top.size(), cv::Size(800, 800));
  EXPECT_GT(fs::file_size(dir + "/out/annotated.mp4"), 0u);
  EXPECT_NE(annotate.log().find("with 2 objects"), std::string::npos) << annotate.log();
}
