// slamaware-eval-data: checks every sequence of the evaluation suite before the pipeline runs on
// it: frames readable, ground truth present and consistent (a pose per frame, boxes inside the
// image). Writes the "data" section of each sequence in the eval report.
#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "common/dataset.h"
#include "common/image_codec.h"

using namespace slamaware;
namespace fs = std::filesystem;

int main(int argc, char** argv) {
  CLI::App app{"slamaware-eval-data: dataset checks for the eval report"};
  std::string out;
  std::vector<std::string> sequences;
  app.add_option("--out", out, "JSON fragment to write")->required();
  app.add_option("sequences", sequences, "sequence folders")->required();
  CLI11_PARSE(app, argc, argv);

  nlohmann::json report;
  int bad = 0;
  for (const auto& dir : sequences) {
    const std::string name = fs::path(dir).filename().string();
    nlohmann::json d;
    try {
      const SequenceFolder seq = SequenceFolder::open(dir);
      int readable = 0;
      for (size_t i = 0; i < seq.size(); ++i) {
        try {
          const cv::Mat img = readImage(seq.framePath(i));
          readable +=
              img.cols == seq.info().camera.width() && img.rows == seq.info().camera.height();
        } catch (const ImageError& e) {
          std::cerr << "eval-data: " << e.what() << "\n";
        }
      }
      d["frames"] = seq.size();
      d["frames_readable"] = readable;
      d["fps"] = seq.info().fps;
      d["classes"] = seq.info().classes;
      if (seq.hasGroundTruth()) d["groundtruth_poses"] = seq.groundTruth().size();
      if (seq.hasBoxes()) {
        const auto boxes = seq.boxes();
        int outside = 0;
        for (const auto& b : boxes)
          outside += b.x < -1 || b.y < -1 || b.x + b.w > seq.info().camera.width() + 1 ||
                     b.y + b.h > seq.info().camera.height() + 1;
        d["groundtruth_boxes"] = boxes.size();
        d["groundtruth_boxes_outside_image"] = outside;
      }
      if (seq.hasObjects()) d["groundtruth_objects"] = seq.objects().size();
      d["ok"] = readable == static_cast<int>(seq.size());
    } catch (const DatasetError& e) {
      d["ok"] = false;
      d["error"] = e.what();
      std::cerr << "eval-data: " << e.what() << "\n";
    }
    bad += !d["ok"].get<bool>();
    report["sequences"][name]["data"] = d;
  }
  std::ofstream(out) << report.dump(2) << "\n";
  return bad ? 1 : 0;
}
