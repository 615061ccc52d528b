// Readers of the sequence folder and object set layouts (DATASETS.md), on the real data and on
// folders written by our own writers.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "common/dataset.h"
#include "common/image_codec.h"
#include "tests/support/test_support.h"

using namespace slamaware;
namespace fs = std::filesystem;

TEST(Dataset, MiddleburyTempleRing) {
  const std::string dir = test::sharedData("sequences/middlebury_temple_ring");
  SKIP_WITHOUT_SHARED_DATA(dir);
  const SequenceFolder seq = SequenceFolder::open(dir);
  EXPECT_EQ(seq.info().name, "middlebury_temple_ring");
  EXPECT_EQ(seq.size(), 47u);
  EXPECT_EQ(seq.info().frames, 47);
  EXPECT_DOUBLE_EQ(seq.info().camera.fx(), 1520.4);
  EXPECT_DOUBLE_EQ(seq.info().camera.cy(), 246.87);
  EXPECT_DOUBLE_EQ(seq.timestamp(5), 5.0);  // no timestamps.txt: i / fps
  EXPECT_EQ(seq.info().classes, std::vector<std::string>{"temple"});
  ASSERT_TRUE(seq.hasGroundTruth());
  EXPECT_EQ(seq.groundTruth().size(), 47u);
  const auto boxes = seq.boxes();
  ASSERT_EQ(boxes.size(), 47u);
  EXPECT_EQ(boxes[0].cls, "temple");
  EXPECT_DOUBLE_EQ(boxes[0].w, 456.2);
  const auto objects = seq.objects();
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_NEAR(objects[0].size.y(), 0.159645, 1e-9);
  EXPECT_EQ(seq.depthPath(0), "");
}

TEST(Dataset, TumCabinetTimestamps) {
  const std::string dir = test::sharedData("sequences/tum_fr3_cabinet_keyframes");
  SKIP_WITHOUT_SHARED_DATA(dir);
  const SequenceFolder seq = SequenceFolder::open(dir);
  EXPECT_EQ(seq.size(), 58u);
  EXPECT_GT(seq.timestamp(1), seq.timestamp(0));
  EXPECT_FALSE(seq.hasObjects());
  // Frame times match the ground-truth times (same clock).
  const auto gt = seq.groundTruth();
  EXPECT_NE(closestPose(gt, seq.timestamp(10), 0.02), nullptr);
}

TEST(Dataset, UwObjectSet) {
  const std::string dir = test::sharedData("objects/uw_rgbd_apple_ball");
  SKIP_WITHOUT_SHARED_DATA(dir);
  const ObjectSet set = ObjectSet::open(dir);
  EXPECT_EQ(set.categories(), (std::vector<std::string>{"apple", "ball"}));
  EXPECT_EQ(set.views().size(), 1008u);
  const auto inst = set.instances();
  EXPECT_EQ(inst.at("apple").size(), 5u);
  EXPECT_EQ(inst.at("ball").size(), 3u);
  const ObjectView& v = set.views().front();
  EXPECT_EQ(v.category, "apple");
  EXPECT_FALSE(v.mask_path.empty());
  EXPECT_TRUE(v.has_location);
  const cv::Mat crop = readImage(v.crop_path);
  EXPECT_GT(crop.cols, 10);
}

TEST(Dataset, WrittenSequenceReadsBack) {
  const std::string dir = test::tempDir("dataset_rt");
  fs::create_directories(dir + "/rgb");
  SequenceInfo info;
  info.name = "toy";
  info.fps = 30;
  info.frames = 3;
  info.camera = CameraModel(64, 48, 50, 51, 31.5, 23.5, {0.1, 0, 0, 0, 0});
  info.classes = {"bowl", "cap"};
  info.notes = "written by a test";
  writeSequenceInfo(dir + "/sequence.yaml", info);
  for (int i = 0; i < 3; ++i)
    writeImage(dir + "/rgb/00000" + std::to_string(i) + ".png",
               cv::Mat(48, 64, CV_8UC3, cv::Scalar(i, 2, 3)));
  writeBoxes(dir + "/boxes.csv", {{1, 2.5, 3, 10, 11, "bowl", "bowl_7"}});
  GroundTruthObject o;
  o.instance = "bowl_7";
  o.cls = "bowl";
  o.center = Eigen::Vector3d(0.1, 0.2, 0.3);
  o.size = Eigen::Vector3d(0.15, 0.15, 0.07);
  writeObjects(dir + "/objects.csv", {o});
  const SequenceFolder seq = SequenceFolder::open(dir);
  EXPECT_EQ(seq.info().camera, info.camera);
  EXPECT_EQ(seq.info().classes, info.classes);
  EXPECT_EQ(seq.info().notes, info.notes);
  EXPECT_NEAR(seq.timestamp(2), 2.0 / 30, 1e-12);
  EXPECT_EQ(seq.boxes()[0].instance, "bowl_7");
  EXPECT_DOUBLE_EQ(seq.boxes()[0].x, 2.5);
  EXPECT_NEAR(seq.objects()[0].size.z(), 0.07, 1e-9);
}

