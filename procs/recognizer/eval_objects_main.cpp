// slamaware-eval-objects: leave-one-instance-out category accuracy and confusion matrix of the
// recognizer on an object set, written as a JSON fragment that the evaluation report merges:
//   {"objects": {"<set name>": {"accuracy": %, "confusion": [[...]], "classes": [...], ...}}}
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "common/config.h"
#include "common/progress.h"
#include "procs/recognizer/trainer.h"

using namespace slamaware;

int main(int argc, char** argv) {
  CLI::App app{
      "slamaware-eval-objects: leave-one-instance-out accuracy of the recognizer on an object set"};
  std::string objects, out, config, log_level = "info";
  int max_views = -1;
  app.add_option("--objects", objects, "object set folder (category/category_N/..._crop.png)")
      ->required();
  app.add_option("--out", out, "JSON fragment to write")->required();
  app.add_option("--config", config, "YAML file with a 'train' section (default: built-in options)")
      ->check(CLI::ExistingFile);
  app.add_option("--max-views", max_views,
                 "views per instance (overrides train.max_views_per_instance)");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error");
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::from_str(log_level));
  try {
    TrainOptions options = loadConfig<TrainOptions>(config, "train", false);
    if (max_views >= 0) options.max_views_per_instance = max_views;
    std::unique_ptr<ProgressBar> bar;
    std::string current;
    const LoioResult r = leaveOneInstanceOut(
        objects, options, [&](const std::string& stage, int64_t done, int64_t total) {
          if (stage != current) {
            if (bar) bar->finish();
            bar = std::make_unique<ProgressBar>(stage, total);
            current = stage;
          }
          bar->update(done);
        });
    if (bar) bar->finish();
    std::string name = std::filesystem::path(objects).lexically_normal().filename().string();
    if (name.empty())
      name = std::filesystem::path(objects).lexically_normal().parent_path().filename().string();
    nlohmann::json entry;
    entry["accuracy"] = r.accuracy();
    entry["confusion"] = r.confusion;
    entry["classes"] = r.classes;
    entry["protocol"] = "leave-one-instance-out, category accuracy";
    entry["crops"] = r.crops;
    entry["instance_accuracy"] = r.instance_accuracy;
    nlohmann::json j;
    j["objects"][name] = entry;
    std::filesystem::path p(out);
    if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path());
    std::ofstream f(out);
    f << j.dump(2) << "\n";
    if (!f) throw std::runtime_error(out + ": cannot write");
    std::cout << name << ": leave-one-instance-out accuracy " << r.accuracy() << "% (" << r.correct
              << "/" << r.crops << ")\nconfusion (rows: true, columns: predicted):\n";
    for (size_t i = 0; i < r.classes.size(); ++i) {
      std::cout << "  " << r.classes[i];
      for (int64_t n : r.confusion[i]) std::cout << " " << n;
      std::cout << "\n";
    }
    for (const auto& [inst, acc] : r.instance_accuracy)
      std::cout << "  " << inst << ": " << acc << "%\n";
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  return 0;
}
