#include "tools/train/trainer.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <set>
#include <sstream>

#include "common/config.h"
#include "common/dataset.h"
#include "common/image_codec.h"
#include "common/parallel.h"
#include "common/progress.h"
#include "tools/train/object_box.h"

namespace slamaware::recognizer {

namespace {

double uniform01(std::mt19937& rng) { return static_cast<double>(rng()) / 4294967296.0; }

double iou(const cv::Rect2d& a, const cv::Rect2d& b) {
  const double inter = (a & b).area();
  const double uni = a.area() + b.area() - inter;
  return uni > 0 ? inter / uni : 0.0;
}

// Seed for item i of stage `stage` (stable whatever else is trained).
uint32_t subSeed(uint32_t seed, uint32_t stage, uint32_t i) {
  std::seed_seq seq{seed, stage, i};
  uint32_t out;
  seq.generate(&out, &out + 1);
  return out;
}

int indexOf(const std::vector<std::string>& v, const std::string& s) {
  auto it = std::find(v.begin(), v.end(), s);
  return it == v.end() ? -1 : static_cast<int>(it - v.begin());
}

// The class index of a crop's category; `other` (background) for a category the model lacks.
int labelOf(const std::vector<std::string>& classes, const std::string& category, int other) {
  const int i = indexOf(classes, category);
  return i >= 0 ? i : other;
}

// The box covering a whole image, on its pooling grid.
PyramidBox wholeImage(const FrameEncoder& encoder, const cv::Mat& image) {
  PyramidBox b;
  encoder.snap(0, 0, image.cols, image.rows, image.cols, image.rows, &b);
  return b;
}

// Softmax probability of the last class (background) from raw one-vs-all scores.
double backgroundProbability(const float* s, int C) {
  float lp[256];
  std::vector<float> big;
  float* out = lp;
  if (C > 256) {
    big.resize(static_cast<size_t>(C));
    out = big.data();
  }
  calibratedLogProbabilities(s, C, 1.f, 0.f, out);
  return std::exp(static_cast<double>(out[C - 1]));
}

struct Split {
  std::vector<bool> crop_val, frame_val;
  std::vector<std::string> held_out_instances;
  std::vector<std::string>
      held_out_sequences;  ///< empty for a domain whose frames are held out one in n
};

// Held out, separately for rendered and photographed data (so that both are validated, and a lone
// photographed sequence is not all held out): one instance of each category with two or more (a
// single instance: every 5th view), one sequence when there are several, else every
// holdout_frame_every-th frame.
Split makeSplit(const std::vector<LabeledCrop>& crops, const std::vector<SceneFrame>& frames,
                const TrainOptions& options) {
  Split s;
  s.crop_val.assign(crops.size(), false);
  s.frame_val.assign(frames.size(), false);
  if (!options.validation) return s;
  std::map<std::pair<std::string, bool>, std::set<std::string>> instances;
  for (const auto& c : crops) instances[{c.category, c.real}].insert(c.instance);
  std::mt19937 rng(subSeed(static_cast<uint32_t>(options.seed), 1, 0));
  std::set<std::string> held;
  for (const auto& [key, names] : instances) {
    if (names.size() < 2) continue;
    auto it = names.begin();
    std::advance(it, static_cast<long>(rng() % names.size()));
    held.insert(*it);
  }
  s.held_out_instances.assign(held.begin(), held.end());
  std::map<std::string, int> view_counter;
  for (size_t i = 0; i < crops.size(); ++i) {
    const auto& c = crops[i];
    if (held.count(c.instance)) {
      s.crop_val[i] = true;
    } else if (instances[{c.category, c.real}].size() < 2) {
      s.crop_val[i] =
          (view_counter[c.instance]++ % 5) == 4;  // single instance: hold out every 5th view
    }
  }
  for (const bool real : {false, true}) {
    std::vector<std::string> sequences;
    std::vector<size_t> domain_frames;
    for (size_t f = 0; f < frames.size(); ++f) {
      if (frames[f].real != real) continue;
      domain_frames.push_back(f);
      if (std::find(sequences.begin(), sequences.end(), frames[f].sequence) == sequences.end())
        sequences.push_back(frames[f].sequence);
    }
    if (sequences.size() >= 2) {
      const std::string& held_scene = sequences[rng() % sequences.size()];
      for (size_t f : domain_frames) s.frame_val[f] = frames[f].sequence == held_scene;
      s.held_out_sequences.push_back(held_scene);
    } else if (domain_frames.size() >= 2) {
      const int every = std::max(2, options.holdout_frame_every);
      for (size_t k = 0; k < domain_frames.size(); ++k)
        s.frame_val[domain_frames[k]] = static_cast<int>(k) % every == every / 2;
    }
  }
  return s;
}

// Encodes `boxes` of one scene frame as background examples (group = -1 - frame index).
// The pixel boxes that snap to the image's pooling grid, encoded into the rows of the result (none
// when no box snaps).
ReusableMatrix encodeRects(FrameEncoder& encoder, const cv::Mat& image,
                           const std::vector<cv::Rect2d>& boxes) {
  std::vector<PyramidBox> snapped;
  for (const auto& r : boxes) {
    PyramidBox b;
    if (encoder.snap(r.x, r.y, r.width, r.height, image.cols, image.rows, &b)) snapped.push_back(b);
  }
  ReusableMatrix rows;
  if (!snapped.empty()) encoder.encode(image, snapped, EncoderKind::kAuto, &rows);
  return rows;
}

// Scene frames held by the workers of a parallel loop at a time (their encoded boxes as floats:
// some MB per frame).
constexpr size_t kFrameWindow = 16;

// A crop and its object mask (8-bit, object > 0) cut to the mask's bounding box; a mask without
// object pixels, or of another size, leaves the crop whole and *mask empty.
void cutToMask(cv::Mat* crop, cv::Mat* mask, const cv::Mat& object) {
  mask->release();
  if (object.size() != crop->size()) return;
  const cv::Rect box = cv::boundingRect(object > 0);
  if (box.area() == 0) return;
  *crop = (*crop)(box).clone();
  *mask = object(box) > 0;
}

// A photographed crop as a camera on a robot would see it, pasted into `scene`: scaled so that its
// longer side is 32-160 px (log-uniform; at most 1.25 times its own size), mirrored half the time,
// its brightness (x 0.78-1.28) and white balance (each channel x 0.9-1.1) changed, sometimes
// blurred (sigma up to 1 px), and pasted at a random place, through its mask when it has one (else
// the whole crop). Returns the pasted rectangle (empty when it does not fit).
cv::Rect pasteVaried(const cv::Mat& crop, const cv::Mat& mask, cv::Mat* scene, std::mt19937& rng) {
  const int side = std::max(crop.cols, crop.rows);
  const double hi = std::max(32.0, std::min(160.0, 1.25 * side));
  const double target = std::exp(std::log(32.0) + uniform01(rng) * (std::log(hi) - std::log(32.0)));
  const double s = target / side;
  const cv::Size size(std::max(8, static_cast<int>(std::lround(crop.cols * s))),
                      std::max(8, static_cast<int>(std::lround(crop.rows * s))));
  if (size.width > scene->cols || size.height > scene->rows) return {};
  cv::Mat obj, m;
  cv::resize(crop, obj, size, 0, 0, s < 1 ? cv::INTER_AREA : cv::INTER_LINEAR);
  if (!mask.empty()) cv::resize(mask, m, size, 0, 0, cv::INTER_NEAREST);
  if (rng() % 2) {
    cv::flip(obj, obj, 1);
    if (!m.empty()) cv::flip(m, m, 1);
  }
  const double brightness = std::exp((uniform01(rng) * 2 - 1) * 0.25);
  cv::Scalar gain;
  for (int c = 0; c < 3; ++c) gain[c] = brightness * std::exp((uniform01(rng) * 2 - 1) * 0.1);
  cv::Mat f;
  obj.convertTo(f, CV_32FC3);
  cv::multiply(f, gain, f);
  // Saturation x 0.75-1.33 about each pixel's grey.
  const double saturation = std::exp((uniform01(rng) * 2 - 1) * std::log(4.0 / 3.0));
  cv::Mat grey, grey3;
  cv::cvtColor(f, grey, cv::COLOR_BGR2GRAY);
  cv::cvtColor(grey, grey3, cv::COLOR_GRAY2BGR);
  f = grey3 + (f - grey3) * saturation;
  f.convertTo(obj, CV_8UC3);
  const double sigma = uniform01(rng) * 1.0;
  if (sigma > 0.3) cv::GaussianBlur(obj, obj, cv::Size(0, 0), sigma);
  const cv::Rect r(static_cast<int>(rng() % static_cast<uint32_t>(scene->cols - size.width + 1)),
                   static_cast<int>(rng() % static_cast<uint32_t>(scene->rows - size.height + 1)),
                   size.width, size.height);
  if (m.empty())
    obj.copyTo((*scene)(r));
  else
    obj.copyTo((*scene)(r), m);
  return r;
}

using Clock = std::chrono::steady_clock;

// Peak resident memory of this process (MB; 0 where /proc does not tell).
double peakRssMb() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmHWM:", 0) == 0) return std::strtod(line.c_str() + 6, nullptr) / 1024.0;
  return 0;
}

// Every line of `text` indented by `n` spaces.
std::string indentLines(const std::string& text, int n) {
  std::string out, line;
  std::istringstream in(text);
  while (std::getline(in, line)) out += std::string(static_cast<size_t>(n), ' ') + line + "\n";
  return out;
}

// What a model was trained on and how (RecognizerModel::provenance; slamaware-train --report).
nlohmann::json provenance(const std::vector<std::string>& object_dirs,
                          const std::vector<std::string>& background_dirs,
                          const std::vector<LabeledCrop>& crops,
                          const std::vector<std::string>& scene_dirs,
                          const std::string& proposals_dir, const TrainOptions& options,
                          const TrainReport& report, double seconds) {
  nlohmann::json j;
  j["format"] = "slamaware training provenance 2";
  j["classes"] = report.classes;
  auto objectSets = [&](const std::vector<std::string>& dirs, bool background) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& dir : dirs) {
      const ObjectSet set = ObjectSet::open(dir);
      std::set<std::string> categories, instances;
      int64_t used = 0;
      const std::string named = folderName(dir) + "/";
      for (const auto& c : crops) {
        // A crop belongs to this set by its path (instances may carry the set's name).
        if (c.path.rfind(set.dir(), 0) != 0) continue;
        ++used;
        categories.insert(c.category);
        instances.insert(c.instance.rfind(named, 0) == 0 ? c.instance.substr(named.size())
                                                         : c.instance);
      }
      list.push_back({{"path", dir},
                      {"kind", set.rendered() ? "rendered" : "photographed"},
                      {"role", background ? "background" : "objects"},
                      {"views", set.views().size()},
                      {"crops_used", used},
                      {"instances_used", instances.size()},
                      {"categories_used", categories}});
    }
    return list;
  };
  j["object_sets"] = objectSets(object_dirs, false);
  for (auto& e : objectSets(background_dirs, true)) j["object_sets"].push_back(e);
  nlohmann::json scenes = nlohmann::json::array();
  for (const auto& dir : scene_dirs) {
    const SequenceFolder seq = SequenceFolder::open(dir);
    scenes.push_back({{"path", dir},
                      {"kind", isSyntheticSequence(seq) ? "rendered" : "photographed"},
                      {"frames", seq.size()},
                      {"boxes", seq.boxes().size()}});
  }
  j["scenes"] = scenes;
  if (!proposals_dir.empty()) j["proposals"] = proposals_dir;
  TrainOptions copy = options;
  j["config"] = "train:\n" + indentLines(describeOptions(optionListOf(copy)), 2);
  j["report"] = nlohmann::json::parse(report.toJson());
  j["training_s"] = seconds;
  j["peak_rss_mb"] = peakRssMb();
  return j;
}

