#include "tools/report/report_markdown.h"

#include <cstdio>
#include <map>
#include <set>
#include <sstream>

namespace slamaware {

namespace {

std::string cell(const nlohmann::json& v) {
  if (v.is_null()) return "–";
  if (v.is_number_float()) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.4g", v.get<double>());
    return buf;
  }
  if (v.is_string()) return v.get<std::string>();
  if (v.is_primitive()) return v.dump();
  return "…";
}

// Scalars of an object, flattened with dotted keys (nested objects one level deep).
void flatten(const nlohmann::json& obj, const std::string& prefix,
             std::map<std::string, nlohmann::json>& out, int depth) {
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
    if (it->is_object() && depth > 0)
      flatten(*it, key, out, depth - 1);
    else if (!it->is_structured())
      out[key] = *it;
  }
}

// Sections with tables of their own (below), left out of the generic per-section tables.
const std::set<std::string> kOwnTables = {"single_view", "multi_view_online", "multi_view_final",
                                          "single_view_ss"};

// The paper's numbers that we can cite: Pillai & Leonard, RSS 2015, on UW RGB-D Scenes v2.
constexpr double kPaperSingleViewMap = 81.5, kPaperMultiViewMap = 89.8;

const nlohmann::json& at(const nlohmann::json& j, const std::string& a, const std::string& b = "",
                         const std::string& c = "") {
  static const nlohmann::json none;
  const nlohmann::json* p = &j;
  for (const std::string* k : {&a, &b, &c}) {
    if (k->empty()) break;
    if (!p->is_object() || !p->contains(*k)) return none;
    p = &(*p)[*k];
  }
  return *p;
}

// A percentage with one decimal, "–" when absent.
std::string pct(const nlohmann::json& v) {
  if (!v.is_number()) return "–";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f", v.get<double>());
  return buf;
}

// A plot written by the eval into <out-dir>/plots/, linked from <out-dir>/report.md.
std::string plotLink(const nlohmann::json& path, const std::string& alt) {
  if (!path.is_string()) return "";
  const std::string p = path.get<std::string>();
  return "![" + alt + "](plots/" + p.substr(p.find_last_of('/') + 1) + ")\n\n";
}

