// slamaware-eval-objects: recognition without the pipeline, written as a JSON fragment that the
// evaluation report merges (docs/architecture.md §7).
//
// Object sets: category accuracy on instances the recognizer was not trained on, with the
// confusion matrix: {"objects": {"<set name>": {"accuracy": %, "confusion": [[...]], ...}}}.
// Leave-one-instance-out (one fold per instance) for sets of up to --loio-max-instances instances,
// else one fold holding out one instance of each category; a set that cannot be split (fewer than
// two categories, or no category with two instances) is skipped and says why ("skipped").
// Without --objects, every object set in <shared>/objects and build/data/objects.
// --extra-training [SET=]DIR adds another set's crops (of the evaluated set's categories) to the
// training data of every fold of SET (of every other set without "SET="); make eval adds the
// rendered config/objects/apple_ball.yaml to uw_rgbd_apple_ball's folds.
//
// Sequence folders (positional; scripts/eval passes the same ones to every eval tool), with
// --model (the shipped model by default):
//   "gt_boxes": the ground-truth boxes classified (the recognizer apart from the proposals):
//     accuracy, a jittered copy's accuracy, per class, confusion matrix (objects of other
//     categories count as background). A continuous video (ground-truth poses) on every 5th frame,
//     as the pipeline's sections; separate frames (boxes, no poses) on every boxed frame.
//   "single_view_ss" (photographed sequences of the model's classes): OpenCV selective search's
//     boxes of each scored frame through the recognizer and its suppression, scored as detections
//     (mAP) against the ground-truth boxes: detection on real frames without SLAM.
//   {"sequences": {"<name>": {"gt_boxes": {...}, "single_view_ss": {...}}}, "overall": {"gt_boxes":
//   {...}}}
// --boxes-csv FILE: every scored ground-truth box with the class it was called and each class's
// probability (which real objects fail, and how close they came).
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "common/config.h"
#include "common/dataset.h"
#include "common/image_codec.h"
#include "common/progress.h"
#include "procs/recognizer/recognizer.h"
#include "tools/eval/recognition_metrics.h"
#include "tools/train/trainer.h"

using namespace slamaware;
using namespace slamaware::recognizer;
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

// One ground-truth box as the model saw it (--boxes-csv).
struct BoxVerdict {
  std::string sequence;  ///< the folder's name
  GroundTruthBox box;
  int called = 0;               ///< index into the classes
  std::vector<float> log_prob;  ///< calibrated, per class
};

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
    runner_up_log_prob.insert(runner_up_log_prob.end(), o.runner_up_log_prob.begin(),
                              o.runner_up_log_prob.end());
  }
  nlohmann::json json() const {
    nlohmann::json j;
    j["boxes"] = boxes;
    j["accuracy"] = boxes ? 100.0 * static_cast<double>(correct) / static_cast<double>(boxes) : 0.0;
    j["jittered_accuracy"] =
        jittered ? 100.0 * static_cast<double>(jittered_correct) / static_cast<double>(jittered)
                 : 0.0;
    j["classes"] = classes;
    j["confusion"] = confusion;
    j["per_class"] = nlohmann::json::object();
    for (size_t c = 0; c < confusion.size(); ++c) {
      int64_t n = 0;
      for (int64_t v : confusion[c]) n += v;
      if (n == 0) continue;
      j["per_class"][classes[c]] = {
          {"boxes", n},
          {"accuracy", 100.0 * static_cast<double>(confusion[c][c]) / static_cast<double>(n)}};
    }
    std::vector<double> r = runner_up_log_prob;
    std::sort(r.begin(), r.end());
    j["runner_up_log_prob_median"] = r.empty() ? 0.0 : r[r.size() / 2];
    return j;
  }
  void print(std::ostream& out) const {
    out << "  per class (accuracy, boxes); confusion (rows: true, columns: predicted):\n";
    for (size_t c = 0; c < confusion.size(); ++c) {
      int64_t n = 0;
      for (int64_t v : confusion[c]) n += v;
      out << fmt::format("    {:<14} {:>6} {:>4} |", classes[c],
                         n ? fmt::format("{:.1f}%", 100.0 * static_cast<double>(confusion[c][c]) /
                                                        static_cast<double>(n))
                           : "-",
                         n);
      for (int64_t v : confusion[c]) out << fmt::format(" {:>4}", v);
      out << "\n";
    }
    out << "  called:";  // the columns' sums: what the boxes were taken for
    for (size_t p = 0; p < classes.size(); ++p) {
      int64_t n = 0;
      for (const auto& row : confusion) n += row[p];
      out << fmt::format(" {} {}", classes[p], n);
    }
    out << "\n";
  }
};

