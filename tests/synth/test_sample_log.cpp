// The bundled sample logs/sample.lcm (`make sample`): small, complete (every frame once, seq =
// frame index), and the same frames the generator renders for config/scenes/sample.yaml today,
// so that a change to the renderer that forgets to regenerate the sample is caught.
#include <gtest/gtest.h>

#include <filesystem>

#include "common/bus/log_reader.h"
#include "common/image_codec.h"
#include "slamaware/camera_info_t.hpp"
#include "slamaware/image_t.hpp"
#include "tests/support/test_support.h"
#include "tools/synth/scene.h"

using namespace slamaware;

TEST(SynthSample, BundledLogIsSmallCompleteAndMatchesTheGenerator) {
  const std::string log = test::sourcePath("logs/sample.lcm");
  ASSERT_TRUE(std::filesystem::exists(log)) << "run `make sample`";
  EXPECT_LE(std::filesystem::file_size(log), 10u * 1024 * 1024);
  const synth::SceneOptions o =
      synth::loadSceneOptions(test::sourcePath("config/scenes/sample.yaml"));
  EXPECT_LE(o.frames, 200);
  synth::SyntheticScene scene(o);
  std::vector<image_t> frames;
  int infos = 0;
  for (const LogRecord& r : LogReader::readAll(log)) {
    if (r.channel == "CAMERA_INFO") {
      camera_info_t info;
      ASSERT_GT(info.decode(r.data.data(), 0, static_cast<int>(r.data.size())), 0);
      EXPECT_EQ(info.width, 640);
      EXPECT_EQ(info.height, 480);
      EXPECT_DOUBLE_EQ(info.fx, o.camera.fx);
      EXPECT_DOUBLE_EQ(info.cy, o.camera.cy);
      ++infos;
    } else if (r.channel == "CAMERA") {
      image_t img;
      ASSERT_GT(img.decode(r.data.data(), 0, static_cast<int>(r.data.size())), 0);
      frames.push_back(std::move(img));
    }
  }
  EXPECT_GT(infos, 0);
  ASSERT_EQ(static_cast<int>(frames.size()), o.frames);
  for (size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i].seq, static_cast<int32_t>(i));
    EXPECT_EQ(frames[i].utime, static_cast<int64_t>(std::llround(i * 1e6 / o.camera.fps)));
    EXPECT_EQ(frames[i].pixel_format, image_t::PIXEL_FORMAT_JPEG);
  }
  // A few frames, byte for byte.
  synth::FrameBuffers fb;
  for (size_t i : {size_t{0}, frames.size() / 2, frames.size() - 1}) {
    const cv::Mat img = scene.render(static_cast<int>(i), &fb);
    EXPECT_EQ(frames[i].data, encodeJpeg(img, o.sensor.jpeg_quality))
        << "frame " << i << ": run `make sample`";
  }
}