// Recognition in the paper's style: per class AP, precision and recall, single view against
// multi-view (online and final), the mAP rows, and the paper's mAPs beside ours; then one row per
// sequence, and the photographed frames' ground-truth boxes and selective-search detections.
void recognitionTables(const nlohmann::json& report, std::ostringstream& md) {
  const nlohmann::json& single = at(report, "overall", "single_view");
  const nlohmann::json& online = at(report, "overall", "multi_view_online");
  const nlohmann::json& final = at(report, "overall", "multi_view_final");
  bool any_sequence = false;
  for (auto& [name, seq] : at(report, "sequences").items())
    any_sequence = any_sequence || seq.contains("single_view");
  if (!single.is_null() || any_sequence) {
    md << "## Recognition: single view and multi-view\n\n"
          "Every 5th frame, each box as the system published it is a detection of every class: "
          "single view "
          "scores the recognizer's p(class | box) from that frame alone (DETECTIONS); multi-view "
          "online the "
          "object map's score of the box at that frame, its object's evidence up to it "
          "(OBJECT_DETECTIONS: "
          "what a user saw then); multi-view final the paper's protocol, the box's object labelled "
          "by the last "
          "OBJECT_MAP (hindsight: later frames label earlier boxes). True positive at IoU >= 0.5 "
          "with an "
          "unmatched ground-truth box of the class; AP = VOC all-point area under the "
          "precision-recall curve; "
          "precision and recall at the label the system gives (argmax, background included). "
          "Distractor "
          "objects (classes outside the model) are not ground truth. Details: "
          "tools/eval/README.md.\n\n";
  }
  if (!single.is_null()) {
    md << "### Synthetic suite (detections of every scene pooled)\n\n"
          "| class | ground-truth boxes | AP single | AP online | AP final | precision single | "
          "precision online | "
          "precision final | recall single | recall online | recall final | boxed |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (auto& [cls, c] : at(single, "per_class").items()) {
      const nlohmann::json& o = at(online, "per_class", cls);
      const nlohmann::json& f = at(final, "per_class", cls);
      md << "| " << cls << " | " << cell(at(c, "ground_truth_boxes"));
      for (const char* key : {"AP", "precision", "recall"})
        md << " | " << pct(at(c, key)) << " | " << pct(at(o, key)) << " | " << pct(at(f, key));
      md << " | " << pct(at(c, "boxed")) << " |\n";
    }
    md << "| **mAP** (classes with ground truth) | " << cell(at(single, "ground_truth_boxes"))
       << " | **" << pct(at(single, "mAP")) << "** | **" << pct(at(online, "mAP")) << "** | **"
       << pct(at(final, "mAP")) << "** | | | | " << pct(at(single, "recall")) << " | "
       << pct(at(online, "recall")) << " | " << pct(at(final, "recall")) << " | "
       << pct(at(single, "boxed")) << " |\n";
    char paper[200];
    std::snprintf(paper, sizeof(paper),
                  "| Pillai & Leonard 2015, UW RGB-D Scenes v2 (their numbers), mAP | | %.1f | | "
                  "%.1f | | | | | | | |\n",
                  kPaperSingleViewMap, kPaperMultiViewMap);
    md << paper;
    md << "| bound: mean boxed share, no labelling of these boxes does better | | "
       << pct(at(single, "mAP_bound")) << " | " << pct(at(online, "mAP_bound")) << " | "
       << pct(at(final, "mAP_bound")) << " | | | | | | | |\n\n"
       << "*Boxed*: the share of the ground-truth boxes that some proposal box overlaps at IoU >= "
          "0.5. A box "
          "no proposal covers is missed whatever the labels, so a class's recall and AP are at "
          "most its "
          "boxed share; the rest is the labelling's.\n\n";
    md << plotLink(at(single, "plot"), "precision-recall per class, synthetic suite");
  }
  if (any_sequence) {
    md << "### Per sequence\n\n| sequence | ground-truth boxes | boxes | mAP single | mAP online | "
          "mAP final | "
          "recall single | recall online | recall final | objects in the map |\n"
          "|---|---|---|---|---|---|---|---|---|---|\n";
    for (auto& [name, seq] : report["sequences"].items()) {
      const nlohmann::json& s = at(seq, "single_view");
      const nlohmann::json& o = at(seq, "multi_view_online");
      const nlohmann::json& f = at(seq, "multi_view_final");
      if (s.is_null()) continue;
      md << "| " << name << " | " << cell(at(s, "ground_truth_boxes")) << " | "
         << cell(at(s, "boxes")) << " | " << pct(at(s, "mAP")) << " | " << pct(at(o, "mAP"))
         << " | " << pct(at(f, "mAP")) << " | " << pct(at(s, "recall")) << " | "
         << pct(at(o, "recall")) << " | " << pct(at(f, "recall")) << " | " << cell(at(f, "objects"))
         << " |\n";
    }
    md << "\n";
  }
  // Photographed frames: the recognizer on their hand-drawn boxes, and on selective search's boxes.
  bool any_real = false;
  for (auto& [name, seq] : at(report, "sequences").items())
    any_real = any_real || seq.contains("single_view_ss");
  if (!any_real) return;
  md << "## Recognition on photographed frames (no SLAM)\n\n"
        "The ground-truth boxes of each frame classified by the recognizer (accuracy of the best "
        "class, "
        "background included), and OpenCV selective search's boxes of each frame through the "
        "recognizer "
        "and its suppression, scored as single-view detections.\n\n"
        "| sequence | boxes | accuracy | per class (accuracy, boxes) | selective search + "
        "recognizer mAP | recall |\n"
        "|---|---|---|---|---|---|\n";
  for (auto& [name, seq] : report["sequences"].items()) {
    if (!seq.contains("single_view_ss")) continue;
    const nlohmann::json& g = at(seq, "gt_boxes");
    std::string per_class;
    for (auto& [cls, c] : at(g, "per_class").items())
      per_class += (per_class.empty() ? "" : ", ") + cls + " " + pct(at(c, "accuracy")) + " (" +
                   cell(at(c, "boxes")) + ")";
    md << "| " << name << " | " << cell(at(g, "boxes")) << " | " << pct(at(g, "accuracy")) << " | "
       << per_class << " | " << pct(at(seq, "single_view_ss", "mAP")) << " | "
       << pct(at(seq, "single_view_ss", "recall")) << " |\n";
  }
  md << "\n";
}

// The recognizer's time against the number of classes (make bench), when the report has it.
void classesRuntimeTable(const nlohmann::json& report, std::ostringstream& md) {
  const nlohmann::json& t5 = at(report, "recognizer_ms_per_frame");
  if (!t5.is_number() || t5.get<double>() <= 0) return;
  md << "## Recognizer runtime against the number of classes\n\n"
        "640x480 frame, 30 boxes, 1 thread (features, encoding and scoring); the paper: 1,600 ms "
        "per "
        "frame for features and encoding.\n\n"
        "| classes (+ background) | ms per frame | relative to 5 |\n|---|---|---|\n";
  for (const auto& [classes, key] :
       std::vector<std::pair<int, std::string>>{{5, "recognizer_ms_per_frame"},
                                                {10, "recognizer_ms_per_frame_10_classes"},
                                                {51, "recognizer_ms_per_frame_51_classes"}}) {
    const nlohmann::json& t = at(report, key);
    if (!t.is_number()) continue;
    char buf[128];
    std::snprintf(buf, sizeof(buf), "| %d | %.1f | %.2f |\n", classes, t.get<double>(),
                  t.get<double>() / t5.get<double>());
    md << buf;
  }
  md << "\n";
  const nlohmann::json& t12 = at(report, "recognizer_ms_per_frame_12_boxes");
  if (t12.is_number()) {
    char buf[256];
    std::snprintf(buf, sizeof(buf),
                  "With 12 boxes of 20-128 px, about as many as a frame publishes (features only "
                  "where a box is): "
                  "%.1f ms per frame, 5 classes. The recognizer classifies about twice as many, "
                  "every proposal box, "
                  "before suppressing overlaps.\n\n",
                  t12.get<double>());
    md << buf;
  }
}