// `verdicts` (may be null): each exact box's, appended.
BoxTally classifySceneBoxes(Recognizer& recognizer, const SequenceFolder& seq, int stride,
                            std::vector<BoxVerdict>* verdicts) {
  BoxTally t;
  t.classes = recognizer.classes();
  const std::string sequence = verdicts ? folderName(seq.dir()) : std::string();
  const int C = static_cast<int>(t.classes.size());
  t.confusion.assign(static_cast<size_t>(C), std::vector<int64_t>(static_cast<size_t>(C), 0));
  std::map<int, std::vector<GroundTruthBox>> by_frame;
  for (const auto& b : seq.boxes()) by_frame[b.frame].push_back(b);
  for (const int frame : framesToScore(seq, stride)) {
    const auto& truth = by_frame[frame];
    if (truth.empty()) continue;
    const cv::Mat image = readImage(seq.framePath(static_cast<size_t>(frame)));
    std::vector<BoxRequest> req;
    std::vector<int> label;        // of each truth box
    std::vector<size_t> truth_of;  // of each request
    for (size_t i = 0; i < truth.size(); ++i) {
      const auto& b = truth[i];
      auto it = std::find(t.classes.begin(), t.classes.end(), b.cls);
      label.push_back(it == t.classes.end() ? C - 1 : static_cast<int>(it - t.classes.begin()));
      req.push_back({b.x, b.y, b.w, b.h, 0});
      truth_of.push_back(i);
      for (const auto& r :
           jitteredBoxes(cv::Rect2d(b.x, b.y, b.w, b.h), image.cols, image.rows, 1, 0.6,
                         static_cast<uint32_t>(frame * 131 + static_cast<int>(i)))) {
        req.push_back({r.x, r.y, r.width, r.height, 1});
        truth_of.push_back(i);
      }
    }
    const FrameDetections d = recognizer.recognize(image, req);
    for (const auto& b : d.boxes) {
      const auto best = std::max_element(b.log_prob.begin(), b.log_prob.end());
      const int pred = static_cast<int>(best - b.log_prob.begin());
      const size_t truth_index = truth_of[static_cast<size_t>(b.input_index)];
      const int truth_label = label[truth_index];
      if (req[static_cast<size_t>(b.input_index)].candidate_id == 1) {
        ++t.jittered;
        t.jittered_correct += pred == truth_label;
        continue;
      }
      ++t.boxes;
      t.correct += pred == truth_label;
      ++t.confusion[static_cast<size_t>(truth_label)][static_cast<size_t>(pred)];
      if (verdicts) verdicts->push_back({sequence, truth[truth_index], pred, b.log_prob});
      std::vector<float> lp = b.log_prob;
      std::nth_element(lp.begin(), lp.begin() + 1, lp.end(), std::greater<float>());
      t.runner_up_log_prob.push_back(lp.size() > 1 ? lp[1] : 0.0);
    }
  }
  return t;
}

