// slamaware-eval-objects: category accuracy of the recognizer on instances it was not trained on,
// per object set, with the confusion matrix, written as a JSON fragment that the evaluation
// report merges (DESIGN.md §7):
//   {"objects": {"<set name>": {"accuracy": %, "confusion": [[...]], "classes": [...], ...}}}
// Protocol: leave-one-instance-out (one fold per instance) for sets of up to --loio-max-instances
// instances, else one fold holding out one instance of each category.
// Without --objects it evaluates every object set in <shared>/objects and build/data/objects.
// --extra-training [SET=]DIR adds another set's crops (of the evaluated set's categories) to the
// training data of every fold of SET (of every other set without "SET="); make eval adds the
// rendered config/objects/apple_ball.yaml to uw_rgbd_apple_ball's folds.
// Positional arguments (the sequence folders scripts/eval passes to every eval tool): the
// ground-truth boxes of their every 5th frame are classified with --model (the shipped model by
// default), which measures the recognizer apart from the proposals:
//   {"sequences": {"<name>": {"gt_boxes": {"accuracy": %, "jittered_accuracy": %, "confusion": ...}}},
//    "overall": {"gt_boxes": {...}}}   (objects of other categories count as background)
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "common/config.h"
#include "common/dataset.h"
#include "common/progress.h"
#include "common/image_codec.h"
#include "procs/recognizer/recognizer.h"
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

// Accuracy of the model on ground-truth boxes of scene frames: the boxes themselves and one
// jittered copy each (IoU >= 0.6, as a proposal would draw them).
struct BoxTally {
  std::vector<std::string> classes;
  std::vector<std::vector<int64_t>> confusion;  // [truth][predicted], exact boxes
  int64_t boxes = 0, correct = 0, jittered = 0, jittered_correct = 0;
  std::vector<double> runner_up_log_prob;  // the second-best class of each exact box

  void merge(const BoxTally& o) {
    if (confusion.empty()) {
      *this = o;
      return;
    }
    for (size_t i = 0; i < confusion.size(); ++i)
      for (size_t j = 0; j < confusion[i].size(); ++j) confusion[i][j] += o.confusion[i][j];
    boxes += o.boxes;
    correct += o.correct;
    jittered += o.jittered;
    jittered_correct += o.jittered_correct;
    runner_up_log_prob.insert(runner_up_log_prob.end(), o.runner_up_log_prob.begin(), o.runner_up_log_prob.end());
  }
  nlohmann::json json() const {
    nlohmann::json j;
    j["boxes"] = boxes;
    j["accuracy"] = boxes ? 100.0 * static_cast<double>(correct) / static_cast<double>(boxes) : 0.0;
    j["jittered_accuracy"] =
        jittered ? 100.0 * static_cast<double>(jittered_correct) / static_cast<double>(jittered) : 0.0;
    j["classes"] = classes;
    j["confusion"] = confusion;
    std::vector<double> r = runner_up_log_prob;
    std::sort(r.begin(), r.end());
    j["runner_up_log_prob_median"] = r.empty() ? 0.0 : r[r.size() / 2];
    return j;
  }
};

BoxTally classifySceneBoxes(Recognizer& recognizer, const SequenceFolder& seq, int stride) {
  BoxTally t;
  t.classes = recognizer.classes();
  const int C = static_cast<int>(t.classes.size());
  t.confusion.assign(static_cast<size_t>(C), std::vector<int64_t>(static_cast<size_t>(C), 0));
  std::map<int, std::vector<GroundTruthBox>> by_frame;
  for (const auto& b : seq.boxes()) by_frame[b.frame].push_back(b);
  for (const auto& [frame, truth] : by_frame) {
    if (frame % stride != 0 || frame >= static_cast<int>(seq.size())) continue;
    const cv::Mat image = readImage(seq.framePath(static_cast<size_t>(frame)));
    std::vector<BoxRequest> req;
    std::vector<int> label;
    for (size_t i = 0; i < truth.size(); ++i) {
      const auto& b = truth[i];
      auto it = std::find(t.classes.begin(), t.classes.end(), b.cls);
      const int l = it == t.classes.end() ? C - 1 : static_cast<int>(it - t.classes.begin());
      req.push_back({b.x, b.y, b.w, b.h, 0});
      label.push_back(l);
      for (const auto& r : jitteredBoxes(cv::Rect2d(b.x, b.y, b.w, b.h), image.cols, image.rows, 1, 0.6,
                                         static_cast<uint32_t>(frame * 131 + static_cast<int>(i)))) {
        req.push_back({r.x, r.y, r.width, r.height, 1});
        label.push_back(l);
      }
    }
    const FrameDetections d = recognizer.recognize(image, req);
    for (const auto& b : d.boxes) {
      const auto best = std::max_element(b.log_prob.begin(), b.log_prob.end());
      const int pred = static_cast<int>(best - b.log_prob.begin());
      const int truth_label = label[static_cast<size_t>(b.input_index)];
      if (req[static_cast<size_t>(b.input_index)].candidate_id == 1) {
        ++t.jittered;
        t.jittered_correct += pred == truth_label;
        continue;
      }
      ++t.boxes;
      t.correct += pred == truth_label;
      ++t.confusion[static_cast<size_t>(truth_label)][static_cast<size_t>(pred)];
      std::vector<float> lp = b.log_prob;
      std::nth_element(lp.begin(), lp.begin() + 1, lp.end(), std::greater<float>());
      t.runner_up_log_prob.push_back(lp.size() > 1 ? lp[1] : 0.0);
    }
  }
  return t;
}

