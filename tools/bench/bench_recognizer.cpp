// slamaware-bench-recognizer: speed of the recognizer on one thread (docs/architecture.md §7), as
// a flat JSON object of medians:
//   recognizer_ms_per_frame            a 640x480 frame with 30 boxes: features, PCA, assignment,
//                                      encoding (the encoder the cost model picks) and scoring
//   recognizer_ms_per_frame_12_boxes   the same with 12 boxes of 20 to 128 px, about what a frame
//                                      publishes (features and codes only where a box is; the
//                                      proposals send about twice as many, the suppression drops
//                                      the rest)
//   flair_speedup_vs_direct_1000_boxes direct time / FLAIR time (table build included) for 1000
//                                      boxes of uniformly random size from 20x20 px to the image
//   flair_area_ratio_full_vs_32px      FLAIR time per box: whole-image box / 32x32 box
//   classes_runtime_ratio_51_vs_5      recognizer_ms_per_frame with 51 (+ background) classes over
//   5 flair_table_mb                     FLAIR table memory for a whole 640x480 frame (MB = 1e6
//   bytes) flair_crossover_boxes              box count (of the 1000-box distribution) above which
//   FLAIR is
//                                      cheaper than the direct encoder
// plus the parts these come from. Frames: the shared real sequences when present, else textured
// synthetic frames; PCA and vocabulary are fitted on the frames' own features and the classifier
// weights are random (timing does not depend on their values).
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "common/bus/image_msg.h"
#include "common/dataset.h"
#include "common/image_codec.h"
#include "procs/recognizer/recognizer.h"

using namespace slamaware;
using namespace slamaware::recognizer;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