// Selective search's boxes (at most `max_boxes`, found on the frame at `width` px) of every
// scored frame through the recognizer and the node's suppression of overlapping boxes, scored as
// single-view detections of `evaluated` against the ground-truth boxes.
nlohmann::json selectiveSearchDetection(Recognizer& recognizer, const RecognizerOptions& options,
                                        const SequenceFolder& seq,
                                        const std::vector<std::string>& evaluated, int stride,
                                        int max_boxes, int width) {
  std::map<int, std::vector<GroundTruthBox>> by_frame;
  for (const auto& b : seq.boxes()) by_frame[b.frame].push_back(b);
  RecognitionScores scores = emptyScores(evaluated);
  int64_t boxes = 0;
  for (const int frame : framesToScore(seq, stride)) {
    const cv::Mat image = readImage(seq.framePath(static_cast<size_t>(frame)));
    std::vector<BoxRequest> req;
    for (const Box2& b : selectiveSearch(image, width, max_boxes))
      req.push_back({b.x, b.y, b.w, b.h, 0});
    FrameDetections d = recognizer.recognize(image, req);
    suppressOverlaps(&d, options.nms_iou, options.nms_per_class);
    std::vector<LabelledBox> labelled;
    for (const auto& b : d.boxes)
      labelled.push_back({Box2{b.x, b.y, b.w, b.h},
                          std::vector<double>(b.log_prob.begin(), b.log_prob.end()), -1});
    boxes += static_cast<int64_t>(labelled.size());
    scoreFrame(d.classes, labelled, by_frame[frame], 0.5, &scores);
  }
  nlohmann::json j = recognitionSection(scores);
  j["proposals"] =
      fmt::format("OpenCV selective search (fast), at most {} boxes per frame found at {} px wide",
                  max_boxes, width);
  j["boxes_per_frame_after_suppression"] =
      scores.frames ? static_cast<double>(boxes) / static_cast<double>(scores.frames) : 0.0;
  return j;
}

