// slamaware-harvest on a map and a recording made here: a synthetic scene fused by the object map
// engine (its mug labelled by a user, saved as the node saves it), and a log of the frames' camera,
// poses and images. Every view the tool writes frames the mug (IoU with the projection of its true
// 3D box), carries a mask of it, and is read back by the trainer's object-set reader.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "common/bus/image_msg.h"
#include "procs/objectmap/map_store.h"
#include "procs/objectmap/object_map.h"
#include "tests/objectmap/synthetic_world.h"
#include "tests/support/test_support.h"
#include "tools/train/trainer.h"

using namespace slamaware;
using namespace slamaware::objectmap;
using namespace slamaware::recognizer;

namespace {

cv::Rect projectedBox(const test::SyntheticWorld& w, const test::SyntheticObject& o, int frame) {
  const SE3 T_cw = w.pose(frame).inverse();
  double lo_x = 1e9, lo_y = 1e9, hi_x = -1e9, hi_y = -1e9;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d corner = o.centre + Eigen::Vector3d((k & 1 ? 1 : -1) * o.half_size.x(),
                                                              (k & 2 ? 1 : -1) * o.half_size.y(),
                                                              (k & 4 ? 1 : -1) * o.half_size.z());
    const Eigen::Vector2d px = w.camera().project(T_cw * corner);
    lo_x = std::min(lo_x, px.x()), lo_y = std::min(lo_y, px.y());
    hi_x = std::max(hi_x, px.x()), hi_y = std::max(hi_y, px.y());
  }
  return cv::Rect(cv::Point(static_cast<int>(lo_x), static_cast<int>(lo_y)),
                  cv::Point(static_cast<int>(hi_x), static_cast<int>(hi_y)));
}

double iou(const cv::Rect& a, const cv::Rect& b) {
  const double inter = (a & b).area();
  return inter / (a.area() + b.area() - inter);
}

}  // namespace

TEST(Harvest, TheLabelledObjectsViewsAreCutWithTheirMasksAndReadBackAsAnObjectSet) {
  const std::string dir = test::tempDir("harvest");
  const test::SyntheticWorld w({}, test::SyntheticWorld::defaultObjects());
  const int frames = 40;
  {
    ObjectMapEngine e{ObjectMapOptions{}};
    std::string why;
    ASSERT_TRUE(e.onCameraInfo(w.cameraInfo(), &why)) << why;
    const auto clouds = w.keyframeClouds(1);
    for (int f = 0; f < frames; ++f) {
      for (const auto& c : clouds) {
        if (c.seq != f) continue;
        ASSERT_TRUE(e.onMap(c, &why)) << why;
      }
      ASSERT_TRUE(e.onPose(w.poseMessage(f, 1), &why)) << why;
      ASSERT_TRUE(e.onProposals(w.proposals(f, 1), &why)) << why;
      ASSERT_TRUE(e.onDetections(w.detections(f, 1), &why)) << why;
    }
    e.regroup();
    int32_t mug = -1;
    for (const auto& o : e.objectMap().objects)
      if (o.label == "coffee_mug") mug = o.id;
    ASSERT_GE(mug, 0);
    object_query_t q{};
    q.kind = object_query_t::KIND_LABEL;
    q.object_id = mug;
    q.label = "my_mug";
    ASSERT_EQ(e.label(q).error, "");
    MapStore store(dir + "/map");
    std::string lock_why;
    ASSERT_TRUE(store.lock(&lock_why)) << lock_why;
    store.save(e.snapshot());
  }
  {
    lcm::LogFile log(dir + "/session.lcm", "w");
    int64_t n = 0;
    test::writeEvent(log, "CAMERA_INFO", w.cameraInfo(), n++);
    cv::Mat img(w.camera().height(), w.camera().width(), CV_8UC3);
    cv::randu(img, 0, 255);
    for (int f = 0; f < frames; ++f) {
      test::writeEvent(log, "SLAM_POSE", w.poseMessage(f, 1), n++);
      test::writeEvent(log, "CAMERA",
                       makeImageMessage(img, w.utime(f), f, image_t::PIXEL_FORMAT_JPEG), n++);
    }
  }
  const std::string out = dir + "/harvested";
  const std::string cmd = test::binPath("slamaware-harvest") + " " + dir + "/session.lcm --map " +
                          dir + "/map --out " + out + " 2>&1";
  std::string printed;
  FILE* p = popen(cmd.c_str(), "r");
  char buf[4096];
  size_t got;
  while ((got = fread(buf, 1, sizeof(buf), p)) > 0) printed.append(buf, got);
  ASSERT_EQ(pclose(p), 0) << printed;
  EXPECT_NE(printed.find("WRITTEN"), std::string::npos) << printed;

  const std::vector<LabeledCrop> crops = collectNamedCrops(out, 0);
  const test::SyntheticObject& truth = w.objects()[0];  // the coffee mug
  int mugs = 0;
  for (const LabeledCrop& c : crops) {
    if (c.category != "my_mug") continue;
    ++mugs;
    EXPECT_TRUE(c.real) << "a harvested set is photographed (not rendered)";
    ASSERT_FALSE(c.mask_path.empty()) << c.path;
    const cv::Mat crop = cv::imread(c.path), mask = cv::imread(c.mask_path, cv::IMREAD_GRAYSCALE);
    ASSERT_EQ(crop.size(), mask.size()) << c.path;
    EXPECT_GT(cv::countNonZero(mask), mask.total() / 3) << c.mask_path;
    // The view's frame is in its name (<instance>_1_<seq>_crop.png), its place in _loc.txt.
    std::string name = std::filesystem::path(c.path).filename().string();
    name = name.substr(0, name.size() - std::string("_crop.png").size());
    const int seq = std::stoi(name.substr(name.rfind('_') + 1));
    std::ifstream loc(c.path.substr(0, c.path.size() - std::string("_crop.png").size()) +
                      "_loc.txt");
    int x = -1, y = -1;
    char comma;
    ASSERT_TRUE(loc >> x >> comma >> y) << c.path;
    const cv::Rect box(x, y, crop.cols, crop.rows);
    EXPECT_GE(iou(box, projectedBox(w, truth, seq)), 0.5)
        << c.path << " " << box << " vs " << projectedBox(w, truth, seq);
  }
  EXPECT_GE(mugs, frames * 3 / 4) << printed;
  // Every 4th frame of the recording: a quarter of the views (frames 0, 4, ..., 36).
  const std::string sparse = dir + "/every4";
  ASSERT_EQ(std::system((test::binPath("slamaware-harvest") + " " + dir + "/session.lcm --map " +
                         dir + "/map --out " + sparse + " --every 4 > /dev/null 2>&1")
                            .c_str()),
            0);
  int sparse_mugs = 0;
  for (const LabeledCrop& c : collectNamedCrops(sparse, 0)) sparse_mugs += c.category == "my_mug";
  EXPECT_EQ(sparse_mugs * 4, mugs) << "all 40 frames give a view, so every 4th gives 10";
  std::ifstream set(out + "/set.yaml");
  const std::string yaml((std::istreambuf_iterator<char>(set)), {});
  EXPECT_NE(yaml.find("source: harvest"), std::string::npos) << yaml;
}
