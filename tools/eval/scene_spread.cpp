#include "tools/eval/scene_spread.h"

#include <algorithm>
#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "common/image_codec.h"
#include "tools/eval/plot.h"
#include "tools/eval/stats.h"

namespace fs = std::filesystem;

namespace slamaware {

namespace {

struct Figure {
  const char* key;      ///< key in per_scene rows
  const char* section;  ///< section of report["sequences"][name]
  const char* field;    ///< field of that section
  bool higher_is_better;
};

// boxes_per_frame: lower is better only with the same recall, so it gets a median, not a worst.
const Figure kFigures[] = {
    {"recall_iou50", "proposals", "recall_iou50", true},
    {"boxes_per_frame", "proposals", "boxes_per_frame", false},
    {"tracked_pct", "slam", "tracked_pct", true},
    {"single_view_mAP", "single_view", "mAP", true},
    {"multi_view_online_mAP", "multi_view_online", "mAP", true},
    {"multi_view_final_mAP", "multi_view_final", "mAP", true},
};

void drawHistogram(const std::vector<double>& recalls, const std::string& path) {
  // 5-point bins from 0 to 100 %.
  std::vector<int> bins(20, 0);
  for (double r : recalls)
    ++bins[static_cast<size_t>(std::clamp(static_cast<int>(r / 5.0), 0, 19))];
  const int most = std::max(1, *std::max_element(bins.begin(), bins.end()));
  cv::Mat canvas(420, 640, CV_8UC3, cv::Scalar(255, 255, 255));
  PlotAxis x{0, 100, false, {0, 20, 40, 60, 80, 85, 100}, "proposals recall at IoU 0.5 (%)"};
  std::vector<double> yt;
  for (int t = 0; t <= most; t += std::max(1, most / 5)) yt.push_back(t);
  PlotAxis y{0, static_cast<double>(most) * 1.1, false, yt, "scenes"};
  PlotPanel panel(canvas, cv::Rect(0, 0, 640, 420), x, y,
                  "per-scene proposals recall (" + std::to_string(recalls.size()) + " scenes)");
  for (size_t b = 0; b < bins.size(); ++b) {
    if (bins[b] == 0) continue;
    const double x0 = 5.0 * static_cast<double>(b), x1 = x0 + 5.0, h = bins[b];
    panel.curve({{x0, 0}, {x0, h}, {x1, h}, {x1, 0}}, plot_colour::kBlue, "", 2);
  }
  panel.curve({{85, 0}, {85, y.max}}, plot_colour::kRed, "85 % (every scene)", 1);
  fs::create_directories(fs::path(path).parent_path());
  writeImage(path, canvas);
}

}  // namespace

nlohmann::json perSceneSection(const nlohmann::json& report, const std::vector<SceneFolder>& scenes,
                               const std::string& histogram_png) {
  nlohmann::json out = nlohmann::json::object();
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& s : scenes) {
    const nlohmann::json& seq = report["sequences"].value(s.name, nlohmann::json::object());
    nlohmann::json row{{"scene", s.name}};
    const fs::path config = fs::path(s.dir) / "scene.yaml";
    row["config"] = fs::exists(config) ? config.string() : s.dir;
    for (const auto& f : kFigures) {
      const auto sec = seq.find(f.section);
      if (sec == seq.end() || !sec->is_object()) continue;
      const auto v = sec->find(f.field);
      if (v != sec->end() && v->is_number()) row[f.key] = v->get<double>();
    }
    rows.push_back(row);
  }
  out["scenes"] = rows;
  for (const auto& f : kFigures) {
    std::vector<double> values;
    const nlohmann::json* worst = nullptr;
    for (const auto& row : rows) {
      if (!row.contains(f.key)) continue;
      const double v = row[f.key].get<double>();
      values.push_back(v);
      if (f.higher_is_better && (!worst || v < (*worst)[f.key].get<double>())) worst = &row;
    }
    if (values.empty()) continue;
    nlohmann::json fig{{"median", median(values)},
                       {"min", *std::min_element(values.begin(), values.end())},
                       {"max", *std::max_element(values.begin(), values.end())}};
    if (worst) fig["worst"] = {{"scene", (*worst)["scene"]}, {"config", (*worst)["config"]}};
    out[f.key] = fig;
  }
  std::vector<double> recalls;
  for (const auto& row : rows)
    if (row.contains("recall_iou50")) recalls.push_back(row["recall_iou50"].get<double>());
  if (!recalls.empty()) {
    int below = 0;
    for (double r : recalls) below += r < 85.0;
    out["recall_iou50"]["scenes_below_85"] = below;
    drawHistogram(recalls, histogram_png);
    out["recall_iou50"]["plot"] = histogram_png;
  }
  return out;
}

}  // namespace slamaware