// The spread over the scenes of a run (overall.per_scene): a row per scene, then per figure its
// median and its worst scene with the config that reproduces it.
void perSceneTable(const nlohmann::json& report, std::ostringstream& md) {
  const nlohmann::json& spread = at(report, "overall", "per_scene");
  if (!spread.is_object() || !spread.contains("scenes")) return;
  static const char* kColumns[] = {"recall_iou50",          "boxes_per_frame",
                                   "tracked_pct",           "single_view_mAP",
                                   "multi_view_online_mAP", "multi_view_final_mAP"};
  md << "## Per scene\n\n| scene |";
  for (const char* c : kColumns) md << " " << c << " |";
  md << "\n|---|";
  for (size_t i = 0; i < std::size(kColumns); ++i) md << "---|";
  md << "\n";
  for (const auto& row : spread["scenes"]) {
    md << "| " << row.value("scene", "?") << " |";
    for (const char* c : kColumns) md << " " << (row.contains(c) ? cell(row[c]) : "–") << " |";
    md << "\n";
  }
  md << "\n| figure | median | min | max | worst scene (config) |\n|---|---|---|---|---|\n";
  for (const char* c : kColumns) {
    if (!spread.contains(c)) continue;
    const nlohmann::json& f = spread[c];
    md << "| " << c << " | " << cell(f["median"]) << " | " << cell(f["min"]) << " | "
       << cell(f["max"]) << " | "
       << (f.contains("worst") ? f["worst"].value("config", "") : std::string("–")) << " |\n";
  }
  if (spread.contains("recall_iou50") && spread["recall_iou50"].contains("plot"))
    md << "\nScenes under 85 % proposals recall: "
       << cell(spread["recall_iou50"]["scenes_below_85"])
       << "; histogram: " << spread["recall_iou50"]["plot"].get<std::string>() << "\n";
  md << "\n";
}

}  // namespace

std::string renderMarkdown(const nlohmann::json& report) {
  std::ostringstream md;
  md << "# slamaware report\n\n";
  recognitionTables(report, md);
  classesRuntimeTable(report, md);
  perSceneTable(report, md);
  // Per-sequence sections: one table per section name, a row per sequence.
  if (report.contains("sequences") && report["sequences"].is_object()) {
    std::set<std::string> sections;
    for (auto& [name, seq] : report["sequences"].items())
      for (auto& [section, v] : seq.items())
        if (v.is_object() && !kOwnTables.count(section)) sections.insert(section);
    for (const auto& section : sections) {
      std::map<std::string, std::map<std::string, nlohmann::json>> rows;
      std::set<std::string> columns;
      for (auto& [name, seq] : report["sequences"].items()) {
        if (!seq.contains(section)) continue;
        flatten(seq[section], "", rows[name], 1);
        for (auto& kv : rows[name]) columns.insert(kv.first);
      }
      if (report.contains("overall") && report["overall"].contains(section)) {
        flatten(report["overall"][section], "", rows["**overall**"], 1);
        for (auto& kv : rows["**overall**"]) columns.insert(kv.first);
      }
      md << "## " << section << "\n\n| sequence |";
      for (const auto& c : columns) md << " " << c << " |";
      md << "\n|---|";
      for (size_t i = 0; i < columns.size(); ++i) md << "---|";
      md << "\n";
      for (auto& [name, row] : rows) {
        md << "| " << name << " |";
        for (const auto& c : columns) md << " " << (row.count(c) ? cell(row[c]) : "–") << " |";
        md << "\n";
      }
      md << "\n";
    }
  }
  // Every other top-level key: a key/value table.
  for (auto& [key, v] : report.items()) {
    if (key == "sequences" || key == "overall") continue;
    std::map<std::string, nlohmann::json> flat;
    if (v.is_object())
      flatten(v, "", flat, 3);
    else
      flat[key] = v;
    md << "## " << key << "\n\n| key | value |\n|---|---|\n";
    for (auto& [k, val] : flat) md << "| " << k << " | " << cell(val) << " |\n";
    md << "\n";
  }
  return md.str();
}

}  // namespace slamaware