ValidationSummary summarize(const LinearClassifier& clf, const ExampleSet& val, bool has_background,
                            const std::vector<std::string>& held_out) {
  ValidationSummary v;
  if (val.size() == 0) return v;
  v.available = true;
  v.held_out_instances = held_out;
  const int C = clf.numClasses();
  const int objects = has_background ? C - 1 : C;
  v.confusion.assign(static_cast<size_t>(C), std::vector<int64_t>(static_cast<size_t>(C), 0));
  MatrixRM x(1, val.dims()), s, lp;
  int64_t obj_right = 0, right = 0, bg_right = 0, real_right = 0, real_bg_right = 0;
  double nll = 0;
  for (int64_t i = 0; i < val.size(); ++i) {
    val.get(i, x.data());
    clf.scores(x, &s);
    clf.logProbabilities(s, &lp);
    const int label = val.label(i);
    int best = 0, best_obj = 0;
    for (int c = 1; c < C; ++c)
      if (lp(0, c) > lp(0, best)) best = c;
    for (int c = 1; c < objects; ++c)
      if (lp(0, c) > lp(0, best_obj)) best_obj = c;
    ++v.confusion[static_cast<size_t>(label)][static_cast<size_t>(best)];
    nll -= lp(0, label);
    const bool real = val.domain(i) != 0;
    if (has_background && label == C - 1) {
      ++v.negatives;
      bg_right += best == label;
      v.real_negatives += real;
      real_bg_right += real && best == label;
    } else {
      ++v.crops;
      obj_right += best_obj == label;
      right += best == label;
      v.real_crops += real;
      real_right += real && best == label;
    }
  }
  v.object_accuracy = v.crops ? 100.0 * obj_right / v.crops : 0;
  v.accuracy = v.crops ? 100.0 * right / v.crops : 0;
  v.background_accuracy = v.negatives ? 100.0 * bg_right / v.negatives : 0;
  v.real_accuracy = v.real_crops ? 100.0 * real_right / v.real_crops : 0;
  v.real_background_accuracy = v.real_negatives ? 100.0 * real_bg_right / v.real_negatives : 0;
  v.nll = nll / static_cast<double>(val.size());
  return v;
}

}  // namespace

ExampleSet pickExemplars(const ExampleSet& set, int classes, int background, int per_class) {
  std::vector<std::vector<int64_t>> of(static_cast<size_t>(std::max(classes, 0)));
  for (int64_t i = 0; i < set.size(); ++i)
    if (set.label(i) >= 0 && set.label(i) < classes)
      of[static_cast<size_t>(set.label(i))].push_back(i);
  std::vector<char> keep(static_cast<size_t>(set.size()), 0);
  for (int l = 0; l < classes; ++l) {
    const auto& idx = of[static_cast<size_t>(l)];
    const size_t want = std::min(
        idx.size(), static_cast<size_t>(std::max(0, per_class * (l == background ? 4 : 1))));
    for (size_t k = 0; k < want; ++k)
      keep[static_cast<size_t>(idx[(2 * k + 1) * idx.size() / (2 * want)])] = 1;
  }
  ExampleSet picked = set.select([&](int64_t i) { return keep[static_cast<size_t>(i)] != 0; });
  for (int64_t i = 0; i < picked.size(); ++i) picked.setWeight(i, 1.f);
  return picked;
}

void balanceDomains(ExampleSet* set, int classes, double real_share) {
  if (real_share <= 0 || real_share >= 1) return;
  std::vector<double> count[2];
  count[0].assign(static_cast<size_t>(classes), 0);
  count[1].assign(static_cast<size_t>(classes), 0);
  for (int64_t i = 0; i < set->size(); ++i)
    count[set->domain(i) ? 1 : 0][static_cast<size_t>(set->label(i))] += 1;
  for (int64_t i = 0; i < set->size(); ++i) {
    const size_t c = static_cast<size_t>(set->label(i));
    const double rendered = count[0][c], real = count[1][c];
    if (rendered == 0 || real == 0) {
      set->setWeight(i, 1.f);
      continue;
    }
    const double share = set->domain(i) ? real_share : 1 - real_share;
    set->setWeight(
        i, static_cast<float>(share * (rendered + real) / (set->domain(i) ? real : rendered)));
  }
}

// A crop's pixels as the training sees them: cut to its object's box when it has one.
cv::Mat readCrop(const LabeledCrop& crop) {
  cv::Mat image = readImage(crop.path);
  if (crop.object_box.area() > 0 &&
      (crop.object_box & cv::Rect(0, 0, image.cols, image.rows)) == crop.object_box)
    image = image(crop.object_box).clone();
  return image;
}

// Crops of a photographed set without masks are taken as framed by their object (UW RGB-D's are
// cut around the object's depth segment), unless the set's crops are loose: when the objects, as
// GrabCut finds them in up to 16 crops spread over the set, cover less than half of their crop
// (median), a box covering the crop would not count as a detection of its object (IoU < 0.5).
// Every crop of such a set without a mask then gets its object's box (objectBoxInCrop). Which
// kind a set is is measured, not declared: UMD's crops (another lab's turntable, objects on a
// blue cloth) are loose, UW RGB-D's are not.
// The set's crops are those of `crops` from `first` on.
void boxLooseCrops(const std::string& dir, std::vector<LabeledCrop>* crops, size_t first) {
  std::vector<size_t> unmasked;
  for (size_t i = first; i < crops->size(); ++i)
    if ((*crops)[i].mask_path.empty()) unmasked.push_back(i);
  if (unmasked.empty()) return;
  // Each crop is read and cut at most once: the sample's cuts are the boxes of its crops too.
  struct Cut {
    cv::Rect box;
    cv::Size size;
  };
  std::map<size_t, Cut> cuts;
  auto cut = [&](size_t i) -> const Cut& {
    auto it = cuts.find(i);
    if (it == cuts.end()) {
      const cv::Mat image = readImage((*crops)[i].path);
      it = cuts.emplace(i, Cut{objectBoxInCrop(image), image.size()}).first;
    }
    return it->second;
  };
  constexpr size_t kSample = 16;
  const size_t n = std::min(kSample, unmasked.size());
  std::vector<double> share;
  for (size_t k = 0; k < n; ++k) {
    const Cut& c = cut(unmasked[k * unmasked.size() / n]);
    share.push_back(static_cast<double>(c.box.area()) / std::max(1, c.size.area()));
  }
  std::nth_element(share.begin(), share.begin() + static_cast<std::ptrdiff_t>(n / 2), share.end());
  const double median = share[n / 2];
  if (median >= 0.5) return;
  spdlog::info(
      "{}: its objects cover {:.0f} % of their crops (median of {}): each of its {} crops without "
      "a mask is boxed around its object",
      dir, 100 * median, n, unmasked.size());
  for (size_t i : unmasked) {
    const Cut& c = cut(i);
    if (c.box != cv::Rect(cv::Point(), c.size)) (*crops)[i].object_box = c.box;
  }
}

std::vector<LabeledCrop> collectCrops(const std::vector<std::string>& object_dirs,
                                      int max_views_per_instance) {
  std::vector<LabeledCrop> crops;
  for (const auto& dir : object_dirs) {
    const ObjectSet set = ObjectSet::open(dir);
    const size_t first = crops.size();
    std::map<std::string, std::vector<const ObjectView*>> by_instance;
    for (const auto& v : set.views()) by_instance[v.instance].push_back(&v);
    for (const auto& [instance, views] : by_instance) {
      const size_t n = views.size();
      const size_t keep =
          max_views_per_instance > 0 ? std::min(n, static_cast<size_t>(max_views_per_instance)) : n;
      for (size_t k = 0; k < keep; ++k) {
        const ObjectView* v = views[k * n / keep];
        crops.push_back(
            LabeledCrop{v->crop_path, v->category, v->instance, v->mask_path, !set.rendered(), {}});
      }
    }
    if (!set.rendered()) boxLooseCrops(dir, &crops, first);
  }
  return crops;
}

std::vector<LabeledCrop> collectNamedCrops(const std::string& object_dir,
                                           int max_views_per_instance) {
  const std::string set_name = folderName(object_dir);
  std::vector<LabeledCrop> crops = collectCrops({object_dir}, max_views_per_instance);
  for (auto& c : crops) c.instance = set_name + "/" + c.instance;
  return crops;
}

std::map<int, std::vector<cv::Rect2d>> readProposalBoxes(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw DatasetError(path + ": cannot read the proposal boxes");
  std::map<int, std::vector<cv::Rect2d>> boxes;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (number == 1 || line.empty()) continue;  // header
    std::istringstream ss(line);
    std::string field;
    std::vector<double> v;
    while (std::getline(ss, field, ',')) {
      char* end = nullptr;
      const double x = std::strtod(field.c_str(), &end);
      if (end == field.c_str() || *end != '\0' || !std::isfinite(x)) break;
      v.push_back(x);
    }
    if (v.size() != 6 || v[0] < 0 || v[4] <= 0 || v[5] <= 0)
      throw DatasetError(path + ":" + std::to_string(number) +
                         ": expected frame,rank,x,y,w,h, got '" + line + "'");
    boxes[static_cast<int>(v[0])].emplace_back(v[2], v[3], v[4], v[5]);
  }
  return boxes;
}

