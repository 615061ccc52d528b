// The camera's "synth:" source renders the same frames, byte for byte, as the scene written to a
// folder, with seq = frame index and utime = index / fps; bad arguments are refused clearly.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

#include "common/frame_source.h"
#include "tests/support/test_support.h"
#include "tools/synth/scene.h"
#include "tools/synth/synth_source.h"
#include "tools/synth/writers.h"

using namespace slamaware;

namespace {

std::vector<uint8_t> readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

TEST(SynthSource, StreamsTheSameFramesAsTheWrittenFolder) {
  synth::registerSynthSource();
  const std::string cfg = test::sourcePath("config/scenes/cafe_small.yaml");
  std::unique_ptr<FrameSource> src =
      openSource("synth:" + cfg + "?frames=4&seed=9", SourceOptions{});
  ASSERT_EQ(src->length(), 4);
  EXPECT_DOUBLE_EQ(src->fps(), 30.0);
  EXPECT_EQ(src->camera().width(), 640);
  EXPECT_DOUBLE_EQ(src->camera().fx(), 525.0);

  const synth::SceneOptions o = synth::loadSceneOptions(cfg);
  synth::SyntheticScene scene(o, 9, 4);
  const std::string dir = test::tempDir("synth_source");
  synth::writeSceneFolder(scene, dir, "cafe_small.yaml", false);

  SourceFrame f;
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(src->next(&f));
    EXPECT_TRUE(f.error.empty());
    EXPECT_EQ(f.seq, i);
    EXPECT_EQ(f.utime, static_cast<int64_t>(std::llround(i * 1e6 / 30.0)));
    char name[32];
    std::snprintf(name, sizeof(name), "/rgb/%06d.jpg", i);
    EXPECT_EQ(f.jpeg, readBytes(dir + name)) << "frame " << i;
    EXPECT_EQ(f.bgr.cols, 640);
  }
  EXPECT_FALSE(src->next(&f));
  ASSERT_TRUE(src->rewind());
  ASSERT_TRUE(src->next(&f));
  EXPECT_EQ(f.seq, 4);  // seq keeps counting after a loop
}

TEST(SynthSource, BadArgumentsAreRefused) {
  synth::registerSynthSource();
  const std::string cfg = test::sourcePath("config/scenes/cafe_small.yaml");
  auto error = [](const std::string& spec) {
    try {
      openSource(spec, SourceOptions{});
    } catch (const SourceError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("synth:" + cfg + "?frames=x").find("frames"), std::string::npos);
  EXPECT_NE(error("synth:" + cfg + "?speed=2").find("speed"), std::string::npos);
  EXPECT_NE(error("synth:/nonexistent/scene.yaml").find("scene.yaml"), std::string::npos);
}