TEST(Dataset, BadFoldersAreRefusedWithTheFileNamed) {
  const std::string dir = test::tempDir("dataset_bad");
  auto errorOf = [&]() -> std::string {
    try {
      SequenceFolder::open(dir);
    } catch (const DatasetError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(errorOf().find("sequence.yaml"), std::string::npos);
  std::ofstream(dir + "/sequence.yaml") << "name: x\nfps: 10\n";
  EXPECT_NE(errorOf().find("camera"), std::string::npos);
  std::ofstream(dir + "/sequence.yaml") << "name: x\nfps: 10\ncamera: {width: 4, height: 4, fx: 1, "
                                           "fy: 1, cx: 1, cy: 1, distortion: [1, 2]}\n";
  EXPECT_NE(errorOf().find("5 values"), std::string::npos);
  std::ofstream(dir + "/sequence.yaml")
      << "name: x\nfps: 10\ncamera: {width: 4, height: 4, fx: 1, fy: 1, cx: 1, cy: 1}\n";
  EXPECT_NE(errorOf().find("rgb"), std::string::npos);
  fs::create_directories(dir + "/rgb");
  writeImage(dir + "/rgb/0.png", cv::Mat(4, 4, CV_8UC3, cv::Scalar(1, 2, 3)));
  std::ofstream(dir + "/timestamps.txt") << "0 0.5\n7 1.0\n";
  EXPECT_NE(errorOf().find("timestamps.txt:2"), std::string::npos) << errorOf();
  fs::remove(dir + "/timestamps.txt");
  const SequenceFolder seq = SequenceFolder::open(dir);
  // Not numbers, numbers that are not finite, and frame numbers beyond int (were undefined
  // behaviour in the conversion: found while writing fuzz_datasets).
  for (const char* row :
       {"0,1,2,3,abc,bowl,bowl_1", "0,1,2,3,nan,bowl,bowl_1", "0,1,inf,3,4,bowl,bowl_1",
        "1e300,1,2,3,4,bowl,bowl_1", "1.5,1,2,3,4,bowl,bowl_1"}) {
    std::ofstream(dir + "/boxes.csv") << "frame,x,y,w,h,class,instance\n" << row << "\n";
    try {
      seq.boxes();
      ADD_FAILURE() << row << " must be refused";
    } catch (const DatasetError& e) {
      EXPECT_NE(std::string(e.what()).find("boxes.csv:2"), std::string::npos) << e.what();
    }
  }
  // A value of the wrong type in sequence.yaml names the file (yaml-cpp's own exception escaped).
  std::ofstream(dir + "/sequence.yaml") << "name: x\nfps: 10\nframes: many\ncamera: {width: 4, "
                                           "height: 4, fx: 1, fy: 1, cx: 1, cy: 1}\n";
  EXPECT_NE(errorOf().find("sequence.yaml"), std::string::npos) << errorOf();
  std::ofstream(dir + "/sequence.yaml")
      << "name: x\nfps: .inf\ncamera: {width: 4, height: 4, fx: 1, fy: 1, cx: 1, cy: 1}\n";
  EXPECT_NE(errorOf().find("fps"), std::string::npos) << errorOf();
}

TEST(Dataset, ObjectSetLayoutErrors) {
  const std::string dir = test::tempDir("objset_bad");
  EXPECT_THROW(ObjectSet::open(dir), DatasetError);  // empty
  fs::create_directories(dir + "/bowl/cup_1");
  writeImage(dir + "/bowl/cup_1/cup_1_1_1_crop.png", cv::Mat(4, 4, CV_8UC3));
  EXPECT_THROW(ObjectSet::open(dir), DatasetError);  // instance not named after its category
}