std::vector<int> labelProposals(const SceneFrame& frame, const std::vector<std::string>& classes,
                                int background, const TrainOptions& options,
                                std::vector<double>* aspect_offsets) {
  std::vector<int> labels;
  std::vector<cv::Rect2d> kept;  // suppression in the file's (rank) order
  for (const auto& r : frame.proposals) {
    if (std::any_of(kept.begin(), kept.end(),
                    [&](const cv::Rect2d& k) { return iou(r, k) > options.proposal_nms_iou; })) {
      labels.push_back(-1);
      continue;
    }
    kept.push_back(r);
    double best = 0;
    int label = background;
    size_t object = 0;
    for (size_t o = 0; o < frame.objects.size(); ++o) {
      const double overlap = iou(r, frame.objects[o]);
      if (overlap <= best) continue;
      best = overlap;
      object = o;
      const int c = indexOf(classes, frame.object_classes[o]);
      label = c >= 0 ? c : background;
    }
    if (best >= options.proposal_positive_iou) {
      labels.push_back(label);
      if (aspect_offsets)
        aspect_offsets->push_back(
            std::log(r.width / r.height) -
            std::log(frame.objects[object].width / frame.objects[object].height));
    } else
      labels.push_back(best < options.proposal_background_iou ? background : -1);
  }
  return labels;
}

std::vector<SceneFrame> collectSceneFrames(const std::vector<std::string>& sequence_dirs,
                                           const std::string& proposals_dir) {
  std::vector<SceneFrame> frames;
  for (const auto& dir : sequence_dirs) {
    const SequenceFolder seq = SequenceFolder::open(dir);
    if (!seq.hasBoxes())
      throw DatasetError(dir +
                         ": no boxes.csv; background boxes need to know where the objects are");
    std::map<int, SceneFrame> by_frame;
    for (const auto& b : seq.boxes()) {
      by_frame[b.frame].objects.push_back(cv::Rect2d(b.x, b.y, b.w, b.h));
      by_frame[b.frame].object_classes.push_back(b.cls);
    }
    if (!proposals_dir.empty()) {
      const std::string path =
          (std::filesystem::path(proposals_dir) / (folderName(dir) + ".csv")).string();
      if (std::filesystem::exists(path)) {
        for (auto& [frame, boxes] : readProposalBoxes(path))
          by_frame[frame].proposals = std::move(boxes);
      } else {
        spdlog::warn("{}: no proposal boxes ({}): trained on its ground-truth boxes only", dir,
                     path);
      }
    }
    for (size_t i = 0; i < seq.size(); ++i) {
      SceneFrame f = std::move(by_frame[static_cast<int>(i)]);
      f.path = seq.framePath(i);
      f.sequence = seq.info().name.empty() ? dir : seq.info().name;
      f.index = static_cast<int>(i);
      f.real = !isSyntheticSequence(seq);
      frames.push_back(std::move(f));
    }
  }
  return frames;
}

std::vector<cv::Rect2d> jitteredBoxes(const cv::Rect2d& object, int width, int height, int count,
                                      double min_iou, uint32_t seed) {
  std::vector<cv::Rect2d> boxes;
  std::mt19937 rng(seed);
  const cv::Rect2d image(0, 0, width, height);
  for (int attempt = 0; attempt < count * 50 && static_cast<int>(boxes.size()) < count; ++attempt) {
    // Sides scaled by 0.75-1.33, centre moved by up to a quarter of the side.
    const double sw = std::exp((uniform01(rng) * 2 - 1) * std::log(4.0 / 3.0));
    const double sh = std::exp((uniform01(rng) * 2 - 1) * std::log(4.0 / 3.0));
    const double w = object.width * sw, h = object.height * sh;
    const double cx = object.x + object.width / 2 + (uniform01(rng) - 0.5) * 0.5 * object.width;
    const double cy = object.y + object.height / 2 + (uniform01(rng) - 0.5) * 0.5 * object.height;
    const cv::Rect2d r = cv::Rect2d(cx - w / 2, cy - h / 2, w, h) & image;
    if (r.width >= 8 && r.height >= 8 && iou(r, object) >= min_iou) boxes.push_back(r);
  }
  return boxes;
}

std::vector<cv::Rect2d> partialBoxes(const std::vector<cv::Rect2d>& objects, size_t index,
                                     int width, int height, int count, double min_iou,
                                     double max_iou, uint32_t seed) {
  std::vector<cv::Rect2d> boxes;
  if (index >= objects.size()) return boxes;
  std::mt19937 rng(seed);
  const cv::Rect2d& object = objects[index];
  const cv::Rect2d image(0, 0, width, height);
  for (int attempt = 0; attempt < count * 100 && static_cast<int>(boxes.size()) < count;
       ++attempt) {
    // Every other attempt a part (sides 0.3-0.8 of the object's, inside it), else the object's box
    // scaled by 0.35-2.5 and moved by up to 0.6 of its side (overhangs, neighbourhoods).
    const bool part = attempt % 2 == 0;
    auto scale = [&](double lo, double hi) {
      return std::exp(std::log(lo) + uniform01(rng) * (std::log(hi) - std::log(lo)));
    };
    const double w = object.width * (part ? scale(0.3, 0.8) : scale(0.35, 2.5));
    const double h = object.height * (part ? scale(0.3, 0.8) : scale(0.35, 2.5));
    const double cx =
        part ? object.x + w / 2 + uniform01(rng) * (object.width - w)
             : object.x + object.width / 2 + (uniform01(rng) - 0.5) * 1.2 * object.width;
    const double cy =
        part ? object.y + h / 2 + uniform01(rng) * (object.height - h)
             : object.y + object.height / 2 + (uniform01(rng) - 0.5) * 1.2 * object.height;
    const cv::Rect2d r = cv::Rect2d(cx - w / 2, cy - h / 2, w, h) & image;
    if (r.width < 16 || r.height < 16) continue;
    const double own = iou(r, object);
    bool ok = own >= min_iou && own < max_iou;
    for (size_t o = 0; ok && o < objects.size(); ++o) ok = iou(r, objects[o]) < max_iou;
    if (ok) boxes.push_back(r);
  }
  return boxes;
}

std::vector<cv::Rect2d> randomBackgroundBoxes(int width, int height,
                                              const std::vector<cv::Rect2d>& objects, int count,
                                              const TrainOptions& options, uint32_t seed) {
  std::vector<cv::Rect2d> boxes;
  std::mt19937 rng(seed);
  const double min_side = options.negative_min_size_px;
  const double max_w = std::max(min_side, options.negative_max_size * width);
  const double max_h = std::max(min_side, options.negative_max_size * height);
  if (width < min_side || height < min_side) return boxes;
  for (int attempt = 0; attempt < count * 50 && static_cast<int>(boxes.size()) < count; ++attempt) {
    const double w =
        std::min(min_side + uniform01(rng) * (max_w - min_side), static_cast<double>(width));
    const double aspect =
        std::exp(std::log(0.5) + uniform01(rng) * (std::log(2.0) - std::log(0.5)));
    const double h = std::clamp(w * aspect, min_side, std::min(max_h, static_cast<double>(height)));
    const cv::Rect2d r(uniform01(rng) * (width - w), uniform01(rng) * (height - h), w, h);
    bool ok = true;
    for (const auto& o : objects)
      if (iou(r, o) >= options.negative_max_iou) ok = false;
    if (ok) boxes.push_back(r);
  }
  return boxes;
}

void fitEncoding(const std::vector<LabeledCrop>& crops, const std::vector<SceneFrame>& frames,
                 const TrainOptions& options, Pca* pca, Vocabulary* vocabulary,
                 const std::function<void(int64_t, int64_t)>& progress) {
  const EncodingParams& p = options.encoding;
  p.validate();
  const int64_t target = std::max<int64_t>(options.vocabulary_descriptors, p.vocabulary_size * 4);
  // Half of the sample from photographs when there are any, half from renderings (codewords fitted
  // to rendered images alone describe photographs poorly); within each, half from scene frames
  // when there are any (the background needs codewords too).
  int64_t count[2][2] = {{0, 0}, {0, 0}};  // [photographed][frame]
  for (const auto& c : crops) ++count[c.real ? 1 : 0][0];
  for (const auto& f : frames) ++count[f.real ? 1 : 0][1];
  const int domains = (count[0][0] + count[0][1] > 0) + (count[1][0] + count[1][1] > 0);
  int64_t quota[2][2] = {{0, 0}, {0, 0}};  // per image
  for (int d = 0; d < 2; ++d) {
    const int kinds = (count[d][0] > 0) + (count[d][1] > 0);
    for (int k = 0; k < 2; ++k)
      if (count[d][k] > 0) quota[d][k] = (target / domains / kinds + count[d][k] - 1) / count[d][k];
  }
  const int64_t per_crop_rendered = quota[0][0], per_crop_real = quota[1][0];
  const int64_t per_frame_rendered = quota[0][1], per_frame_real = quota[1][1];
  // Each image's share of the sample, drawn by the workers and gathered in image order (crops,
  // then frames).
  struct Worker {
    explicit Worker(const FeatureParams& params) : extractor(params) {}
    DenseFeatureExtractor extractor;
    FeatureGrid grid;
  };
  std::vector<std::unique_ptr<Worker>> workers;
  for (int w = 0; w < workerThreads(options.threads); ++w)
    workers.push_back(std::make_unique<Worker>(p.features));
  auto sample = [&](size_t i, std::unique_ptr<Worker>& worker) {
    const bool crop = i < crops.size();
    const size_t k = crop ? i : i - crops.size();
    const bool real = crop ? crops[k].real : frames[k].real;
    const int64_t quota = crop ? (real ? per_crop_real : per_crop_rendered)
                               : (real ? per_frame_real : per_frame_rendered);
    worker->extractor.setImage(crop ? readCrop(crops[k]) : readImage(frames[k].path));
    worker->extractor.extract(worker->extractor.imageCells(), &worker->grid);
    const ReusableMatrix& features = worker->grid.features;
    const int64_t n = features.rows();
    std::vector<int64_t> idx(static_cast<size_t>(n));
    for (int64_t j = 0; j < n; ++j) idx[static_cast<size_t>(j)] = j;
    std::mt19937 rng(
        subSeed(static_cast<uint32_t>(options.seed), crop ? 2 : 3, static_cast<uint32_t>(k)));
    const int64_t take = std::min(quota, n);
    std::vector<float> out;
    out.reserve(static_cast<size_t>(std::max<int64_t>(0, take) * kFeatureDims));
    for (int64_t j = 0; j < take; ++j) {
      std::swap(
          idx[static_cast<size_t>(j)],
          idx[static_cast<size_t>(j + static_cast<int64_t>(rng() % static_cast<uint32_t>(n - j)))]);
      const float* r = features.row(idx[static_cast<size_t>(j)]);
      out.insert(out.end(), r, r + kFeatureDims);
    }
    return out;
  };
  std::vector<float> rows;
  const size_t total = crops.size() + frames.size();
  orderedParallelFor<std::vector<float>>(
      total, workers, 64, sample, [&](size_t i, const std::vector<float>& sampled) {
        rows.insert(rows.end(), sampled.begin(), sampled.end());
        if (progress) progress(static_cast<int64_t>(i + 1), static_cast<int64_t>(total));
      });
  int64_t n = static_cast<int64_t>(rows.size()) / kFeatureDims;
  if (n < p.vocabulary_size)
    throw std::runtime_error("fitEncoding: only " + std::to_string(n) + " features for " +
                             std::to_string(p.vocabulary_size) + " codewords");
  // The shuffled subset.
  MatrixRM samples(std::min(n, target), kFeatureDims);
  {
    std::vector<int64_t> idx(static_cast<size_t>(n));
    for (int64_t i = 0; i < n; ++i) idx[static_cast<size_t>(i)] = i;
    std::mt19937 rng(subSeed(static_cast<uint32_t>(options.seed), 4, 0));
    for (int64_t i = n - 1; i > 0; --i)
      std::swap(idx[static_cast<size_t>(i)],
                idx[static_cast<size_t>(rng() % static_cast<uint32_t>(i + 1))]);
    for (int64_t i = 0; i < samples.rows(); ++i)
      std::copy_n(rows.data() + idx[static_cast<size_t>(i)] * kFeatureDims, kFeatureDims,
                  samples.row(i).data());
  }
  *pca = Pca::fit(samples, p.pca_dims);
  MatrixRM projected(samples.rows(), p.pca_dims);
  pca->project(samples, projected);
  *vocabulary = Vocabulary::train(projected, p.vocabulary_size,
                                  subSeed(static_cast<uint32_t>(options.seed), 5, 0),
                                  options.kmeans_iterations);
}

