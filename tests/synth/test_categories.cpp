// The 51 categories: every one builds, has a plausible size, is a closed outward-facing solid,
// renders to a visible object, and two seeds give two different instances. Writes a contact sheet
// of all of them (build/synth-sheets/categories.png) for a person to look at.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "tools/synth/categories.h"
#include "tools/synth/rasterizer.h"
#include "tools/synth/sensor.h"
#include "tools/synth/textures.h"
#include "tools/synth/writers.h"

using namespace slamaware::synth;
namespace fs = std::filesystem;

namespace {

struct Shot {
  cv::Mat image;
  int64_t pixels = 0;
  int box_w = 0, box_h = 0;
};

// The object alone on a grey mat, seen from 35 degrees above at a distance that fits it.
Shot photograph(const ObjectModel& model) {
  RenderScene s;
  Material floor;
  Rng rng(5);
  floor.texture = std::make_shared<const Texture>(
      plasticTexture(rng, 64, 64, {0.55f, 0.57f, 0.6f}, 0.1f), true, true);
  Mesh mat = quad({-2.f, -2.f, 0.f}, {4.f, 0, 0}, {0, 4.f, 0}, 8, 8);  // faces +z
  s.add(mat, s.addMaterial(floor));
  for (const auto& part : model.parts) s.add(part.mesh, s.addMaterial(part.material), 0);
  s.finalize();
  const Eigen::AlignedBox3f b = model.bounds();
  const double size = b.sizes().maxCoeff();
  const Eigen::Vector3d target = b.center().cast<double>();
  const double el = 35 * M_PI / 180, az = -100 * M_PI / 180, dist = 2.0 * size + 0.15;
  const Eigen::Vector3d cam =
      target + dist * Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                                      std::sin(el));
  const Eigen::Vector3d z = (target - cam).normalized(),
                        x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = z.cross(x);
  T.linear().col(2) = z;
  T.translation() = cam;
  const Intrinsics K{525.f, 525.f, 159.5f, 119.5f};
  Rasterizer r;
  FrameBuffers fb;
  r.render(s, K, T, Viewport{0, 0, 320, 240}, &fb, true);
  Shot shot;
  int x0 = 320, y0 = 240, x1 = -1, y1 = -1;
  for (int y = 0; y < 240; ++y)
    for (int xx = 0; xx < 320; ++xx)
      if (fb.object[static_cast<size_t>(y) * 320 + xx] == 0) {
        ++shot.pixels;
        x0 = std::min(x0, xx);
        x1 = std::max(x1, xx);
        y0 = std::min(y0, y);
        y1 = std::max(y1, y);
      }
  shot.box_w = x1 - x0 + 1;
  shot.box_h = y1 - y0 + 1;
  SensorOptions so;
  so.read_noise = 0.5;
  shot.image = applySensor(fb, K, T, so, ShutterMotion{}, 1);
  return shot;
}

}  // namespace

TEST(SynthCategories, FiftyOneCategoriesPaperClassesFirst) {
  const auto& names = categoryNames();
  ASSERT_EQ(names.size(), 51u);
  const std::vector<std::string> first{"bowl", "cap", "cereal_box", "coffee_mug", "soda_can"};
  EXPECT_EQ(std::vector<std::string>(names.begin(), names.begin() + 5), first);
  EXPECT_EQ(paperClasses(), first);
  for (const auto& n : names) EXPECT_FALSE(categoryFamily(n).empty()) << n;
  EXPECT_THROW(makeObject("teapot", 1), std::invalid_argument);
}

TEST(SynthCategories, EveryCategoryRendersAndInstancesDiffer) {
  std::vector<cv::Mat> sheet;
  std::vector<std::string> captions;
  for (const auto& cat : categoryNames()) {
    SCOPED_TRACE(cat);
    const ObjectModel a = makeObject(cat, instanceSeed(SeedDomain::kScene, 1, cat, 0));
    const ObjectModel b = makeObject(cat, instanceSeed(SeedDomain::kScene, 1, cat, 1));
    for (const ObjectModel* m : {&a, &b}) {
      ASSERT_FALSE(m->parts.empty());
      EXPECT_GE(m->triangleCount(), 12u);  // a box
      const Eigen::AlignedBox3f bb = m->bounds();
      EXPECT_NEAR(bb.min().z(), 0.f, 1e-5f);  // rests on z = 0
      EXPECT_NEAR(bb.center().x(), 0.f, 1e-4f);
      EXPECT_NEAR(bb.center().y(), 0.f, 1e-4f);
      EXPECT_GT(bb.sizes().maxCoeff(), 0.03f);  // a dry battery is the smallest (4.5 cm)
      EXPECT_LT(bb.sizes().maxCoeff(), 0.5f);   // a keyboard the largest
      // Closed and facing outwards: a positive enclosed volume, no bigger than the box.
      double vol = 0;
      for (const auto& p : m->parts) vol += p.mesh.signedVolume();
      EXPECT_GT(vol, 0.0);
      EXPECT_LT(vol, 1.01 * bb.volume());
    }
    const Shot sa = photograph(a), sb = photograph(b);
    EXPECT_GT(sa.pixels, 1000) << "the object should fill a good part of the shot";
    EXPECT_GE(sa.box_w, 40);
    EXPECT_GE(sa.box_h, 25);
    // Two instances differ in size or in appearance.
    const Eigen::Vector3f ds = a.bounds().sizes() - b.bounds().sizes();
    cv::Mat diff;
    cv::absdiff(sa.image, sb.image, diff);
    const double mean_diff = cv::mean(diff)[0] + cv::mean(diff)[1] + cv::mean(diff)[2];
    EXPECT_TRUE(ds.cwiseAbs().maxCoeff() > 0.002f || mean_diff > 3.0) << "instances look the same";
    sheet.push_back(sa.image);
    sheet.push_back(sb.image);
    captions.push_back(cat + " a");
    captions.push_back(cat + " b");
  }
  const fs::path dir = fs::path(SLAMAWARE_BIN_DIR).parent_path() / "synth-sheets";
  fs::create_directories(dir);
  ASSERT_TRUE(
      cv::imwrite((dir / "categories.png").string(), contactSheet(sheet, captions, 12, 160, 120)));
}

TEST(SynthCategories, SeedsOfObjectSetsAndScenesNeverMeet) {
  for (const auto& cat : categoryNames())
    for (uint64_t i = 0; i < 20; ++i) {
      const uint64_t train = instanceSeed(SeedDomain::kObjectSet, 1000 + i, cat, i);
      const uint64_t test = instanceSeed(SeedDomain::kScene, 1000 + i, cat, i);
      EXPECT_EQ(seedDomain(train), SeedDomain::kObjectSet);
      EXPECT_EQ(seedDomain(test), SeedDomain::kScene);
      EXPECT_NE(train, test);
    }
}
