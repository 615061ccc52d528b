#include "tools/synth/synth_source.h"

#include <cmath>
#include <sstream>

#include "common/config.h"
#include "common/image_codec.h"
#include "tools/synth/scene.h"

namespace slamaware::synth {

namespace {

class SynthSource : public FrameSource {
 public:
  SynthSource(const std::string& arg, const std::string& config, int64_t seed, int frames)
      : arg_(arg) {
    const synth::SceneOptions o = synth::loadSceneOptions(config);
    scene_ = std::make_unique<synth::SyntheticScene>(o, seed, frames);
    camera_ = scene_->camera();
  }
  const CameraModel& camera() const override { return camera_; }
  double fps() const override { return scene_->fps(); }
  int64_t length() const override { return scene_->frames(); }
  std::string describe() const override { return "synth:" + arg_; }

  bool next(SourceFrame* f) override {
    if (index_ >= scene_->frames()) return false;
    const int i = index_++;
    f->error.clear();
    f->seq = static_cast<int32_t>(i + loops_ * scene_->frames());
    const double period_us = 1e6 / scene_->fps();
    f->utime = static_cast<int64_t>(std::llround((i + loops_ * scene_->frames()) * period_us));
    f->bgr = scene_->render(i, &fb_);
    f->jpeg = encodeJpeg(f->bgr, scene_->options().sensor.jpeg_quality);
    return true;
  }
  bool rewind() override {
    index_ = 0;
    ++loops_;
    return true;
  }

 private:
  std::string arg_;
  std::unique_ptr<synth::SyntheticScene> scene_;
  CameraModel camera_;
  synth::FrameBuffers fb_;
  int index_ = 0;
  int64_t loops_ = 0;
};

int64_t parseInt(const std::string& arg, const std::string& key, const std::string& value) {
  try {
    size_t used = 0;
    const long long v = std::stoll(value, &used);
    if (used != value.size() || v < 0) throw std::invalid_argument(value);
    return v;
  } catch (const std::exception&) {
    throw SourceError("synth:" + arg + ": '" + key + "' must be a non-negative integer, got '" +
                      value + "'");
  }
}

}  // namespace

std::unique_ptr<FrameSource> openSynthSource(const std::string& arg) {
  std::string config = arg, query;
  const size_t q = arg.find('?');
  if (q != std::string::npos) {
    config = arg.substr(0, q);
    query = arg.substr(q + 1);
  }
  int64_t seed = -1, frames = -1;
  std::istringstream qs(query);
  std::string kv;
  while (std::getline(qs, kv, '&')) {
    if (kv.empty()) continue;
    const size_t eq = kv.find('=');
    const std::string key = kv.substr(0, eq),
                      value = eq == std::string::npos ? "" : kv.substr(eq + 1);
    if (key == "seed")
      seed = parseInt(arg, key, value);
    else if (key == "frames")
      frames = parseInt(arg, key, value);
    else
      throw SourceError("synth:" + arg + ": unknown option '" + key + "' (known: seed, frames)");
  }
  if (config.empty())
    throw SourceError("synth:" + arg + ": expected synth:CONFIG[?seed=N&frames=M]");
  try {
    return std::make_unique<SynthSource>(arg, config, seed, static_cast<int>(frames));
  } catch (const ConfigError& e) {
    throw SourceError(std::string("synth: ") + e.what());
  } catch (const std::invalid_argument& e) {
    throw SourceError("synth:" + arg + ": " + e.what());
  }
}

void registerSynthSource() { registerSourceScheme("synth", openSynthSource); }

}  // namespace slamaware::synth
