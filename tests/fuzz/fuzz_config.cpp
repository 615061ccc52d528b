// Fuzz target: every config loader: system.yaml (bus, scheduling, channels; supervisor and
// processes), each process's section (camera, slam, proposals, recognizer, objectmap), training
// options, the generator's scene and object-set files, and a sequence's sequence.yaml.
// Input: one byte choosing the loader (modulo their count), then the YAML text.
// Checks beyond "no crash": a refusal is a ConfigError or DatasetError (the errors that name the
// file), never another exception, and its message names the file.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>

#include "common/bus/system_config.h"
#include "common/config.h"
#include "common/dataset.h"
#include "procs/camera/camera_options.h"
#include "procs/objectmap/objectmap_options.h"
#include "procs/proposals/proposal_options.h"
#include "procs/recognizer/recognizer.h"
#include "procs/slam/slam_options.h"
#include "procs/supervisor/process_spec.h"
#include "tests/fuzz/fuzz_support.h"
#include "tools/synth/synth_options.h"
#include "tools/train/trainer.h"

namespace {

using Loader = std::function<void(const std::string&)>;

template <class Options>
Loader section(const char* name) {
  return [name](const std::string& path) { slamaware::loadConfig<Options>(path, name, false); };
}

const Loader kLoaders[] = {
    [](const std::string& p) { slamaware::loadSystemConfig(p, false); },
    [](const std::string& p) { slamaware::supervisor::loadSupervisorConfig(p); },
    section<slamaware::camera::CameraOptions>("camera"),
    section<slamaware::slam::SlamOptions>("slam"),
    section<slamaware::proposals::ProposalOptions>("proposals"),
    section<slamaware::recognizer::RecognizerOptions>("recognizer"),
    section<slamaware::objectmap::ObjectMapOptions>("objectmap"),
    section<slamaware::recognizer::TrainOptions>("train"),
    [](const std::string& p) { slamaware::synth::loadSceneOptions(p); },
    [](const std::string& p) { slamaware::synth::loadObjectSetOptions(p); },
    [](const std::string& p) { slamaware::readSequenceInfo(p); },
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const std::string path = slamaware::fuzz::scratchDir() + "/config.yaml";
  slamaware::fuzz::writeFile(path, data + 1, size - 1);
  const size_t n = sizeof(kLoaders) / sizeof(kLoaders[0]);
  std::string error;
  try {
    kLoaders[data[0] % n](path);
    return 0;
  } catch (const slamaware::ConfigError& e) {
    error = e.what();
  } catch (const slamaware::DatasetError& e) {
    error = e.what();
  }
  if (error.find(path) == std::string::npos) {
    std::fprintf(stderr, "fuzz_config: a refusal that does not name the file: %s\n", error.c_str());
    std::abort();
  }
  return 0;
}