// An --extra-training argument: "SET=DIR" (for the set named SET only) or "DIR" (set empty: for
// every set but DIR itself).
struct ExtraTraining {
  std::string set, dir;
  explicit ExtraTraining(const std::string& arg) {
    const size_t eq = arg.find('=');
    if (eq != std::string::npos) set = arg.substr(0, eq);
    dir = eq == std::string::npos ? arg : arg.substr(eq + 1);
  }
};

// The extra training sets of the evaluated set `name`.
std::vector<std::string> extraTrainingFor(const std::string& name, const std::vector<std::string>& args) {
  std::vector<std::string> dirs;
  for (const auto& a : args) {
    const ExtraTraining e(a);
    if (e.set.empty() ? folderName(e.dir) != name : e.set == name) dirs.push_back(e.dir);
  }
  return dirs;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"slamaware-eval-objects: recognizer accuracy on held-out object instances"};
  std::vector<std::string> objects, sequences;
  std::string model_path = "models/recognizer.model";
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
  std::vector<std::string> extra, held_out;
  // One value per occurrence (repeat the option for more): a list would swallow the sequence
  // folders that follow it on the command line (make eval passes them last).
  app.add_option("--hold-out", held_out,
                 "leave-one-instance-out: only this instance's folds (e.g. ball_1; repeat for more; default: "
                 "every instance)")
      ->expected(1)
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app.add_option("--extra-training", extra,
                 "[SET=]DIR: an object set (e.g. rendered by slamaware-synth objects) whose crops of the "
                 "categories of the evaluated set SET (default: of every set but itself) are added to the "
                 "training data of every fold; never tested; repeat for more")
      ->expected(1)
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app.add_option("--max-views", max_views, "views per instance (overrides train.max_views_per_instance)");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error");
  app.add_option("sequences", sequences,
                 "sequence folders: their ground-truth boxes are classified with --model (objects of other "
                 "categories count as background)");
  app.add_option("--model", model_path, "model for the ground-truth boxes of the sequences");
  bool skip_sets = false;
  app.add_flag("--no-object-sets", skip_sets, "only the ground-truth boxes of the sequences");
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::from_str(log_level));
  try {
    TrainOptions options = loadConfig<TrainOptions>(config, "train", false);
    if (max_views >= 0) options.max_views_per_instance = max_views;
    if (objects.empty() && !skip_sets) objects = defaultObjectSets(shared);
    if (objects.empty() && !skip_sets) throw std::runtime_error("no object sets found (give --objects DIR)");
    for (const auto& a : extra) {
      const ExtraTraining e(a);
      if (!e.set.empty() &&
          std::none_of(objects.begin(), objects.end(), [&](const std::string& d) { return folderName(d) == e.set; }))
        throw std::runtime_error("--extra-training " + a + ": no evaluated object set is named " + e.set);
    }
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
      const std::string name = folderName(dir);
      const std::vector<std::string> extra_dirs = extraTrainingFor(name, extra);
      const HeldOutResult r =
          loio ? leaveOneInstanceOut(dir, options, progress, extra_dirs, held_out)
               : oneInstancePerCategoryOut(dir, options, progress, extra_dirs);
      if (bar) bar->finish();
      nlohmann::json entry;
      entry["accuracy"] = r.accuracy();
      entry["confusion"] = r.confusion;
      entry["classes"] = r.classes;
      entry["protocol"] = r.protocol;
      entry["crops"] = r.crops;
      if (!extra_dirs.empty()) {
        entry["extra_training"] = extra_dirs;
        entry["extra_training_crops"] = r.extra_crops;
      }
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
    if (!sequences.empty()) {
      auto model = std::make_shared<const RecognizerModel>(loadModel(model_path));
      Recognizer recognizer(model, RecognizerOptions{});
      BoxTally suite;
      for (const auto& dir : sequences) {
        const SequenceFolder seq = SequenceFolder::open(dir);
        if (!seq.hasBoxes()) continue;
        const BoxTally t = classifySceneBoxes(recognizer, seq, 5);
        const std::string name = folderName(dir);
        j["sequences"][name]["gt_boxes"] = t.json();
        std::cout << name << ": " << t.json()["accuracy"].get<double>() << "% of " << t.boxes
                  << " ground-truth boxes right (jittered: " << t.json()["jittered_accuracy"].get<double>()
                  << "%)\n";
        if (isSyntheticSequence(seq)) suite.merge(t);
      }
      if (suite.boxes > 0) {
        j["overall"]["gt_boxes"] = suite.json();
        std::cout << "suite: " << suite.json()["accuracy"].get<double>() << "% of " << suite.boxes
                  << " ground-truth boxes right; confusion (rows: true, columns: predicted):\n";
        for (size_t i = 0; i < suite.classes.size(); ++i) {
          std::cout << "  " << suite.classes[i];
          for (int64_t n : suite.confusion[i]) std::cout << " " << n;
          std::cout << "\n";
        }
      }
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
