// Object sets: the promised views per instance in the UW layout (crop, mask, location), readable
// by the common ObjectSet reader, byte-identical for one seed; a contact sheet of the crops
// (build/synth-sheets/objects.png). Also the shipped object-set configs.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <set>

#include "common/dataset.h"
#include "common/image_codec.h"
#include "tests/support/test_support.h"
#include "tests/synth/synth_test_util.h"
#include "tools/synth/categories.h"
#include "tools/synth/synth_options.h"
#include "tools/synth/writers.h"

using namespace slamaware;
using namespace slamaware::synth;
namespace fs = std::filesystem;

namespace {

ObjectSetOptions smallSet() {
  ObjectSetOptions o;
  o.name = "small";
  o.seed = 77;
  o.categories = {"coffee_mug", "cereal_box", "apple"};
  o.instances = 2;
  o.azimuth_step_deg = 30;  // 12 per elevation
  o.backgrounds = 2;
  return o;
}

}  // namespace

TEST(SynthObjectSet, EveryInstanceHasThePromisedViewsInTheUwLayout) {
  const std::string dir = test::tempDir("synth_objects");
  const ObjectSetOptions o = smallSet();
  writeObjectSet(o, dir, -1, false);
  const ObjectSet set = ObjectSet::open(dir);
  EXPECT_EQ(set.categories(), (std::vector<std::string>{"apple", "cereal_box", "coffee_mug"}));
  const auto inst = set.instances();
  for (const auto& c : o.categories)
    EXPECT_EQ(inst.at(c), (std::vector<std::string>{c + "_1", c + "_2"}));
  std::map<std::string, std::set<std::pair<int, int>>> views;
  std::vector<cv::Mat> sheet;
  std::vector<std::string> captions;
  for (const auto& v : set.views()) {
    views[v.instance].insert({v.video, v.frame});
    ASSERT_FALSE(v.mask_path.empty()) << v.crop_path;
    ASSERT_TRUE(v.has_location) << v.crop_path;
    const cv::Mat crop = readImage(v.crop_path), mask = readImage(v.mask_path, true);
    ASSERT_EQ(crop.size(), mask.size()) << v.crop_path;
    EXPECT_GE(v.loc_x, 0);
    EXPECT_GE(v.loc_y, 0);
    EXPECT_LE(v.loc_x + crop.cols, 640);
    EXPECT_LE(v.loc_y + crop.rows, 480);
    // The object fills the middle of its crop, with background around it (like the UW crops).
    const double fill = cv::countNonZero(mask) / static_cast<double>(mask.total());
    EXPECT_GT(fill, 0.15) << v.crop_path;
    EXPECT_LT(fill, 0.9) << v.crop_path;
    EXPECT_EQ(mask.at<uint8_t>(0, 0), 0) << "the corner of a crop is background: " << v.crop_path;
    if (v.frame % 4 == 1 && sheet.size() < 72) {
      sheet.push_back(crop);
      captions.push_back(v.instance + " " + std::to_string(v.video) + "_" +
                         std::to_string(v.frame));
    }
  }
  for (const auto& [name, vs] : views) {
    EXPECT_EQ(vs.size(), 36u) << name;  // 3 elevations x 12 azimuths
    std::set<int> videos;
    for (const auto& p : vs) videos.insert(p.first);
    EXPECT_EQ(videos, (std::set<int>{1, 2, 4})) << name;
  }
  EXPECT_TRUE(fs::exists(dir + "/set.yaml"));
  const fs::path sheets = fs::path(SLAMAWARE_BIN_DIR).parent_path() / "synth-sheets";
  fs::create_directories(sheets);
  ASSERT_TRUE(
      cv::imwrite((sheets / "objects.png").string(), contactSheet(sheet, captions, 9, 128, 128)));
}

TEST(SynthObjectSet, SameSeedSameBytes) {
  ObjectSetOptions o = smallSet();
  o.categories = {"soda_can"};
  o.instances = 1;
  o.azimuth_step_deg = 90;
  const std::string a = test::tempDir("synth_objects_a"), b = test::tempDir("synth_objects_b"),
                    c = test::tempDir("synth_objects_c");
  writeObjectSet(o, a, -1, false);
  writeObjectSet(o, b, -1, false);
  writeObjectSet(o, c, 78, false);
  const auto ha = synth_test::treeHashes(a), hb = synth_test::treeHashes(b),
             hc = synth_test::treeHashes(c);
  EXPECT_EQ(ha.size(), 1u + 3u * 4u * 3u);  // set.yaml + 12 views x (crop, mask, loc)
  EXPECT_EQ(ha, hb);
  EXPECT_NE(ha.at("soda_can/soda_can_1/soda_can_1_1_1_crop.png"),
            hc.at("soda_can/soda_can_1/soda_can_1_1_1_crop.png"));
}

TEST(SynthObjectSet, ShippedConfigsPromiseTheTrainingSets) {
  const ObjectSetOptions five = loadObjectSetOptions(test::sourcePath("config/objects/uw5.yaml"));
  EXPECT_EQ(five.categories, paperClasses());
  EXPECT_GE(five.instances, 10);
  const ObjectSetOptions all = loadObjectSetOptions(test::sourcePath("config/objects/uw51.yaml"));
  ASSERT_EQ(all.categories, std::vector<std::string>{"all"});
  EXPECT_GE(all.instances, 3);
  for (const auto* o : {&five, &all}) {
    EXPECT_EQ(o->elevations_deg, (std::vector<double>{30, 45, 60}));
    EXPECT_DOUBLE_EQ(o->azimuth_step_deg, 5);
  }
  // Every scene config of the suite loads and asks for 300-600 frames and 3-8 objects.
  int scenes = 0;
  for (const auto& e : fs::directory_iterator(test::sourcePath("config/scenes"))) {
    if (e.path().extension() != ".yaml" || e.path().stem() == "sample") continue;
    const SceneOptions s = loadSceneOptions(e.path().string());
    EXPECT_GE(s.frames, 300) << e.path();
    EXPECT_LE(s.frames, 600) << e.path();
    EXPECT_GE(s.objects.count, 3) << e.path();
    EXPECT_LE(s.objects.count, 8) << e.path();
    EXPECT_EQ(s.name, e.path().stem().string());
    // The camera circles the table at 0.7-1.5 m from its centre.
    const TrajectoryOptions& t = s.trajectory;
    EXPECT_GE(std::hypot(t.radius_min, t.height_min), 0.7) << e.path();
    EXPECT_LE(std::hypot(t.radius_max, t.height_max), 1.5) << e.path();
    ++scenes;
  }
  EXPECT_GE(scenes, 8);
}