ExampleSet encodeCrops(const std::vector<LabeledCrop>& crops,
                       const std::vector<std::string>& classes,
                       const std::vector<std::string>& instances, FrameEncoder& encoder,
                       bool mirror, const std::function<void(int64_t, int64_t)>& progress,
                       int other_label) {
  ExampleSet set(encoder.params().encodedDims(), encoder.params().pca_dims);
  ReusableMatrix buffer;
  for (size_t i = 0; i < crops.size(); ++i) {
    cv::Mat image = readCrop(crops[i]);
    const int label = labelOf(classes, crops[i].category, other_label);
    const int group = indexOf(instances, crops[i].instance);
    const int domain = crops[i].real ? 1 : 0;
    encoder.encode(image, {wholeImage(encoder, image)}, EncoderKind::kDirect, &buffer);
    set.add(buffer.row(0), label, group, domain);
    if (mirror) {
      cv::flip(image, image, 1);
      encoder.encode(image, {wholeImage(encoder, image)}, EncoderKind::kDirect, &buffer);
      set.add(buffer.row(0), label, group, domain);
    }
    if (progress) progress(static_cast<int64_t>(i + 1), static_cast<int64_t>(crops.size()));
  }
  return set;
}

std::string TrainReport::toJson() const {
  nlohmann::json j;
  j["classes"] = classes;
  j["train_crops"] = train_crops;
  j["train_negatives"] = train_negatives;
  j["mined_per_round"] = mined;
  if (validation.available) {
    nlohmann::json v;
    v["held_out_instances"] = validation.held_out_instances;
    v["crops"] = validation.crops;
    v["object_accuracy"] = validation.object_accuracy;
    v["accuracy"] = validation.accuracy;
    v["negatives"] = validation.negatives;
    v["background_accuracy"] = validation.background_accuracy;
    v["real_crops"] = validation.real_crops;
    v["real_accuracy"] = validation.real_accuracy;
    v["real_negatives"] = validation.real_negatives;
    v["real_background_accuracy"] = validation.real_background_accuracy;
    v["nll"] = validation.nll;
    v["confusion"] = validation.confusion;
    j["validation"] = v;
  }
  return j.dump();
}

std::string TrainReport::toText() const {
  std::ostringstream o;
  o << "classes: ";
  for (size_t i = 0; i < classes.size(); ++i) o << (i ? ", " : "") << classes[i];
  o << "\ntraining examples: " << train_crops << " crops (with their copies in scene context), "
    << train_negatives << " background boxes";
  for (size_t r = 0; r < mined.size(); ++r)
    o << (r ? ", " : " (hard negatives mined: ") << mined[r];
  if (!mined.empty()) o << ")";
  o << "\n";
  if (!validation.available) {
    o << "validation: none (nothing held out)\n";
    return o.str();
  }
  const auto& v = validation;
  o << "validation on held-out data";
  if (!v.held_out_instances.empty()) {
    o << " (instances ";
    for (size_t i = 0; i < v.held_out_instances.size(); ++i)
      o << (i ? ", " : "") << v.held_out_instances[i];
    o << ")";
  }
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                ":\n  %lld crops: best object class right %.1f%%, best class overall right %.1f%%\n"
                "  %lld background boxes: classified background %.1f%%\n  calibrated NLL %.3f\n",
                static_cast<long long>(v.crops), v.object_accuracy, v.accuracy,
                static_cast<long long>(v.negatives), v.background_accuracy, v.nll);
  o << buf;
  if (v.real_crops + v.real_negatives > 0) {
    std::snprintf(
        buf, sizeof(buf),
        "  of them photographed: %lld crops, best class overall right %.1f%%; %lld background "
        "boxes, classified background %.1f%%\n",
        static_cast<long long>(v.real_crops), v.real_accuracy,
        static_cast<long long>(v.real_negatives), v.real_background_accuracy);
    o << buf;
  }
  o << "  confusion (rows: true, columns: predicted):\n";
  for (size_t r = 0; r < v.confusion.size(); ++r) {
    std::snprintf(buf, sizeof(buf), "    %-14s", classes[r].c_str());
    o << buf;
    for (int64_t n : v.confusion[r]) {
      std::snprintf(buf, sizeof(buf), " %6lld", static_cast<long long>(n));
      o << buf;
    }
    o << "\n";
  }
  return o.str();
}