// Why an object set cannot be evaluated by held-out instances ("" when it can): leave-one-instance-
// out needs two instances of every category (a category's only instance held out leaves nothing to
// learn it from), one held-out instance per category needs one category with two; both need two
// categories.
std::string whyNotSplit(const ObjectSet& set, bool loio) {
  const auto instances = set.instances();
  if (instances.size() < 2) return "it has fewer than two categories";
  std::vector<std::string> single;
  for (const auto& [category, list] : instances)
    if (list.size() < 2) single.push_back(category);
  if (loio && !single.empty())
    return fmt::format(
        "{} of its {} categories have a single instance ({}{}): leave-one-instance-out cannot hold "
        "it out",
        single.size(), instances.size(),
        fmt::join(single.begin(), single.begin() + std::min<size_t>(single.size(), 5), ", "),
        single.size() > 5 ? ", ..." : "");
  if (single.size() == instances.size()) return "no category has two instances to hold one out";
  return "";
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
std::vector<std::string> extraTrainingFor(const std::string& name,
                                          const std::vector<std::string>& args) {
  std::vector<std::string> dirs;
  for (const auto& a : args) {
    const ExtraTraining e(a);
    if (e.set.empty() ? folderName(e.dir) != name : e.set == name) dirs.push_back(e.dir);
  }
  return dirs;
}

struct Args {
  std::vector<std::string> objects, sequences, extra, held_out;
  std::string model_path = "models/recognizer.model";
  std::string out, config, shared = "../shared/data", protocol = "auto", log_level = "info";
  int max_views = -1, loio_max = 16, ss_boxes = 300, ss_width = 320;
  std::string boxes_csv;
  bool skip_sets = false;
};

void addOptions(CLI::App& app, Args& a) {
  app.add_option(
      "--objects", a.objects,
      "object set folders (default: every set in <shared>/objects and build/data/objects)");
  app.add_option("--out", a.out, "JSON fragment to write")->required();
  app.add_option("--config", a.config,
                 "YAML file with a 'train' section (default: built-in options)")
      ->check(CLI::ExistingFile);
  app.add_option("--shared", a.shared, "the shared data folder");
  app.add_option("--protocol", a.protocol,
                 "auto, loio (leave-one-instance-out) or holdout (one instance per category)")
      ->check(CLI::IsMember({"auto", "loio", "holdout"}));
  app.add_option("--loio-max-instances", a.loio_max,
                 "auto: leave-one-instance-out up to this many instances");
  // One value per occurrence (repeat the option for more): a list would swallow the sequence
  // folders that follow it on the command line (make eval passes them last).
  app.add_option("--hold-out", a.held_out,
                 "leave-one-instance-out: only this instance's folds (e.g. ball_1; repeat for "
                 "more; default: "
                 "every instance)")
      ->expected(1)
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app.add_option(
         "--extra-training", a.extra,
         "[SET=]DIR: an object set (e.g. rendered by slamaware-synth objects) whose crops of the "
         "categories of the evaluated set SET (default: of every set but itself) are added to the "
         "training data of every fold; never tested; repeat for more")
      ->expected(1)
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app.add_option("--max-views", a.max_views,
                 "views per instance (overrides train.max_views_per_instance)");
  app.add_option("--log-level", a.log_level, "trace, debug, info, warn, error");
  app.add_option(
      "sequences", a.sequences,
      "sequence folders: their ground-truth boxes are classified with --model (objects of other "
      "categories count as background)");
  app.add_option("--model", a.model_path, "model for the ground-truth boxes of the sequences");
  app.add_option("--ss-boxes", a.ss_boxes,
                 "photographed sequences: selective-search boxes per frame classified as "
                 "detections (0: none)");
  app.add_option("--ss-width", a.ss_width,
                 "px, frames are downscaled to this width for selective search");
  app.add_flag("--no-object-sets", a.skip_sets, "only the ground-truth boxes of the sequences");
  app.add_option("--boxes-csv", a.boxes_csv,
                 "CSV file: every ground-truth box of the sequences with the class it was called "
                 "and the probability of each class");
}

// The CSV of --boxes-csv: a header, then one row per box of `verdicts`.
void writeBoxesCsv(const std::string& path, const std::vector<std::string>& classes,
                   const std::vector<BoxVerdict>& verdicts) {
  std::ofstream f(path);
  f << "sequence,frame,x,y,w,h,class,instance,called";
  for (const auto& c : classes) f << ",p_" << c;
  f << "\n";
  for (const BoxVerdict& v : verdicts) {
    f << fmt::format("{},{},{:g},{:g},{:g},{:g},{},{},{}", v.sequence, v.box.frame, v.box.x,
                     v.box.y, v.box.w, v.box.h, v.box.cls, v.box.instance,
                     classes[static_cast<size_t>(v.called)]);
    for (float lp : v.log_prob) f << fmt::format(",{:.4f}", std::exp(lp));
    f << "\n";
  }
  if (!f) throw std::runtime_error(path + ": cannot write");
}

void printConfusion(const std::vector<std::string>& classes,
                    const std::vector<std::vector<int64_t>>& confusion) {
  for (size_t i = 0; i < classes.size(); ++i) {
    std::cout << "  " << classes[i];
    for (int64_t n : confusion[i]) std::cout << " " << n;
    std::cout << "\n";
  }
}

// One object set: held-out accuracy (leave-one-instance-out or one instance per category out),
// or why it cannot be split.
nlohmann::json evaluateObjectSet(const std::string& dir, const Args& a,
                                 const TrainOptions& options) {
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
  size_t instances = 0;
  for (const auto& [c, list] : set.instances()) instances += list.size();
  // Photographed sets are small and are what counts: every instance is held out in turn.
  const bool loio =
      a.protocol == "loio" ||
      (a.protocol == "auto" && (!set.rendered() || static_cast<int>(instances) <= a.loio_max));
  const std::string name = folderName(dir);
  const std::string why_not = whyNotSplit(set, loio);
  if (!why_not.empty()) {
    std::cout << name << ": skipped, " << why_not << "\n";
    return {{"skipped", why_not}};
  }
  const std::vector<std::string> extra_dirs = extraTrainingFor(name, a.extra);
  const HeldOutResult r = loio ? leaveOneInstanceOut(dir, options, progress, extra_dirs, a.held_out)
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
  std::cout << name << " (" << r.protocol << "): category accuracy " << r.accuracy() << "% ("
            << r.correct << "/" << r.crops << ")\nconfusion (rows: true, columns: predicted):\n";
  printConfusion(r.classes, r.confusion);
  for (const auto& [inst, acc] : r.instance_accuracy)
    std::cout << "  " << inst << ": " << acc << "%\n";
  return entry;
}

// The ground-truth boxes of every boxed sequence through the model, and on photographed ones
// selective search + the recognizer as detections; into j["sequences"] and j["overall"].
void evaluateSequences(const Args& a, nlohmann::json& j) {
  auto model = std::make_shared<const RecognizerModel>(loadModel(a.model_path));
  const RecognizerOptions recognizer_options;
  Recognizer recognizer(model, recognizer_options);
  BoxTally suite;
  std::vector<BoxVerdict> verdicts;
  for (const auto& dir : a.sequences) {
    const SequenceFolder seq = SequenceFolder::open(dir);
    if (!seq.hasBoxes()) continue;
    const BoxTally t =
        classifySceneBoxes(recognizer, seq, 5, a.boxes_csv.empty() ? nullptr : &verdicts);
    const std::string name = folderName(dir);
    j["sequences"][name]["gt_boxes"] = t.json();
    std::cout << name << ": " << t.json()["accuracy"].get<double>() << "% of " << t.boxes
              << " ground-truth boxes right (jittered: "
              << t.json()["jittered_accuracy"].get<double>() << "%)\n";
    t.print(std::cout);
    if (isSyntheticSequence(seq)) {
      suite.merge(t);
      continue;
    }
    const std::vector<std::string> evaluated = evaluatedClasses(recognizer.classes(), seq);
    if (evaluated.empty() || a.ss_boxes <= 0) continue;
    const nlohmann::json ss = selectiveSearchDetection(recognizer, recognizer_options, seq,
                                                       evaluated, 5, a.ss_boxes, a.ss_width);
    j["sequences"][name]["single_view_ss"] = ss;
    std::cout << name << ": selective search + recognizer, single-view mAP " << ss["mAP"] << " ("
              << ss["boxes_per_frame_after_suppression"] << " boxes per frame)\n";
  }
  if (!a.boxes_csv.empty()) writeBoxesCsv(a.boxes_csv, recognizer.classes(), verdicts);
  if (suite.boxes > 0) {
    j["overall"]["gt_boxes"] = suite.json();
    std::cout << "suite: " << suite.json()["accuracy"].get<double>() << "% of " << suite.boxes
              << " ground-truth boxes right; confusion (rows: true, columns: predicted):\n";
    printConfusion(suite.classes, suite.confusion);
  }
}

void writeJson(const nlohmann::json& j, const std::string& out) {
  fs::path p(out);
  if (p.has_parent_path()) fs::create_directories(p.parent_path());
  std::ofstream f(out);
  f << j.dump(2) << "\n";
  if (!f) throw std::runtime_error(out + ": cannot write");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"slamaware-eval-objects: recognizer accuracy on held-out object instances"};
  Args a;
  addOptions(app, a);
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::from_str(a.log_level));
  try {
    TrainOptions options = loadConfig<TrainOptions>(a.config, "train", false);
    if (a.max_views >= 0) options.max_views_per_instance = a.max_views;
    if (a.objects.empty() && !a.skip_sets) a.objects = defaultObjectSets(a.shared);
    if (a.objects.empty() && !a.skip_sets)
      throw std::runtime_error("no object sets found (give --objects DIR)");
    for (const auto& arg : a.extra) {
      const ExtraTraining e(arg);
      if (!e.set.empty() &&
          std::none_of(a.objects.begin(), a.objects.end(),
                       [&](const std::string& d) { return folderName(d) == e.set; }))
        throw std::runtime_error("--extra-training " + arg + ": no evaluated object set is named " +
                                 e.set);
    }
    nlohmann::json j = nlohmann::json::object();
    j["objects"] = nlohmann::json::object();
    for (const auto& dir : a.objects)
      j["objects"][folderName(dir)] = evaluateObjectSet(dir, a, options);
    if (!a.sequences.empty()) evaluateSequences(a, j);
    writeJson(j, a.out);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  return 0;
}
