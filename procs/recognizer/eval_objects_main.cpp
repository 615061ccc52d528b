// slamaware-eval-objects: category accuracy of the recognizer on instances it was not trained on,
// per object set, with the confusion matrix, written as a JSON fragment that the evaluation
// report merges (DESIGN.md §7):
//   {"objects": {"<set name>": {"accuracy": %, "confusion": [[...]], "classes": [...], ...}}}
// Protocol: leave-one-instance-out (one fold per instance) for sets of up to --loio-max-instances
// instances, else one fold holding out one instance of each category.
// Without --objects it evaluates every object set in <shared>/objects and build/data/objects.
// Positional arguments (the sequence folders scripts/eval passes to every eval tool) are ignored.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "common/config.h"
#include "common/dataset.h"
#include "common/progress.h"
#include "procs/recognizer/trainer.h"

using namespace slamaware;
namespace fs = std::filesystem;

namespace {

std::vector<std::string> defaultObjectSets(const std::string& shared) {
  std::vector<std::string> sets;
  for (const fs::path& root : {fs::path(shared) / "objects", fs::path("build/data/objects")}) {
    if (!fs::is_directory(root)) continue;
    std::vector<std::string> found;
    for (const auto& e : fs::directory_iterator(root))
      if (e.is_directory()) found.push_back(e.path().string());
    std::sort(found.begin(), found.end());
    sets.insert(sets.end(), found.begin(), found.end());
  }
  return sets;
}

std::string setName(const std::string& dir) {
  fs::path p = fs::path(dir).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  return p.filename().string();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"slamaware-eval-objects: recognizer accuracy on held-out object instances"};
  std::vector<std::string> objects, ignored;
  std::string out, config, shared = "../shared/data", protocol = "auto", log_level = "info";
  int max_views = -1, loio_max = 16;
  app.add_option("--objects", objects, "object set folders (default: every set in <shared>/objects and build/data/objects)");
  app.add_option("--out", out, "JSON fragment to write")->required();
  app.add_option("--config", config, "YAML file with a 'train' section (default: built-in options)")
      ->check(CLI::ExistingFile);
  app.add_option("--shared", shared, "the shared data folder");
  app.add_option("--protocol", protocol, "auto, loio (leave-one-instance-out) or holdout (one instance per category)")
      ->check(CLI::IsMember({"auto", "loio", "holdout"}));
  app.add_option("--loio-max-instances", loio_max, "auto: leave-one-instance-out up to this many instances");
  app.add_option("--max-views", max_views, "views per instance (overrides train.max_views_per_instance)");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error");
  app.add_option("sequences", ignored, "ignored (scripts/eval passes its sequence folders to every eval tool)");
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::from_str(log_level));
  try {
    TrainOptions options = loadConfig<TrainOptions>(config, "train", false);
    if (max_views >= 0) options.max_views_per_instance = max_views;
    if (objects.empty()) objects = defaultObjectSets(shared);
    if (objects.empty()) throw std::runtime_error("no object sets found (give --objects DIR)");
    nlohmann::json j = nlohmann::json::object();
    j["objects"] = nlohmann::json::object();
    for (const auto& dir : objects) {
      std::unique_ptr<ProgressBar> bar;
      std::string current;
      auto progress = [&](const std::string& stage, int64_t done, int64_t total) {
        if (stage != current) {
          if (bar) bar->finish();
          bar = std::make_unique<ProgressBar>(stage, total);
          current = stage;
        }
        bar->update(done);
      };
      const ObjectSet set = ObjectSet::open(dir);
      const size_t instances = [&] {
        size_t n = 0;
        for (const auto& [c, list] : set.instances()) n += list.size();
        return n;
      }();
      const bool loio = protocol == "loio" || (protocol == "auto" && static_cast<int>(instances) <= loio_max);
      const HeldOutResult r =
          loio ? leaveOneInstanceOut(dir, options, progress) : oneInstancePerCategoryOut(dir, options, progress);
      if (bar) bar->finish();
      const std::string name = setName(dir);
      nlohmann::json entry;
      entry["accuracy"] = r.accuracy();
      entry["confusion"] = r.confusion;
      entry["classes"] = r.classes;
      entry["protocol"] = r.protocol;
      entry["crops"] = r.crops;
      entry["instance_accuracy"] = r.instance_accuracy;
      j["objects"][name] = entry;
      std::cout << name << " (" << r.protocol << "): category accuracy " << r.accuracy() << "% (" << r.correct << "/"
                << r.crops << ")\nconfusion (rows: true, columns: predicted):\n";
      for (size_t i = 0; i < r.classes.size(); ++i) {
        std::cout << "  " << r.classes[i];
        for (int64_t n : r.confusion[i]) std::cout << " " << n;
        std::cout << "\n";
      }
      for (const auto& [inst, acc] : r.instance_accuracy) std::cout << "  " << inst << ": " << acc << "%\n";
    }
    fs::path p(out);
    if (p.has_parent_path()) fs::create_directories(p.parent_path());
    std::ofstream f(out);
    f << j.dump(2) << "\n";
    if (!f) throw std::runtime_error(out + ": cannot write");
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  return 0;
}