namespace {

// What a model is trained on: the crops and scene frames, the model's categories (background last
// when there is any) and the held-out split (trainer.h, step 1).
struct TrainingData {
  std::vector<LabeledCrop> crops;
  std::vector<SceneFrame> frames;
  std::vector<std::string> classes, instances;
  bool has_background = false;
  int bg = -1;  ///< index of "background" in classes, -1 without
  Split split;
};

TrainingData gatherTrainingData(const std::vector<std::string>& object_dirs,
                                const std::vector<std::string>& scene_dirs,
                                const TrainOptions& options, const std::string& proposals_dir,
                                const std::vector<std::string>& background_object_dirs) {
  std::vector<LabeledCrop> crops;
  for (const auto& dir : object_dirs) {
    // A rendered set's instances are named after the set: its "coffee_mug_1" is not the UW RGB-D
    // dataset's coffee_mug_1, which photographed sets share.
    const bool rendered = ObjectSet::open(dir).rendered();
    // Photographed views are scarce: every one of them is used.
    for (auto& c :
         rendered ? collectNamedCrops(dir, options.max_views_per_instance) : collectCrops({dir}, 0))
      crops.push_back(std::move(c));
  }
  std::vector<SceneFrame> frames = collectSceneFrames(scene_dirs, proposals_dir);
  if (crops.empty()) throw DatasetError("no training crops");
  std::set<std::string> category_set, instance_set;
  for (const auto& c : crops) category_set.insert(c.category);
  // Objects of other categories: background, as the scenes' other objects are: those of the object
  // sets outside train.classes, and those of the background sets (their instances named after
  // their set: two sets may both hold a "kleenex_1").
  int64_t background_crops = 0;
  std::set<std::string> background_categories;
  if (!options.classes.empty()) {
    for (const auto& c : options.classes)
      if (!category_set.count(c))
        throw DatasetError("train.classes: no crops of '" + c + "' in the object sets");
    category_set = std::set<std::string>(options.classes.begin(), options.classes.end());
    for (const auto& c : crops)
      if (!category_set.count(c.category)) {
        background_categories.insert(c.category);
        ++background_crops;
      }
  }
  for (const auto& dir : background_object_dirs) {
    for (auto& c : collectNamedCrops(dir, options.background_views_per_instance)) {
      if (category_set.count(c.category)) continue;
      background_categories.insert(c.category);
      crops.push_back(std::move(c));
      ++background_crops;
    }
  }
  for (const auto& c : crops) instance_set.insert(c.instance);
  if (category_set.size() < 2 && frames.empty() && background_crops == 0)
    throw DatasetError(
        "need at least two categories, or background from --negatives or --background-objects");
  std::vector<std::string> classes(category_set.begin(), category_set.end());
  const bool has_background = !frames.empty() || background_crops > 0;
  if (has_background) classes.push_back("background");
  const int bg = has_background ? static_cast<int>(classes.size()) - 1 : -1;
  std::vector<std::string> instances(instance_set.begin(), instance_set.end());
  Split split = makeSplit(crops, frames, options);
  spdlog::info(
      "{} crops of {} instances in {} categories ({} of them of {} other categories: background; "
      "{} "
      "photographed), {} scene frames ({} photographed); held out: {} instances, {} frames{}",
      crops.size(), instances.size(), category_set.size(), background_crops,
      background_categories.size(),
      std::count_if(crops.begin(), crops.end(), [](const LabeledCrop& c) { return c.real; }),
      frames.size(),
      std::count_if(frames.begin(), frames.end(), [](const SceneFrame& f) { return f.real; }),
      split.held_out_instances.size(),
      std::count(split.frame_val.begin(), split.frame_val.end(), true),
      split.held_out_sequences.empty()
          ? ""
          : fmt::format(" (scenes {})", fmt::join(split.held_out_sequences, ", ")));
  return {std::move(crops),     std::move(frames), std::move(classes),
          std::move(instances), has_background,    bg,
          std::move(split)};
}

// Encoded examples, and which of them are held out (is_val: one per example of `all`).
struct Examples {
  Examples(int64_t dims, int64_t block_dims)
      : all(dims, block_dims), held_out_mirrors(dims, block_dims) {}
  ExampleSet all;
  std::vector<bool> is_val;
  ExampleSet held_out_mirrors;  ///< mirror images of the held-out crops: trained on at the end only
};

/// One encoder per worker of the frame loops (the examples do not depend on their number).
using Workers = std::vector<std::unique_ptr<FrameEncoder>>;

// Every crop as one box covering it (and mirrored).
void encodeCropExamples(const TrainingData& d, const TrainOptions& options, FrameEncoder& encoder,
                        Examples* ex) {
  const std::vector<LabeledCrop>& crops = d.crops;
  const Split& split = d.split;
  ExampleSet& all = ex->all;
  std::vector<bool>& is_val = ex->is_val;
  ExampleSet& held_out_mirrors = ex->held_out_mirrors;
  {
    ProgressBar bar("encode crops", static_cast<int64_t>(crops.size()));
    all = encodeCrops(
        crops, d.classes, d.instances, encoder, options.mirror_crops,
        [&](int64_t done, int64_t) { bar.update(done); }, d.bg);
    bar.finish();
  }
  // Held-out crops stay held out; their mirror images are augmentation, not validation data, and
  // join the training set only for the final retraining on everything.
  const size_t per_crop = options.mirror_crops ? 2 : 1;
  is_val.assign(static_cast<size_t>(all.size()), false);
  for (size_t i = 0; i < crops.size(); ++i)
    for (size_t k = 0; k < per_crop; ++k) is_val[i * per_crop + k] = split.crop_val[i];
  if (per_crop > 1) {
    held_out_mirrors =
        all.select([&](int64_t i) { return i % 2 == 1 && is_val[static_cast<size_t>(i)]; });
    std::vector<bool> keep(static_cast<size_t>(all.size()));
    for (size_t i = 0; i < keep.size(); ++i) keep[i] = !(i % 2 == 1 && is_val[i]);
    all.filter([&](int64_t i) { return keep[static_cast<size_t>(i)]; });
    std::vector<bool> v;
    for (size_t i = 0; i < keep.size(); ++i)
      if (keep[i]) v.push_back(is_val[i]);
    is_val = v;
  }
}

// Each crop pasted into scene frames (step 3).
void encodeCropsInContext(const TrainingData& d, const TrainOptions& options, FrameEncoder& encoder,
                          Examples* ex) {
  const std::vector<LabeledCrop>& crops = d.crops;
  const std::vector<SceneFrame>& frames = d.frames;
  const Split& split = d.split;
  const std::vector<std::string>& classes = d.classes;
  const std::vector<std::string>& instances = d.instances;
  const int bg = d.bg;
  ExampleSet& all = ex->all;
  std::vector<bool>& is_val = ex->is_val;
  ReusableMatrix buffer;
  if (!frames.empty() && (options.context_copies > 0 || options.real_copies > 0)) {
    // Crops in context: pasted into scene frames of the same split (any frame if that split has
    // none), a photographed frame half the time when there are any: rendered objects in
    // photographs and photographed objects in renderings, so that neither look tells a class.
    // Each crop `context_copies` times at its own size, anywhere it fits; each photographed crop
    // `real_copies` times more, varied as a camera would see it (pasteVaried).
    std::vector<size_t> frames_of[2][2];  // [held out][photographed]
    for (size_t f = 0; f < frames.size(); ++f)
      frames_of[split.frame_val[f] ? 1 : 0][frames[f].real ? 1 : 0].push_back(f);
    std::mt19937 rng(subSeed(static_cast<uint32_t>(options.seed), 7, 0));
    ProgressBar bar("encode crops in scene context", static_cast<int64_t>(crops.size()));
    std::map<size_t, cv::Mat> frame_cache;
    auto pickFrame = [&](bool held_out) -> const cv::Mat& {
      int s = held_out ? 1 : 0;
      if (frames_of[s][0].empty() && frames_of[s][1].empty()) s = 1 - s;
      const auto& rendered = frames_of[s][0];
      const auto& real = frames_of[s][1];
      const bool use_real = !real.empty() && (rendered.empty() || rng() % 2 == 0);
      const std::vector<size_t>& pool = use_real ? real : rendered;
      const size_t f = pool[rng() % pool.size()];
      auto it = frame_cache.find(f);
      if (it == frame_cache.end()) {
        if (frame_cache.size() > 64) frame_cache.clear();
        it = frame_cache.emplace(f, readImage(frames[f].path)).first;
      }
      return it->second;
    };
    for (size_t i = 0; i < crops.size(); ++i) {
      // A crop with a mask is pasted as its object alone, boxed tightly (what is around it in the
      // box is the frame's); one without is pasted whole (a loose one cut to its object's box).
      cv::Mat crop = readCrop(crops[i]), mask;
      if (!crops[i].mask_path.empty()) cutToMask(&crop, &mask, readImage(crops[i].mask_path, true));
      const int copies = options.context_copies + (crops[i].real ? options.real_copies : 0);
      for (int k = 0; k < copies; ++k) {
        cv::Mat scene = pickFrame(split.crop_val[i]).clone();
        cv::Rect r;
        if (k < options.context_copies) {
          if (crop.cols > scene.cols || crop.rows > scene.rows) continue;
          r = cv::Rect(static_cast<int>(rng() % static_cast<uint32_t>(scene.cols - crop.cols + 1)),
                       static_cast<int>(rng() % static_cast<uint32_t>(scene.rows - crop.rows + 1)),
                       crop.cols, crop.rows);
          if (mask.empty())
            crop.copyTo(scene(r));
          else
            crop.copyTo(scene(r), mask);
        } else {
          r = pasteVaried(crop, mask, &scene, rng);
          if (r.empty()) continue;
        }
        PyramidBox b;
        if (!encoder.snap(r.x, r.y, r.width, r.height, scene.cols, scene.rows, &b)) continue;
        encoder.encode(scene, {b}, EncoderKind::kDirect, &buffer);
        all.add(buffer.row(0), labelOf(classes, crops[i].category, bg),
                indexOf(instances, crops[i].instance), crops[i].real ? 1 : 0);
        is_val.push_back(split.crop_val[i]);
      }
      bar.update(static_cast<int64_t>(i + 1));
    }
    bar.finish();
  }
}

// `negatives_per_frame` random background boxes per scene frame (step 3).
void encodeBackgroundBoxes(const TrainingData& d, const TrainOptions& options, Workers& workers,
                           Examples* ex) {
  const std::vector<SceneFrame>& frames = d.frames;
  const Split& split = d.split;
  ExampleSet& all = ex->all;
  std::vector<bool>& is_val = ex->is_val;
  const int bg = d.bg;
  if (d.has_background) {
    ProgressBar bar("encode background boxes", static_cast<int64_t>(frames.size()));
    orderedParallelFor<ReusableMatrix>(
        frames.size(), workers, kFrameWindow,
        [&](size_t f, std::unique_ptr<FrameEncoder>& worker) {
          const cv::Mat image = readImage(frames[f].path);
          return encodeRects(
              *worker, image,
              randomBackgroundBoxes(
                  image.cols, image.rows, frames[f].objects, options.negatives_per_frame, options,
                  subSeed(static_cast<uint32_t>(options.seed), 6, static_cast<uint32_t>(f))));
        },
        [&](size_t f, const ReusableMatrix& rows) {
          for (int64_t i = 0; i < rows.rows(); ++i)
            all.add(rows.row(i), bg, -1 - static_cast<int>(f), frames[f].real ? 1 : 0);
          is_val.resize(static_cast<size_t>(all.size()), split.frame_val[f]);
          bar.update(static_cast<int64_t>(f + 1));
        });
    bar.finish();
  }
}

// The scenes' objects and proposal boxes (step 3).
void encodeSceneObjects(const TrainingData& d, const TrainOptions& options, Workers& workers,
                        Examples* ex) {
  const std::vector<SceneFrame>& frames = d.frames;
  const std::vector<std::string>& classes = d.classes;
  const Split& split = d.split;
  const int bg = d.bg;
  ExampleSet& all = ex->all;
  std::vector<bool>& is_val = ex->is_val;
  if (d.has_background && (options.scene_positive_every > 0 || options.proposal_every > 0)) {
    // The scenes' objects, boxed as a proposal would box them: a category of the model is a
    // positive, any other object is background (a calculator is not a cap).
    auto every = [](int index, int n) { return n > 0 && index % n == 0; };
    ProgressBar bar("encode scene objects", static_cast<int64_t>(frames.size()));
    int64_t positives = 0, others = 0, partials = 0, proposal_positives = 0, proposal_others = 0;
    struct Encoded {  // one frame's boxes
      ReusableMatrix rows;
      std::vector<int> labels;
      int64_t partials = 0, proposal_positives = 0, proposal_others = 0;
      std::vector<double> aspect_offsets;  // of the proposal boxes that are views of an object
    };
    double offset_sum = 0, offset_sum2 = 0;
    int64_t offsets = 0;
    orderedParallelFor<Encoded>(
        frames.size(), workers, kFrameWindow,
        [&](size_t f, std::unique_ptr<FrameEncoder>& worker) {
          Encoded e;
          FrameEncoder& encoder = *worker;
          const bool objects =
              every(frames[f].index, options.scene_positive_every) && !frames[f].objects.empty();
          const bool proposals =
              every(frames[f].index, options.proposal_every) && !frames[f].proposals.empty();
          if (!objects && !proposals) return e;
          const cv::Mat image = readImage(frames[f].path);
          std::vector<PyramidBox> snapped;
          for (size_t o = 0; objects && o < frames[f].objects.size(); ++o) {
            const int c = indexOf(classes, frames[f].object_classes[o]);
            const int label = c >= 0 ? c : bg;
            std::vector<cv::Rect2d> boxes{frames[f].objects[o]};
            const auto jittered = jitteredBoxes(
                frames[f].objects[o], image.cols, image.rows, options.positive_jitter,
                options.positive_min_iou,
                subSeed(static_cast<uint32_t>(options.seed), 8, static_cast<uint32_t>(f * 64 + o)));
            boxes.insert(boxes.end(), jittered.begin(), jittered.end());
            const size_t whole = boxes.size();
            const auto partial = partialBoxes(
                frames[f].objects, o, image.cols, image.rows, options.partial_negatives,
                options.partial_min_iou, options.partial_max_iou,
                subSeed(static_cast<uint32_t>(options.seed), 9, static_cast<uint32_t>(f * 64 + o)));
            boxes.insert(boxes.end(), partial.begin(), partial.end());
            for (size_t n = 0; n < boxes.size(); ++n) {
              const auto& r = boxes[n];
              PyramidBox b;
              if (!encoder.snap(r.x, r.y, r.width, r.height, image.cols, image.rows, &b)) continue;
              snapped.push_back(b);
              e.labels.push_back(n < whole ? label : bg);
              e.partials += n >= whole;
            }
          }
          // The boxes the proposals stage drew here: views of objects as the pipeline frames them,
          // and its boxes on parts, on several objects, on the table (background).
          const std::vector<int> proposal_labels =
              proposals ? labelProposals(frames[f], classes, bg, options, &e.aspect_offsets)
                        : std::vector<int>();
          for (size_t n = 0; n < proposal_labels.size(); ++n) {
            const auto& r = frames[f].proposals[n];
            PyramidBox b;
            if (proposal_labels[n] < 0 ||
                !encoder.snap(r.x, r.y, r.width, r.height, image.cols, image.rows, &b))
              continue;
            snapped.push_back(b);
            e.labels.push_back(proposal_labels[n]);
            (proposal_labels[n] == bg ? e.proposal_others : e.proposal_positives) += 1;
          }
          if (!snapped.empty()) encoder.encode(image, snapped, EncoderKind::kAuto, &e.rows);
          return e;
        },
        [&](size_t f, const Encoded& e) {
          bar.update(static_cast<int64_t>(f + 1));
          if (e.labels.empty()) return;
          partials += e.partials;
          proposal_positives += e.proposal_positives;
          proposal_others += e.proposal_others;
          for (double x : e.aspect_offsets) {
            offset_sum += x;
            offset_sum2 += x * x;
            ++offsets;
          }
          for (int64_t i = 0; i < e.rows.rows(); ++i) {
            const int label = e.labels[static_cast<size_t>(i)];
            all.add(e.rows.row(i), label, -1 - static_cast<int>(f), frames[f].real ? 1 : 0);
            (label == bg ? others : positives) += 1;
          }
          is_val.resize(static_cast<size_t>(all.size()), split.frame_val[f]);
        });
    bar.finish();
    spdlog::info(
        "scene objects: {} boxes of the model's categories, {} of other objects or parts "
        "(background: {} "
        "parts); of them from the proposal boxes: {} of the model's categories, {} background",
        positives, others, partials, proposal_positives, proposal_others);
    if (offsets > 1) {
      const double mean = offset_sum / offsets;
      spdlog::info(
          "proposal boxes that are views of an object: log aspect ratio minus the object's, mean "
          "{:.3f}, standard deviation {:.3f} over {} boxes (train.shape_noise {:.3f})",
          mean, std::sqrt(std::max(0.0, offset_sum2 / offsets - mean * mean)), offsets,
          options.shape_noise);
    }
  }
}

// Keeps the `max` hardest examples of *hard (by *hardness, one per example; ties: the earlier).
void keepHardest(ExampleSet* hard, std::vector<double>* hardness, int64_t max) {
  if (hard->size() <= max) return;
  std::vector<double> sorted = *hardness;
  std::nth_element(sorted.begin(), sorted.begin() + max - 1, sorted.end(), std::greater<double>());
  const double cut = sorted[static_cast<size_t>(max - 1)];
  int64_t kept = 0;
  std::vector<double> kept_h;
  hard->filter([&](int64_t i) {
    const bool k = (*hardness)[static_cast<size_t>(i)] >= cut && kept < max;
    if (k) {
      ++kept;
      kept_h.push_back((*hardness)[static_cast<size_t>(i)]);
    }
    return k;
  });
  *hardness = std::move(kept_h);
}

// `mining_rounds` rounds of hard-negative mining (step 4): the background boxes *clf takes for
// objects join *train and the classifiers are trained again. Returns the boxes added per round.
std::vector<int64_t> mineHardNegatives(
    const TrainingData& d, const TrainOptions& options, Workers& workers,
    const std::function<LinearClassifier(ExampleSet&, const std::string&)>& trainStage,
    ExampleSet* train_set, LinearClassifier* classifier) {
  const std::vector<SceneFrame>& frames = d.frames;
  const std::vector<std::string>& classes = d.classes;
  const Split& split = d.split;
  const int bg = d.bg;
  ExampleSet& train = *train_set;
  LinearClassifier& clf = *classifier;
  std::vector<int64_t> mined;
  if (!frames.empty()) {  // mining searches scene frames
    const int C = static_cast<int>(classes.size());
    for (int round = 1; round <= options.mining_rounds; ++round) {
      ExampleSet hard(train.dims(), train.blockDims());
      std::vector<double> hardness;
      ProgressBar bar("hard negatives, round " + std::to_string(round),
                      static_cast<int64_t>(frames.size()));
      // Each frame's candidates scored by the workers; those taken for objects kept in frame order.
      struct Scored {  // the candidates taken for objects (p(background) < 0.5), in box order
        ReusableMatrix rows;
        std::vector<double> p_background;
      };
      auto score = [&](size_t f, std::unique_ptr<FrameEncoder>& worker) {
        Scored out;
        if (split.frame_val[f]) return out;
        const cv::Mat image = readImage(frames[f].path);
        auto boxes = randomBackgroundBoxes(
            image.cols, image.rows, frames[f].objects, options.mining_candidates_per_frame, options,
            subSeed(static_cast<uint32_t>(options.seed), 10 + static_cast<uint32_t>(round),
                    static_cast<uint32_t>(f)));
        // Parts and overhangs of the objects are candidates too.
        for (size_t o = 0; o < frames[f].objects.size(); ++o) {
          const auto partial = partialBoxes(
              frames[f].objects, o, image.cols, image.rows, options.partial_negatives,
              options.partial_min_iou, options.partial_max_iou,
              subSeed(static_cast<uint32_t>(options.seed), 20 + static_cast<uint32_t>(round),
                      static_cast<uint32_t>(f * 64 + o)));
          boxes.insert(boxes.end(), partial.begin(), partial.end());
        }
        const ReusableMatrix rows = encodeRects(*worker, image, boxes);
        if (rows.rows() == 0) return out;
        MatrixRM s;
        clf.scores(rows.map(), &s);
        std::vector<int64_t> taken;
        for (int64_t i = 0; i < s.rows(); ++i) {
          const double p_bg = backgroundProbability(s.row(i).data(), C);
          if (p_bg >= 0.5) continue;
          taken.push_back(i);
          out.p_background.push_back(p_bg);
        }
        out.rows.resize(static_cast<int64_t>(taken.size()), rows.cols());
        for (size_t k = 0; k < taken.size(); ++k)
          std::copy_n(rows.row(taken[k]), rows.cols(), out.rows.row(static_cast<int64_t>(k)));
        return out;
      };
      orderedParallelFor<Scored>(
          frames.size(), workers, kFrameWindow, score, [&](size_t f, const Scored& scored) {
            bar.update(static_cast<int64_t>(f + 1));
            for (int64_t i = 0; i < scored.rows.rows(); ++i) {
              hard.add(scored.rows.row(i), bg, -1 - static_cast<int>(f), frames[f].real ? 1 : 0);
              hardness.push_back(-scored.p_background[static_cast<size_t>(i)]);
            }
            // Keep the memory bounded: only the hardest mining_max_per_round survive.
            if (hard.size() > 2 * static_cast<int64_t>(options.mining_max_per_round))
              keepHardest(&hard, &hardness, options.mining_max_per_round);
          });
      bar.finish();
      keepHardest(&hard, &hardness, options.mining_max_per_round);
      mined.push_back(hard.size());
      spdlog::info("hard-negative round {}: {} background boxes taken for objects added", round,
                   hard.size());
      if (hard.size() == 0) break;
      train.append(hard);
      clf = trainStage(train, "retrain, round " + std::to_string(round));
    }
  }

  return mined;
}

}  // namespace

