// slamaware-train: trains the recognizer's model (PCA, vocabulary, classifiers) from object sets
// and scene sequences with ground-truth boxes (their objects as positives or background, the rest
// as background); prints a validation summary on held-out data and writes one model file. With
// --base MODEL, adds the classes of --objects to an existing model instead (seconds, without the
// base's training data: addClasses in trainer.h).
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <fstream>
#include <iostream>
#include <new>

#include "common/config.h"
#include "procs/recognizer/classifier.h"
#include "procs/recognizer/model.h"
#include "tools/train/trainer.h"

using namespace slamaware;
using namespace slamaware::recognizer;

int main(int argc, char** argv) {
  CLI::App app{
      "slamaware-train: trains the recognizer model from object sets (--objects) and scene "
      "sequences with boxes.csv (--scenes: their objects of the model's categories, the rest as "
      "background)"};
  std::vector<std::string> objects, scenes, background_objects;
  std::string out, config, report_path, proposals_dir, log_level = "info";
  int64_t seed = -1;
  int threads = 0;
  std::string show, base;
  bool replace = false;
  app.add_option("--report", show,
                 "prints what the model file was trained on (object sets, scenes, options, "
                 "validation) and exits");
  app.add_option("--objects", objects, "object set folders (category/category_N/..._crop.png)");
  app.add_option(
      "--base", base,
      "adds the categories of --objects (e.g. slamaware-harvest's sets) to this model, keeping its "
      "classes, encoding and calibration; --scenes and --proposals are not used");
  app.add_flag("--replace", replace,
               "with --base: a category the base model has is trained again from the new views");
  app.add_option(
      "--scenes,--negatives", scenes,
      "sequence folders with boxes.csv: their objects (jittered boxes) and background boxes");
  app.add_option(
      "--background-objects", background_objects,
      "object set folders of other categories: their crops are background (categories of --objects "
      "in them are left out)");
  app.add_option(
         "--proposals", proposals_dir,
         "folder of <scene>.csv proposal boxes (slamaware-eval --dump-proposals on the scenes): "
         "also trained on, labelled by their overlap with the ground truth")
      ->check(CLI::ExistingDirectory);
  app.add_option("--out", out, "model file to write");
  app.add_option("--config", config, "YAML file with a 'train' section (default: built-in options)")
      ->check(CLI::ExistingFile);
  app.add_option("--seed", seed, "overrides train.seed");
  app.add_option("--threads", threads,
                 "threads of the long loops (0: one per core); the model does not depend on it")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--write-report", report_path, "also write the training report (JSON) here");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error");
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::from_str(log_level));
  if (!show.empty()) {
    try {
      std::cout << provenanceText(loadModel(show));
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      return 1;
    }
    return 0;
  }
  if (objects.empty() || out.empty()) {
    std::cerr << "slamaware-train: --objects and --out are required to train (or --report MODEL to "
                 "describe one)\n";
    return 2;
  }
  if (!base.empty()) {
    try {
      TrainOptions options = loadConfig<TrainOptions>(config, "train", false);
      options.threads = threads;
      AddClassesReport report;
      const RecognizerModel model = addClasses(loadModel(base), objects, options, replace, &report);
      saveModel(model, out);
      std::cout << report.toText() << "model written to " << out << "\n";
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      return 1;
    }
    return 0;
  }
  size_t example_kb = 0;
  try {
    TrainOptions options = loadConfig<TrainOptions>(config, "train", false);
    example_kb =
        ExampleSet(options.encoding.encodedDims(), options.encoding.pca_dims).maxRowBytes() / 1000;
    if (seed >= 0) options.seed = static_cast<int>(seed);
    options.threads = threads;
    TrainReport report;
    const RecognizerModel model =
        trainModel(objects, scenes, options, &report, proposals_dir, background_objects);
    saveModel(model, out);
    std::cout << report.toText();
    std::cout << "model written to " << out << "\n";
    if (!report_path.empty()) {
      std::ofstream f(report_path);
      f << report.toJson() << "\n";
      if (!f) throw std::runtime_error(report_path + ": cannot write the report");
    }
  } catch (const std::bad_alloc&) {
    // Every encoded example is held in memory (ExampleSet).
    spdlog::error(
        "out of memory: the training examples (up to {} kB each) did not fit; train on fewer: "
        "lower "
        "train.max_views_per_instance, train.negatives_per_frame or train.context_copies, or raise "
        "train.proposal_every (--config)",
        example_kb);
    return 1;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  return 0;
}