namespace {

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

cv::Mat syntheticFrame(int seed) {
  std::mt19937 rng(static_cast<uint32_t>(seed));
  cv::Mat coarse(30, 40, CV_8UC3), img;
  cv::randu(coarse, 0, 255);
  cv::resize(coarse, img, cv::Size(640, 480), 0, 0, cv::INTER_CUBIC);
  std::uniform_int_distribution<int> x(0, 639), y(0, 479), r(5, 80), c(0, 255);
  for (int k = 0; k < 60; ++k)
    cv::rectangle(img, cv::Rect(x(rng), y(rng), r(rng), r(rng)), cv::Scalar(c(rng), c(rng), c(rng)),
                  cv::FILLED);
  cv::Mat noise(480, 640, CV_8UC3);
  cv::randn(noise, 0, 8);
  return img + noise;
}

// 640x480 frames: every 8th frame of the shared sequences, or synthetic ones.
std::vector<cv::Mat> benchFrames(const std::string& shared, int count) {
  std::vector<cv::Mat> frames;
  for (const char* name :
       {"sequences/tum_fr3_cabinet_keyframes", "sequences/middlebury_temple_ring"}) {
    const fs::path dir = fs::path(shared) / name;
    if (!fs::exists(dir / "sequence.yaml")) continue;
    const SequenceFolder seq = SequenceFolder::open(dir.string());
    for (size_t i = 0; i < seq.size() && static_cast<int>(frames.size()) < count; i += 8) {
      cv::Mat img = readImage(seq.framePath(i));
      if (img.cols != 640 || img.rows != 480) cv::resize(img, img, cv::Size(640, 480));
      frames.push_back(img);
    }
  }
  for (int s = 0; static_cast<int>(frames.size()) < count; ++s) frames.push_back(syntheticFrame(s));
  return frames;
}

// Boxes of uniformly random size in [min_side, max_w] x [min_side, max_h], uniformly placed.
std::vector<BoxRequest> randomBoxes(std::mt19937& rng, int n, double max_w, double max_h) {
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<BoxRequest> boxes;
  for (int i = 0; i < n; ++i) {
    const double w = 20 + u(rng) * (max_w - 20), h = 20 + u(rng) * (max_h - 20);
    boxes.push_back(BoxRequest{u(rng) * (640 - w), u(rng) * (480 - h), w, h, i});
  }
  return boxes;
}

/// Random weights for `classes` classes + background (timing does not depend on their values).
void setRandomClassifier(RecognizerModel* m, int classes) {
  LinearClassifier& c = m->classifier;
  c.classes.clear();
  for (int i = 0; i < classes; ++i) c.classes.push_back("class_" + std::to_string(i));
  c.classes.push_back("background");
  c.weights = MatrixRM::Random(classes + 1, m->params.encodedDims()) * 0.01f;
  c.bias = Eigen::VectorXf::Zero(classes + 1);
}

std::shared_ptr<RecognizerModel> benchModel(const std::vector<cv::Mat>& frames, int classes) {
  auto m = std::make_shared<RecognizerModel>();
  DenseFeatureExtractor ex(m->params.features);
  FeatureGrid g;
  MatrixRM sample(40000, kFeatureDims);
  std::mt19937 rng(1);
  int64_t row = 0;
  for (size_t f = 0; f < frames.size() && row < sample.rows(); ++f) {
    ex.setImage(frames[f]);
    ex.extract(ex.imageCells(), &g);
    for (int k = 0; k < 10000 && row < sample.rows(); ++k, ++row) {
      const float* src =
          g.features.row(static_cast<int64_t>(rng() % static_cast<uint32_t>(g.features.rows())));
      std::copy(src, src + kFeatureDims, sample.row(row).data());
    }
  }
  sample.conservativeResize(row, kFeatureDims);
  m->pca = Pca::fit(sample, m->params.pca_dims);
  MatrixRM y(sample.rows(), m->params.pca_dims);
  m->pca.project(sample, y);
  m->vocabulary = Vocabulary::train(y, m->params.vocabulary_size, 2, 30);
  setRandomClassifier(m.get(), classes);
  m->check("bench model");
  return m;
}

// 1. Frames with 30 object-sized boxes (20x20 up to a quarter of the image), 5, 10 and 51 classes;
// then about 12 boxes of 20 to 128 px, as many as a frame publishes.
void benchPerFrame(const std::vector<cv::Mat>& frames,
                   const std::shared_ptr<RecognizerModel>& model5, std::mt19937& rng,
                   nlohmann::json& j) {
  // The same encoding with 10 and 51 classes (+ background): only the classifier grows.
  auto withClasses = [&](int classes) {
    auto m = std::make_shared<RecognizerModel>(*model5);
    setRandomClassifier(m.get(), classes);
    return std::shared_ptr<const RecognizerModel>(m);
  };
  auto model10 = withClasses(10), model51 = withClasses(51);
  RecognizerOptions opts;
  Recognizer rec5(model5, opts), rec10(model10, opts), rec51(model51, opts);
  std::vector<double> t5, t10, t51, feat, code, enc, score, decode;
  int flair_frames = 0;
  for (int r = 0; r < 3; ++r)
    for (const cv::Mat& f : frames) {
      const auto boxes = randomBoxes(rng, 30, 320, 240);
      // JPEG decoding happens in the node before recognize(); measured apart.
      const image_t msg = makeImageMessage(f, 0, 0, image_t::PIXEL_FORMAT_JPEG, 90);
      auto t0 = Clock::now();
      const cv::Mat decoded = decodeImageMessage(msg, "bench");
      decode.push_back(msSince(t0));
      const FrameDetections d5 = rec5.recognize(f, boxes);
      const FrameDetections d10 = rec10.recognize(f, boxes);
      const FrameDetections d51 = rec51.recognize(f, boxes);
      if (r == 0) continue;  // warm-up pass
      t5.push_back(d5.total_ms);
      t10.push_back(d10.total_ms);
      t51.push_back(d51.total_ms);
      feat.push_back(d5.stats.features_ms);
      code.push_back(d5.stats.coding_ms);
      enc.push_back(d5.stats.encode_ms);
      score.push_back(d5.total_ms - d5.stats.features_ms - d5.stats.coding_ms - d5.stats.encode_ms);
      flair_frames += d5.stats.used == EncoderKind::kFlair;
    }
  j["recognizer_ms_per_frame"] = median(t5);
  j["recognizer_ms_per_frame_10_classes"] = median(t10);
  j["recognizer_ms_per_frame_51_classes"] = median(t51);
  j["classes_runtime_ratio_51_vs_5"] = median(t51) / median(t5);
  j["recognizer_features_ms"] = median(feat);
  j["recognizer_pca_assign_ms"] = median(code);
  j["recognizer_encode_ms_30_boxes"] = median(enc);
  j["recognizer_score_ms_30_boxes"] = median(score);
  j["recognizer_frames_using_flair_pct"] = 100.0 * flair_frames / std::max<size_t>(1, t5.size());
  j["recognizer_jpeg_decode_ms"] = median(decode);
  // About 12 boxes of 20 to 128 px, as many as a frame publishes (features and codes are
  // computed only where a box is).
  std::vector<double> t12;
  for (int r = 0; r < 3; ++r)
    for (const cv::Mat& f : frames) {
      const double ms = rec5.recognize(f, randomBoxes(rng, 12, 128, 128)).total_ms;
      if (r > 0) t12.push_back(ms);
    }
  j["recognizer_ms_per_frame_12_boxes"] = median(t12);
}

// 2. FLAIR against the direct encoder on 1000 boxes (both after the shared features and codes).
// Returns the median time to build FLAIR's tables for a frame (ms).
double benchFlairVsDirect(const std::vector<cv::Mat>& frames, const RecognizerModel& model,
                          FrameEncoder& encoder, std::mt19937& rng, int reps, nlohmann::json& j) {
  std::vector<double> flair_ms, direct_ms, build_ms, per_box_flair, per_box_direct,
      descriptors_per_box;
  std::vector<double> crossover;
  ReusableMatrix out_rows;
  FlairEncoder flair_alone;
  for (int r = 0; r < reps; ++r) {
    const cv::Mat& f = frames[static_cast<size_t>(r) % frames.size()];
    std::vector<PyramidBox> boxes;
    double descriptors = 0;
    for (const auto& b : randomBoxes(rng, 1000, 640, 480)) {
      PyramidBox pb;
      encoder.snap(b.x, b.y, b.w, b.h, 640, 480, &pb);
      boxes.push_back(pb);
      descriptors +=
          static_cast<double>(pb.cells().area()) * model.params.features.descriptorsPerCell();
    }
    FrameEncoder::Stats sd, sf;
    encoder.encode(f, boxes, EncoderKind::kDirect, &out_rows, &sd);
    encoder.encode(f, boxes, EncoderKind::kFlair, &out_rows, &sf);
    direct_ms.push_back(sd.encode_ms);
    flair_ms.push_back(sf.encode_ms);
    // FLAIR's build alone: the same frame and span, no boxes encoded (memory already mapped, as
    // in the running process).
    if (r == 0) flair_alone.build(encoder.codes(), model.vocabulary, encoder.codes().region);
    auto t0 = Clock::now();
    flair_alone.build(encoder.codes(), model.vocabulary, encoder.codes().region);
    const double build = msSince(t0);
    build_ms.push_back(build);
    const double fpb = (sf.encode_ms - build) / boxes.size(), dpb = sd.encode_ms / boxes.size();
    per_box_flair.push_back(fpb * 1000);
    per_box_direct.push_back(dpb * 1000);
    descriptors_per_box.push_back(descriptors / boxes.size());
    crossover.push_back(dpb > fpb ? build / (dpb - fpb) : 1e9);
  }
  j["flair_ms_1000_boxes"] = median(flair_ms);
  j["direct_ms_1000_boxes"] = median(direct_ms);
  j["flair_speedup_vs_direct_1000_boxes"] = median(direct_ms) / median(flair_ms);
  j["flair_table_build_ms_640x480"] = median(build_ms);
  j["flair_us_per_box"] = median(per_box_flair);
  j["direct_us_per_box_1000_box_distribution"] = median(per_box_direct);
  j["direct_descriptors_per_box_1000_box_distribution"] = median(descriptors_per_box);
  j["flair_crossover_boxes"] = median(crossover);
  return median(build_ms);
}

// 3. FLAIR time per box against box area (tables built once; each box encoded many times), and
// the direct encoder's time model from the same two boxes.
void benchCostModel(const cv::Mat& f, const RecognizerModel& model, FrameEncoder& encoder,
                    double build_ms, nlohmann::json& j) {
  ReusableMatrix out_rows;
  PyramidBox full, small;
  encoder.snap(0, 0, 640, 480, 640, 480, &full);
  encoder.snap(304, 224, 32, 32, 640, 480, &small);
  encoder.encode(f, {full}, EncoderKind::kDirect, &out_rows);
  FlairEncoder flair;
  flair.build(encoder.codes(), model.vocabulary, encoder.codes().region);
  std::vector<float> v(static_cast<size_t>(model.params.encodedDims()));
  auto perBox = [&](const PyramidBox& b) {
    std::vector<double> batches;
    for (int r = 0; r < 15; ++r) {
      auto t0 = Clock::now();
      for (int k = 0; k < 40; ++k) flair.encode(b, v.data());
      batches.push_back(msSince(t0) * 1000 / 40);
    }
    return median(batches);
  };
  perBox(full);
  const double us_full = perBox(full), us_small = perBox(small);
  j["flair_us_per_box_full_image"] = us_full;
  j["flair_us_per_box_32px"] = us_small;
  j["flair_area_ratio_full_vs_32px"] = us_full / us_small;
  // The direct encoder's time model (EncoderCostModel): a fixed part per box plus a part per
  // descriptor, from the same two boxes.
  DirectEncoder direct(encoder.codes(), model.vocabulary);
  auto directPerBox = [&](const PyramidBox& b) {
    std::vector<double> batches;
    for (int r = 0; r < 9; ++r) {
      auto t0 = Clock::now();
      for (int k = 0; k < 10; ++k) direct.encode(b, v.data());
      batches.push_back(msSince(t0) * 1000 / 10);
    }
    return median(batches);
  };
  const double per_cell = model.params.features.descriptorsPerCell();
  const double d_full = directPerBox(full), d_small = directPerBox(small);
  const double n_full = full.cells().area() * per_cell, n_small = small.cells().area() * per_cell;
  const double ns_per_descriptor = (d_full - d_small) / (n_full - n_small) * 1000;
  j["cost_direct_ns_per_descriptor"] = ns_per_descriptor;
  j["cost_direct_us_per_box"] = d_small - n_small * ns_per_descriptor / 1000;
  j["cost_flair_us_per_box"] = 0.5 * (us_full + us_small);
  j["cost_flair_ns_per_corner"] = build_ms * 1e6 / (81.0 * 61.0);
}

void writeJson(const nlohmann::json& j, const std::string& out) {
  fs::path p(out);
  if (p.has_parent_path()) fs::create_directories(p.parent_path());
  std::ofstream f(out);
  f << j.dump(2) << "\n";
  if (!f) throw std::runtime_error(out + ": cannot write");
  std::cout << j.dump(2) << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"slamaware-bench-recognizer: recognizer speed on one thread (flat JSON of medians)"};
  std::string out, shared = "../shared/data";
  int frames_n = 8, reps = 5;
  app.add_option("--out", out, "JSON file to write")->required();
  app.add_option("--shared", shared,
                 "the shared data folder (frames of its sequences are used if present)");
  app.add_option("--frames", frames_n, "frames to average over");
  app.add_option("--reps", reps, "repetitions of the FLAIR/direct comparisons");
  bool classes_only = false;
  app.add_flag("--classes-only", classes_only,
               "only the time per frame against the number of classes (for make eval)");
  CLI11_PARSE(app, argc, argv);
  cv::setNumThreads(1);  // one thread, as the benchmark is defined
  spdlog::set_level(spdlog::level::warn);
  try {
    const std::vector<cv::Mat> frames = benchFrames(shared, frames_n);
    auto model5 = benchModel(frames, 5);
    nlohmann::json j;
    std::mt19937 rng(11);
    benchPerFrame(frames, model5, rng, j);
    if (!classes_only) {
      FrameEncoder encoder(model5->params, model5->pca, model5->vocabulary);
      const double build_ms = benchFlairVsDirect(frames, *model5, encoder, rng, reps, j);
      benchCostModel(frames[0], *model5, encoder, build_ms, j);
      j["flair_table_mb"] =
          FlairEncoder::tableBytesFor(CellRect{0, 0, 80, 60}, model5->params.vocabulary_size,
                                      model5->params.pca_dims) /
          1e6;
      j["recognizer_bench_frames"] = frames.size();
    }
    writeJson(j, out);
  } catch (const std::exception& e) {
    std::cerr << "slamaware-bench-recognizer: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