RecognizerModel trainModel(const std::vector<std::string>& object_dirs,
                           const std::vector<std::string>& scene_dirs, const TrainOptions& options,
                           TrainReport* report, const std::string& proposals_dir,
                           const std::vector<std::string>& background_object_dirs) {
  const auto started = Clock::now();
  options.encoding.validate();
  const TrainingData d =
      gatherTrainingData(object_dirs, scene_dirs, options, proposals_dir, background_object_dirs);
  const std::vector<LabeledCrop>& crops = d.crops;
  const std::vector<SceneFrame>& frames = d.frames;
  const std::vector<std::string>& classes = d.classes;
  const Split& split = d.split;
  const int bg = d.bg;

  RecognizerModel model;
  model.params = options.encoding;
  {
    std::vector<LabeledCrop> train_crops;
    std::vector<SceneFrame> train_frames;
    for (size_t i = 0; i < crops.size(); ++i)
      if (!split.crop_val[i]) train_crops.push_back(crops[i]);
    for (size_t i = 0; i < frames.size(); ++i)
      if (!split.frame_val[i]) train_frames.push_back(frames[i]);
    ProgressBar bar("vocabulary features",
                    static_cast<int64_t>(train_crops.size() + train_frames.size()));
    fitEncoding(train_crops, train_frames, options, &model.pca, &model.vocabulary,
                [&](int64_t done, int64_t) { bar.update(done); });
    bar.finish();
  }
  Workers workers;
  for (int w = 0; w < workerThreads(options.threads); ++w) {
    workers.push_back(std::make_unique<FrameEncoder>(model.params, model.pca, model.vocabulary));
    workers.back()->setShapeNoise(options.shape_noise);
  }
  Examples ex(model.params.encodedDims(), model.params.pca_dims);
  // The crops on one thread: the first worker's encoder (no encoder's buffers held twice).
  encodeCropExamples(d, options, *workers.front(), &ex);
  encodeCropsInContext(d, options, *workers.front(), &ex);
  encodeBackgroundBoxes(d, options, workers, &ex);
  encodeSceneObjects(d, options, workers, &ex);
  ExampleSet& all = ex.all;
  const std::vector<bool>& is_val = ex.is_val;
  spdlog::info("{} examples encoded, {:.1f} GB in memory", all.size(),
               static_cast<double>(all.allocatedBytes()) / 1e9);
  // Training and held-out parts.
  ExampleSet val = all.select([&](int64_t i) { return is_val[static_cast<size_t>(i)]; });
  ExampleSet train = std::move(all);
  train.filter([&](int64_t i) { return !is_val[static_cast<size_t>(i)]; });

  auto trainStage = [&](ExampleSet& set, const std::string& label) {
    balanceDomains(&set, static_cast<int>(classes.size()), options.real_share);
    ProgressBar bar(label, options.sgd.epochs);
    LinearClassifier clf = trainOneVsAll(
        set, classes, options.sgd, [&](int e) { bar.update(e); }, options.threads);
    bar.finish();
    return clf;
  };
  LinearClassifier clf = trainStage(train, "train classifiers");

  const std::vector<int64_t> mined =
      mineHardNegatives(d, options, workers, trainStage, &train, &clf);

  ValidationSummary summary;
  if (val.size() > 0) {
    MatrixRM s(val.size(), clf.numClasses()), x(1, val.dims()), row;
    std::vector<int> labels;
    for (int64_t i = 0; i < val.size(); ++i) {
      val.get(i, x.data());
      clf.scores(x, &row);
      s.row(i) = row.row(0);
      labels.push_back(val.label(i));
    }
    calibrate(s, labels, &clf);
    summary = summarize(clf, val, d.has_background, split.held_out_instances);
    // Final classifiers on all the data, with the held-out calibration.
    const float temperature = clf.temperature, mix = clf.uniform_mix;
    train.append(val);
    train.append(ex.held_out_mirrors);
    clf = trainStage(train, "final training on all data");
    clf.temperature = temperature;
    clf.uniform_mix = mix;
  } else {
    clf.uniform_mix = 0.01f;  // nothing to fit on: keep a floor so that views can still be summed
  }
  model.classifier = std::move(clf);
  model.exemplars =
      pickExemplars(train, static_cast<int>(classes.size()), bg, options.exemplars_per_class);
  spdlog::info("{} exemplars kept in the model ({:.1f} MB)", model.exemplars.size(),
               static_cast<double>(model.exemplars.bytes()) / 1e6);

  TrainReport local;
  TrainReport& r = report ? *report : local;
  r.classes = classes;
  r.train_crops = 0;
  r.train_negatives = 0;
  for (int64_t i = 0; i < train.size(); ++i)
    (train.label(i) == bg ? r.train_negatives : r.train_crops) += 1;
  r.mined = mined;
  r.validation = summary;
  model.provenance =
      provenance(object_dirs, background_object_dirs, crops, scene_dirs, proposals_dir, options, r,
                 std::chrono::duration<double>(Clock::now() - started).count())
          .dump();
  model.check("trained model");
  return model;
}

