// slamaware-synth: generates synthetic tabletop scenes (sequence folders with complete ground
// truth) and turntable object sets (the layout of the UW RGB-D Object dataset).
//   slamaware-synth scene --config FILE [--seed N] [--frames N] --out DIR
//   slamaware-synth scene --random SEED [--frames N] --out DIR
//   slamaware-synth objects --config FILE [--seed N] --out DIR
//   slamaware-synth categories
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>

#include "common/atomic_file.h"
#include "common/config.h"
#include "tools/synth/categories.h"
#include "tools/synth/random_scene.h"
#include "tools/synth/scene.h"
#include "tools/synth/writers.h"

using namespace slamaware;
using namespace slamaware::synth;

int main(int argc, char** argv) {
  CLI::App app{
      "slamaware-synth: synthetic tabletop scenes and turntable object sets with exact ground "
      "truth"};
  app.require_subcommand(1);
  std::string config, out;
  int64_t seed = -1, random_seed = -1;
  int frames = -1, path_frames = 300;
  bool quiet = false;
  CLI::App* scene_cmd = app.add_subcommand("scene", "render a scene config into a sequence folder");
  CLI::Option* config_opt =
      scene_cmd->add_option("--config", config, "scene config (config/scenes/*.yaml)");
  CLI::Option* random_opt = scene_cmd->add_option(
      "--random", random_seed,
      "a random scene: every option drawn from the ranges of tools/synth/README.md with this "
      "seed; the drawn config is written to <out>/scene.yaml");
  random_opt->check(CLI::NonNegativeNumber);
  config_opt->excludes(random_opt);
  scene_cmd
      ->add_option("--path-frames", path_frames,
                   "--random: frames of the camera path (default 300)")
      ->needs(random_opt)
      ->check(CLI::Range(2, 100000));
  scene_cmd->add_option("--seed", seed, "scene seed (default: the config's)")->excludes(random_opt);
  scene_cmd->add_option("--frames", frames,
                        "render only the first N frames (default: all of the config's)");
  scene_cmd->add_option("--out", out, "output sequence folder")->required();
  scene_cmd->add_flag("--quiet", quiet, "no progress bar");
  CLI::App* objects_cmd =
      app.add_subcommand("objects", "render an object-set config (turntable views)");
  objects_cmd->add_option("--config", config, "object-set config (config/objects/*.yaml)")
      ->required();
  objects_cmd->add_option("--seed", seed, "object-set seed (default: the config's)");
  objects_cmd->add_option("--out", out, "output object-set folder")->required();
  objects_cmd->add_flag("--quiet", quiet, "no progress bar");
  CLI::App* cat_cmd =
      app.add_subcommand("categories", "list the object categories and their shape families");
  CLI11_PARSE(app, argc, argv);

  try {
    if (cat_cmd->parsed()) {
      const auto& paper = paperClasses();
      int i = 0;
      for (const auto& c : categoryNames()) {
        const bool p = std::find(paper.begin(), paper.end(), c) != paper.end();
        std::printf("%2d  %-16s %-6s %s\n", ++i, c.c_str(), p ? "paper" : "",
                    categoryFamily(c).c_str());
      }
      return 0;
    }
    const std::string config_name = std::filesystem::path(config).filename().string();
    if (scene_cmd->parsed()) {
      if (frames == 0 || frames < -1)
        throw ConfigError("--frames: expected a positive number of frames");
      if (config.empty() && random_seed < 0)
        throw ConfigError("scene: give --config FILE or --random SEED");
      SceneOptions o;
      std::unique_ptr<SyntheticScene> scene;
      std::string source = config;
      if (random_seed >= 0) {
        scene = buildRandomScene(static_cast<uint64_t>(random_seed), path_frames, frames, &o);
        source = "--random " + std::to_string(random_seed);
      } else {
        o = loadSceneOptions(config);
        scene = std::make_unique<SyntheticScene>(o, seed, frames);
        if (seed >= 0) o.seed = seed;
      }
      spdlog::info("scene '{}' from {} (seed {}, {} of {} frames) -> {}", o.name, source,
                   scene->seed(), scene->frames(), o.frames, out);
      const WriteStats st = writeSceneFolder(
          *scene, out, random_seed >= 0 ? "scene.yaml (random)" : config_name, !quiet);
      // The options that built the scene, so that any sequence can be reproduced from its folder.
      const std::string yaml = sceneConfigYaml(o);
      writeFileAtomic((std::filesystem::path(out) / "scene.yaml").string(), yaml.data(),
                      yaml.size());
      spdlog::info("wrote {} files, {:.1f} MB in {:.1f} s ({:.1f} frames/s)", st.files,
                   st.bytes / 1e6, st.seconds, scene->frames() / std::max(1e-9, st.seconds));
      return 0;
    }
    if (objects_cmd->parsed()) {
      const ObjectSetOptions o = loadObjectSetOptions(config);
      spdlog::info("object set '{}' from {} (seed {}) -> {}", o.name, config,
                   seed >= 0 ? seed : o.seed, out);
      const WriteStats st = writeObjectSet(o, out, seed, !quiet);
      spdlog::info("wrote {} files, {:.1f} MB in {:.1f} s", st.files, st.bytes / 1e6, st.seconds);
      return 0;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "slamaware-synth: %s\n", e.what());
    return 2;
  }
  return 0;
}