namespace {

// `extra`: crops added to the training data of every fold (never tested).
HeldOutResult evaluateFolds(const std::vector<LabeledCrop>& crops,
                            const std::vector<LabeledCrop>& extra,
                            const std::vector<std::set<std::string>>& folds,
                            const TrainOptions& options, const FoldProgress& progress,
                            HeldOutResult result) {
  const size_t C = result.classes.size();
  result.confusion.assign(C, std::vector<int64_t>(C, 0));
  std::vector<std::string> instances = result.instances;
  for (const auto& c : extra)
    if (indexOf(instances, c.instance) < 0) instances.push_back(c.instance);
  const SgdOptions& sgd = options.sgd;
  for (size_t fold = 0; fold < folds.size(); ++fold) {
    const std::set<std::string>& held = folds[fold];
    std::vector<LabeledCrop> train_crops = extra, test_crops;
    for (const auto& c : crops) (held.count(c.instance) ? test_crops : train_crops).push_back(c);
    const std::string stage = "fold " + std::to_string(fold + 1) + "/" +
                              std::to_string(folds.size()) + " (" +
                              (held.size() > 3 ? std::to_string(held.size()) + " instances"
                                               : fmt::format("{}", fmt::join(held, ", "))) +
                              ")";
    Pca pca;
    Vocabulary vocabulary;
    fitEncoding(train_crops, {}, options, &pca, &vocabulary, [&](int64_t d, int64_t t) {
      if (progress) progress(stage + " vocabulary", d, t);
    });
    FrameEncoder encoder(options.encoding, pca, vocabulary);
    encoder.setShapeNoise(options.shape_noise);
    const ExampleSet train = encodeCrops(train_crops, result.classes, instances, encoder,
                                         options.mirror_crops, [&](int64_t d, int64_t t) {
                                           if (progress) progress(stage + " encode", d, t);
                                         });
    encoder.setShapeNoise(0);  // the held-out crops as they are
    const ExampleSet test = encodeCrops(test_crops, result.classes, instances, encoder);
    const LinearClassifier clf = trainOneVsAll(
        train, result.classes, sgd,
        [&](int e) {
          if (progress) progress(stage + " train", e, sgd.epochs);
        },
        options.threads);
    MatrixRM x(1, test.dims()), s;
    std::map<std::string, std::pair<int64_t, int64_t>> per_instance;  // right, total
    for (int64_t i = 0; i < test.size(); ++i) {
      test.get(i, x.data());
      clf.scores(x, &s);
      Eigen::Index best;
      s.row(0).maxCoeff(&best);
      const int label = test.label(i);
      ++result.confusion[static_cast<size_t>(label)][static_cast<size_t>(best)];
      auto& pi = per_instance[instances[static_cast<size_t>(test.group(i))]];
      pi.first += best == label;
      ++pi.second;
      result.correct += best == label;
      ++result.crops;
    }
    for (const auto& [inst, rt] : per_instance) {
      result.instance_accuracy[inst] = 100.0 * rt.first / rt.second;
      spdlog::info("{}: {} {}/{} right ({:.1f}%)", stage, inst, rt.first, rt.second,
                   result.instance_accuracy[inst]);
    }
  }
  return result;
}

// The crops of the extra training sets whose category the evaluated set has; `result.extra_crops`
// counts them.
std::vector<LabeledCrop> extraTrainingCrops(const std::vector<std::string>& extra_dirs,
                                            HeldOutResult& result, const TrainOptions& options) {
  std::vector<LabeledCrop> extra;
  for (const auto& dir : extra_dirs)
    for (auto& c : collectNamedCrops(dir, options.max_views_per_instance))
      if (indexOf(result.classes, c.category) >= 0) extra.push_back(std::move(c));
  if (!extra_dirs.empty() && extra.empty())
    throw DatasetError(
        fmt::format("{}: no crops of the evaluated categories to add to the training",
                    fmt::join(extra_dirs, ", ")));
  result.extra_crops = static_cast<int64_t>(extra.size());
  return extra;
}

HeldOutResult prepare(const std::vector<LabeledCrop>& crops, const std::string& object_dir,
                      const char* protocol) {
  std::set<std::string> category_set, instance_set;
  for (const auto& c : crops) {
    category_set.insert(c.category);
    instance_set.insert(c.instance);
  }
  HeldOutResult r;
  r.protocol = protocol;
  r.classes.assign(category_set.begin(), category_set.end());
  r.instances.assign(instance_set.begin(), instance_set.end());
  if (r.classes.size() < 2) throw DatasetError(object_dir + ": evaluation needs two categories");
  return r;
}

}  // namespace

HeldOutResult leaveOneInstanceOut(const std::string& object_dir, const TrainOptions& options,
                                  const FoldProgress& progress,
                                  const std::vector<std::string>& extra_dirs,
                                  const std::vector<std::string>& held_out) {
  const std::vector<LabeledCrop> crops = collectCrops({object_dir}, options.max_views_per_instance);
  HeldOutResult r = prepare(crops, object_dir, "leave-one-instance-out");
  for (const auto& inst : held_out)
    if (indexOf(r.instances, inst) < 0)
      throw DatasetError(object_dir + ": no instance " + inst + " to hold out");
  std::vector<std::set<std::string>> folds;
  for (const auto& inst : held_out.empty() ? r.instances : held_out) folds.push_back({inst});
  const std::vector<LabeledCrop> extra = extraTrainingCrops(extra_dirs, r, options);
  return evaluateFolds(crops, extra, folds, options, progress, r);
}

HeldOutResult oneInstancePerCategoryOut(const std::string& object_dir, const TrainOptions& options,
                                        const FoldProgress& progress,
                                        const std::vector<std::string>& extra_dirs) {
  const std::vector<LabeledCrop> crops = collectCrops({object_dir}, options.max_views_per_instance);
  HeldOutResult r = prepare(crops, object_dir, "one held-out instance per category");
  TrainOptions o = options;
  o.validation = true;
  const Split split = makeSplit(crops, {}, o);
  if (split.held_out_instances.empty())
    throw DatasetError(object_dir + ": no category has two instances");
  const std::vector<LabeledCrop> extra = extraTrainingCrops(extra_dirs, r, options);
  return evaluateFolds(
      crops, extra,
      {std::set<std::string>(split.held_out_instances.begin(), split.held_out_instances.end())},
      options, progress, r);
}

namespace {

// The classes of a model with `categories` added to the base's (background stays last); fills
// r.added and r.replaced. A category the base has is refused unless `replace`.
std::vector<std::string> classesWithAdded(const RecognizerModel& base,
                                          const std::set<std::string>& categories, bool replace,
                                          AddClassesReport& r) {
  const std::vector<std::string>& old = base.classifier.classes;  // background last
  std::vector<std::string> classes(old.begin(), old.end() - 1);
  r.added.clear();
  r.replaced.clear();
  for (const auto& c : categories) {
    if (std::find(classes.begin(), classes.end(), c) == classes.end()) {
      r.added.push_back(c);
    } else if (!replace) {
      throw std::runtime_error(
          "class '" + c +
          "' is already in the base model (--replace trains it from these views instead)");
    } else {
      r.replaced.push_back(c);
    }
  }
  classes.insert(classes.end(), r.added.begin(), r.added.end());
  classes.push_back("background");
  return classes;
}

// The base's exemplars, relabelled to `classes`, but those of the replaced classes.
ExampleSet keptExemplars(const RecognizerModel& base, const std::vector<std::string>& classes,
                         const std::vector<std::string>& replaced) {
  const std::vector<std::string>& old = base.classifier.classes;
  const int64_t dims = base.params.encodedDims();
  ExampleSet set(dims, base.params.pca_dims);
  std::vector<float> row(static_cast<size_t>(dims));
  for (int64_t i = 0; i < base.exemplars.size(); ++i) {
    const std::string& name = old[static_cast<size_t>(base.exemplars.label(i))];
    if (indexOf(replaced, name) >= 0) continue;
    base.exemplars.get(i, row.data());
    set.add(row.data(), indexOf(classes, name), -1, base.exemplars.domain(i));
  }
  return set;
}

// The base's classifier rows for the classes it keeps, `fresh`'s rows (one per `trained` class)
// for the new and replaced ones; the base's calibration.
LinearClassifier mergedClassifier(const RecognizerModel& base,
                                  const std::vector<std::string>& classes,
                                  const std::vector<std::string>& trained,
                                  const LinearClassifier& fresh) {
  const std::vector<std::string>& old = base.classifier.classes;
  const int C = static_cast<int>(classes.size());
  LinearClassifier clf;
  clf.classes = classes;
  clf.weights.resize(C, base.params.encodedDims());
  clf.bias.resize(C);
  for (size_t i = 0; i < old.size(); ++i) {
    if (indexOf(trained, old[i]) >= 0) continue;
    const int c = indexOf(classes, old[i]);
    clf.weights.row(c) = base.classifier.weights.row(static_cast<int64_t>(i));
    clf.bias[c] = base.classifier.bias[static_cast<int64_t>(i)];
  }
  for (size_t t = 0; t < trained.size(); ++t) {
    const int c = indexOf(classes, trained[t]);
    clf.weights.row(c) = fresh.weights.row(static_cast<int64_t>(t));
    clf.bias[c] = fresh.bias[static_cast<int64_t>(t)];
  }
  clf.temperature = base.classifier.temperature;
  clf.uniform_mix = base.classifier.uniform_mix;
  return clf;
}

std::string addedClassesProvenance(const RecognizerModel& base,
                                   const std::vector<std::string>& object_dirs,
                                   const AddClassesReport& r) {
  nlohmann::json j;
  j["kind"] = "classes added";
  j["added_classes"] = r.added;
  j["replaced_classes"] = r.replaced;
  j["object_sets"] = object_dirs;
  j["views"] = r.views;
  j["examples"] = {
      {"classes", r.positives}, {"background", r.background}, {"base_exemplars", r.exemplars}};
  j["seconds"] = r.seconds;
  try {
    j["base"] = nlohmann::json::parse(base.provenance);
  } catch (const nlohmann::json::exception&) {
    j["base"] = base.provenance;
  }
  return j.dump();
}

}  // namespace

RecognizerModel addClasses(const RecognizerModel& base, const std::vector<std::string>& object_dirs,
                           const TrainOptions& options, bool replace, AddClassesReport* report) {
  const auto started = Clock::now();
  AddClassesReport local;
  AddClassesReport& r = report ? *report : local;
  if (!base.hasBackground()) throw std::runtime_error("the base model has no background class");
  if (base.exemplars.size() == 0)
    throw std::runtime_error(
        "the base model holds no exemplars (trained before models kept them): train it again (make "
        "model, "
        "slamaware-train) to add classes to it");
  std::vector<LabeledCrop> crops;
  for (const auto& dir : object_dirs) {
    auto c = collectNamedCrops(dir, 0);
    crops.insert(crops.end(), c.begin(), c.end());
  }
  std::set<std::string> categories;
  for (const auto& c : crops)
    if (c.category != "background") categories.insert(c.category);
  if (categories.empty())
    throw DatasetError(
        fmt::format("{}: no views of any class (only background)", fmt::join(object_dirs, ", ")));
  const std::vector<std::string> classes = classesWithAdded(base, categories, replace, r);
  const int C = static_cast<int>(classes.size()), bg = C - 1;

  ExampleSet set = keptExemplars(base, classes, r.replaced);
  r.exemplars = set.size();
  ExampleSet fresh;
  {
    std::vector<std::string> instances;
    for (const auto& c : crops)
      if (indexOf(instances, c.instance) < 0) instances.push_back(c.instance);
    FrameEncoder encoder(base.params, base.pca, base.vocabulary);
    encoder.setShapeNoise(options.shape_noise);
    ProgressBar bar("encode views", static_cast<int64_t>(crops.size()));
    fresh = encodeCrops(
        crops, classes, instances, encoder, options.mirror_crops,
        [&](int64_t done, int64_t) { bar.update(done); }, bg);
    bar.finish();
  }
  r.views = static_cast<int64_t>(crops.size());
  r.positives = r.background = 0;
  for (int64_t i = 0; i < fresh.size(); ++i)
    (fresh.label(i) == bg ? r.background : r.positives) += 1;
  set.append(fresh);

  // The base's classifiers stay as the base learnt them from all its data. Only the new (and
  // replaced) classes are trained: one-vs-all rows are independent, so each is trained against
  // every other example of this small set (the exemplars, the sets' background, the other new
  // classes), which all take one label here.
  std::vector<std::string> trained;
  for (const auto& c : classes)
    if (indexOf(r.added, c) >= 0 || indexOf(r.replaced, c) >= 0) trained.push_back(c);
  ExampleSet relabelled = set.select([](int64_t) { return true; });
  const int rest = static_cast<int>(trained.size());
  for (int64_t i = 0; i < relabelled.size(); ++i) {
    const int t = indexOf(trained, classes[static_cast<size_t>(relabelled.label(i))]);
    relabelled.setLabel(i, t >= 0 ? t : rest);
  }
  std::vector<std::string> trained_and_rest = trained;
  trained_and_rest.push_back("(every other)");
  ProgressBar bar("train classifiers", options.sgd.epochs);
  const LinearClassifier fresh_rows = trainOneVsAll(
      relabelled, trained_and_rest, options.sgd, [&](int e) { bar.update(e); }, options.threads);
  bar.finish();

  RecognizerModel model;
  model.params = base.params;
  model.pca = base.pca;
  model.vocabulary = base.vocabulary;
  model.classifier = mergedClassifier(base, classes, trained, fresh_rows);
  model.exemplars = set.select([&](int64_t i) { return i < r.exemplars; });
  model.exemplars.append(pickExemplars(fresh, C, bg, options.exemplars_per_class));
  r.seconds = std::chrono::duration<double>(Clock::now() - started).count();
  model.provenance = addedClassesProvenance(base, object_dirs, r);
  model.check("model with added classes");
  return model;
}

std::string AddClassesReport::toText() const {
  return fmt::format(
      "added classes: {}{}{}\n{} views read; trained on {} examples of the classes, {} background, "
      "{} exemplars of "
      "the base model, in {:.1f} s\n",
      added.empty() ? "none" : fmt::format("{}", fmt::join(added, ", ")),
      replaced.empty() ? "" : "; retrained: ", fmt::format("{}", fmt::join(replaced, ", ")), views,
      positives, background, exemplars, seconds);
}

std::string provenanceText(const RecognizerModel& model) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(model.provenance);
  } catch (const nlohmann::json::exception&) {
    return "provenance (not JSON):\n" + model.provenance + "\n";
  }
  std::ostringstream o;
  o << "classes: " << fmt::format("{}", fmt::join(model.classifier.classes, ", ")) << "\n";
  // Classes added to a base model (addClasses), possibly several times: each step, then the base.
  while (j.is_object() && j.value("kind", std::string()) == "classes added") {
    o << fmt::format(
        "classes {} added{} from {} views of {} (slamaware-train --base), to a model:\n",
        fmt::join(j["added_classes"].get<std::vector<std::string>>(), ", "),
        j["replaced_classes"].empty()
            ? std::string()
            : fmt::format(" ({} retrained)",
                          fmt::join(j["replaced_classes"].get<std::vector<std::string>>(), ", ")),
        j.value("views", int64_t{0}),
        fmt::join(j["object_sets"].get<std::vector<std::string>>(), ", "));
    const nlohmann::json next = j["base"];
    j = next;
  }
  if (!j.is_object()) {
    o << "provenance (not JSON):\n" << j.dump() << "\n";
    return o.str();
  }
  if (!j.contains("format")) {  // a model trained before the provenance named sets and options
    o << "provenance (older format):\n" << j.dump(2) << "\n";
    return o.str();
  }
  o << fmt::format("trained in {:.1f} min, peak memory {:.0f} MB\n",
                   j.value("training_s", 0.0) / 60, j.value("peak_rss_mb", 0.0));
  o << "object sets:\n";
  for (const auto& s : j["object_sets"])
    o << fmt::format("  {:<12} {:<13} {:<48} {:>5} of {:>5} views, {:>3} instances ({})\n",
                     s["role"].get<std::string>(), s["kind"].get<std::string>(),
                     s["path"].get<std::string>(), s["crops_used"].get<int64_t>(),
                     s["views"].get<int64_t>(), s["instances_used"].get<int64_t>(),
                     fmt::join(s["categories_used"].get<std::vector<std::string>>(), ", "));
  o << "scenes:\n";
  for (const auto& s : j["scenes"])
    o << fmt::format("  {:<13} {:<48} {:>5} frames, {:>6} boxes\n", s["kind"].get<std::string>(),
                     s["path"].get<std::string>(), s["frames"].get<int64_t>(),
                     s["boxes"].get<int64_t>());
  if (j.contains("proposals")) o << "proposal boxes: " << j["proposals"].get<std::string>() << "\n";
  const auto& r = j["report"];
  o << fmt::format("examples: {} of objects, {} background", r.value("train_crops", int64_t{0}),
                   r.value("train_negatives", int64_t{0}));
  if (r.contains("mined_per_round"))
    o << fmt::format(" (hard negatives mined: {})",
                     fmt::join(r["mined_per_round"].get<std::vector<int64_t>>(), ", "));
  o << "\n";
  if (r.contains("validation")) {
    const auto& v = r["validation"];
    o << fmt::format(
        "validation on held-out instances and frames: {} crops, best class right {:.1f}% "
        "(photographed: {} crops, "
        "{:.1f}%); {} background boxes, {:.1f}% called background (photographed: {}, {:.1f}%); NLL "
        "{:.3f}\n",
        v.value("crops", int64_t{0}), v.value("accuracy", 0.0), v.value("real_crops", int64_t{0}),
        v.value("real_accuracy", 0.0), v.value("negatives", int64_t{0}),
        v.value("background_accuracy", 0.0), v.value("real_negatives", int64_t{0}),
        v.value("real_background_accuracy", 0.0), v.value("nll", 0.0));
  }
  o << "options (a config that trains it again with slamaware-train --config):\n"
    << j.value("config", std::string());
  return o.str();
}

}  // namespace slamaware::recognizer
