#include "tools/eval/recognition_metrics.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <set>
#include <tuple>
#include <opencv2/imgproc.hpp>

#include "common/bus/log_reader.h"
#include "common/geometry.h"
#include "common/image_codec.h"
#include "procs/objectmap/fusion.h"
#include "tools/eval/plot.h"

namespace slamaware {

namespace {

constexpr double kNegInf = -std::numeric_limits<double>::infinity();
/// As the object map: a log-probability below this is this (sums stay finite).
constexpr double kMinLogProb = -100.0;

nlohmann::json percentOrNull(double num, double den) {
  return den > 0 ? nlohmann::json(100.0 * num / den) : nlohmann::json(nullptr);
}

nlohmann::json numberOrNull(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

int argmaxOf(const std::vector<double>& v) {
  int best = -1;
  for (size_t i = 0; i < v.size(); ++i)
    if (!std::isnan(v[i]) && (best < 0 || v[i] > v[static_cast<size_t>(best)])) best = static_cast<int>(i);
  return best;
}

/// log-softmax of summed log-evidence (shifted by its maximum).
std::vector<double> logSoftmax(const std::vector<double>& e) {
  if (e.empty()) return {};
  const double m = *std::max_element(e.begin(), e.end());
  double s = 0;
  for (double v : e) s += std::exp(v - m);
  std::vector<double> out(e.size());
  for (size_t i = 0; i < e.size(); ++i) out[i] = e[i] - m - std::log(s);
  return out;
}

// log(p / (1 - p)) of class k from log-probabilities of all classes: log p_k - log sum_{j != k} p_j.
// Monotone in p_k, so it ranks boxes as p_k does, but without the ties that rounding makes of
// posteriors saturated at 1 (fused over hundreds of views) or at 0.
double logOdds(const std::vector<double>& log_p, size_t k) {
  if (k >= log_p.size() || std::isnan(log_p[k]) || log_p[k] == kNegInf) return kNegInf;
  double m = kNegInf;
  for (size_t j = 0; j < log_p.size(); ++j)
    if (j != k && !std::isnan(log_p[j])) m = std::max(m, log_p[j]);
  if (m == kNegInf) return std::numeric_limits<double>::infinity();
  double s = 0;
  for (size_t j = 0; j < log_p.size(); ++j)
    if (j != k && !std::isnan(log_p[j])) s += std::exp(log_p[j] - m);
  return log_p[k] - (m + std::log(s));
}

bool usableBox(const box_t& b) {
  return std::isfinite(b.x) && std::isfinite(b.y) && std::isfinite(b.w) && std::isfinite(b.h) && b.w > 0 && b.h > 0;
}

}  // namespace

// ---- Average precision ------------------------------------------------------------------------

double averagePrecision(std::vector<ScoredDetection> d, int num_truth, std::vector<PrPoint>* curve) {
  if (curve) curve->clear();
  if (num_truth <= 0) return std::numeric_limits<double>::quiet_NaN();
  std::sort(d.begin(), d.end(), [](const ScoredDetection& a, const ScoredDetection& b) { return a.score > b.score; });
  std::vector<PrPoint> points;
  int tp = 0, fp = 0;
  for (size_t i = 0; i < d.size();) {
    size_t j = i;
    for (; j < d.size() && d[j].score == d[i].score; ++j) (d[j].true_positive ? tp : fp) += 1;
    points.push_back({static_cast<double>(tp) / num_truth, static_cast<double>(tp) / (tp + fp)});
    i = j;
  }
  if (curve) *curve = points;
  // VOC 2010+ devkit: mrec = [0, rec, 1], mpre = [0, prec, 0], precision made monotone from the
  // right, area summed where recall changes.
  std::vector<double> mrec{0.0}, mpre{0.0};
  for (const auto& p : points) mrec.push_back(p.recall), mpre.push_back(p.precision);
  mrec.push_back(1.0);
  mpre.push_back(0.0);
  for (size_t i = mpre.size() - 1; i-- > 0;) mpre[i] = std::max(mpre[i], mpre[i + 1]);
  double ap = 0;
  for (size_t i = 1; i < mrec.size(); ++i)
    if (mrec[i] != mrec[i - 1]) ap += (mrec[i] - mrec[i - 1]) * mpre[i];
  return ap;
}

// ---- Scoring ----------------------------------------------------------------------------------

RecognitionScores emptyScores(const std::vector<std::string>& evaluated_classes) {
  RecognitionScores s;
  for (const auto& c : evaluated_classes) s.classes[c];
  return s;
}

void scoreFrame(const std::vector<std::string>& model_classes, const std::vector<LabelledBox>& boxes,
                const std::vector<GroundTruthBox>& truth, double iou_threshold, RecognitionScores* s) {
  ++s->frames;
  s->boxes += static_cast<int>(boxes.size());
  const auto background = std::find(model_classes.begin(), model_classes.end(), std::string(kBackgroundClass));
  const int bg = background == model_classes.end() ? -1 : static_cast<int>(background - model_classes.begin());
  std::vector<int> label(boxes.size());
  for (size_t i = 0; i < boxes.size(); ++i) label[i] = boxes[i].label >= 0 ? boxes[i].label : argmaxOf(boxes[i].log_p);
  std::vector<Box2> truth_boxes;
  for (const auto& t : truth) truth_boxes.push_back({t.x, t.y, t.w, t.h});

  // Per class: every box is a detection scored log p(class); greedy matching in descending score
  // (ties: the earlier box), each to the unmatched ground-truth box of the class it overlaps most.
  for (auto& [cls, tally] : s->classes) {
    const auto it = std::find(model_classes.begin(), model_classes.end(), cls);
    std::vector<size_t> gt;
    for (size_t j = 0; j < truth.size(); ++j)
      if (truth[j].cls == cls) gt.push_back(j);
    tally.truth += static_cast<int>(gt.size());
    for (const size_t g : gt)
      tally.boxed += std::any_of(boxes.begin(), boxes.end(),
                                 [&](const LabelledBox& b) { return iou(b.box, truth_boxes[g]) >= iou_threshold; });
    if (it == model_classes.end()) continue;  // the model cannot say it: no detections
    const size_t k = static_cast<size_t>(it - model_classes.begin());
    std::vector<size_t> order(boxes.size());
    std::iota(order.begin(), order.end(), 0);
    auto score = [&](size_t i) { return logOdds(boxes[i].log_p, k); };
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return score(a) > score(b); });
    auto match = [&](size_t i, std::vector<bool>& matched) {
      int best = -1;
      double best_iou = iou_threshold;
      for (size_t g = 0; g < gt.size(); ++g) {
        if (matched[g]) continue;
        const double v = iou(boxes[i].box, truth_boxes[gt[g]]);
        if (v >= best_iou && (best < 0 || v > best_iou)) best = static_cast<int>(g), best_iou = v;
      }
      if (best >= 0) matched[static_cast<size_t>(best)] = true;
      return best >= 0;
    };
    std::vector<bool> matched(gt.size(), false), matched_labelled(gt.size(), false);
    for (size_t i : order) {
      tally.ranked.push_back({score(i), match(i, matched)});
      if (label[i] != static_cast<int>(k)) continue;
      ++tally.labelled;
      tally.labelled_tp += match(i, matched_labelled);
    }
  }

  // Where each box is and what it was called.
  for (size_t i = 0; i < boxes.size(); ++i) {
    int best = -1;
    double best_iou = iou_threshold;
    for (size_t j = 0; j < truth_boxes.size(); ++j) {
      const double v = iou(boxes[i].box, truth_boxes[j]);
      if (v >= best_iou && (best < 0 || v > best_iou)) best = static_cast<int>(j), best_iou = v;
    }
    const bool is_bg = label[i] == bg && bg >= 0;
    const std::string name = label[i] >= 0 ? model_classes[static_cast<size_t>(label[i])] : "none";
    if (best < 0) {
      ++s->boxes_elsewhere;
      s->background_elsewhere += is_bg;
    } else if (s->classes.count(truth[static_cast<size_t>(best)].cls)) {
      const std::string& t = truth[static_cast<size_t>(best)].cls;
      ++s->boxes_on_objects;
      s->correct_on_objects += name == t;
      s->background_on_objects += is_bg;
      ++s->confusion[t][name];
    } else {
      ++s->boxes_on_distractors;
      s->background_on_distractors += is_bg;
    }
  }
}

void mergeRecognition(RecognitionScores* into, const RecognitionScores& more) {
  for (const auto& [cls, t] : more.classes) {
    ClassTally& a = into->classes[cls];
    a.ranked.insert(a.ranked.end(), t.ranked.begin(), t.ranked.end());
    a.truth += t.truth;
    a.labelled += t.labelled;
    a.labelled_tp += t.labelled_tp;
    a.boxed += t.boxed;
  }
  into->frames += more.frames;
  into->boxes += more.boxes;
  into->boxes_on_objects += more.boxes_on_objects;
  into->correct_on_objects += more.correct_on_objects;
  into->background_on_objects += more.background_on_objects;
  into->boxes_on_distractors += more.boxes_on_distractors;
  into->background_on_distractors += more.background_on_distractors;
  into->boxes_elsewhere += more.boxes_elsewhere;
  into->background_elsewhere += more.background_elsewhere;
  for (const auto& [t, row] : more.confusion)
    for (const auto& [l, n] : row) into->confusion[t][l] += n;
  into->fallback_boxes += more.fallback_boxes;
}

nlohmann::json recognitionSection(const RecognitionScores& s) {
  nlohmann::json j;
  j["per_class"] = nlohmann::json::object();
  double ap_sum = 0, boxed_sum = 0;
  int ap_classes = 0, truth = 0, tp = 0, boxed = 0;
  for (const auto& [cls, t] : s.classes) {
    const double ap = averagePrecision(t.ranked, t.truth);
    if (std::isfinite(ap)) ap_sum += ap, boxed_sum += static_cast<double>(t.boxed) / t.truth, ++ap_classes;
    truth += t.truth;
    tp += t.labelled_tp;
    boxed += t.boxed;
    nlohmann::json c;
    c["AP"] = numberOrNull(100.0 * ap);
    c["precision"] = percentOrNull(t.labelled_tp, t.labelled);
    c["recall"] = percentOrNull(t.labelled_tp, t.truth);
    c["ground_truth_boxes"] = t.truth;
    c["labelled_boxes"] = t.labelled;
    c["true_positives"] = t.labelled_tp;
    c["boxed"] = percentOrNull(t.boxed, t.truth);
    j["per_class"][cls] = c;
  }
  j["mAP"] = ap_classes > 0 ? nlohmann::json(100.0 * ap_sum / ap_classes) : nlohmann::json(nullptr);
  j["recall"] = percentOrNull(tp, truth);
  // What the boxes allow: a ground-truth box no box overlaps at the threshold is missed whatever the
  // labels, so a class's AP is at most its share of boxed ground truth, and the mAP at most their mean.
  j["boxed"] = percentOrNull(boxed, truth);
  j["mAP_bound"] = ap_classes > 0 ? nlohmann::json(100.0 * boxed_sum / ap_classes) : nlohmann::json(nullptr);
  j["classes_with_ground_truth"] = ap_classes;
  j["frames_evaluated"] = s.frames;
  j["boxes"] = s.boxes;
  j["ground_truth_boxes"] = truth;
  nlohmann::json d;
  d["boxes_on_objects"] = s.boxes_on_objects;
  d["accuracy_on_objects"] = percentOrNull(s.correct_on_objects, s.boxes_on_objects);
  d["background_on_objects"] = percentOrNull(s.background_on_objects, s.boxes_on_objects);
  d["boxes_on_distractors"] = s.boxes_on_distractors;
  d["background_on_distractors"] = percentOrNull(s.background_on_distractors, s.boxes_on_distractors);
  d["boxes_elsewhere"] = s.boxes_elsewhere;
  d["background_elsewhere"] = percentOrNull(s.background_elsewhere, s.boxes_elsewhere);
  d["confusion"] = s.confusion;
  j["diagnostics"] = d;
  j["fallback_boxes"] = s.fallback_boxes;
  return j;
}

void drawPrCurves(const RecognitionScores& single, const RecognitionScores& multi, const std::string& title,
                  const std::string& path) {
  std::vector<std::string> classes;
  for (const auto& [cls, t] : single.classes)
    if (t.truth > 0) classes.push_back(cls);
  if (classes.empty()) return;
  const int cols = std::min<int>(3, static_cast<int>(classes.size()));
  const int rows = (static_cast<int>(classes.size()) + cols - 1) / cols;
  const int pw = 420, ph = 340, header = 34;
  cv::Mat img(header + rows * ph, cols * pw, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::putText(img, title, cv::Point(12, 22), cv::FONT_HERSHEY_SIMPLEX, 0.55, plot_colour::kBlack, 1, cv::LINE_AA);
  const std::vector<double> ticks{0, 20, 40, 60, 80, 100};
  for (size_t n = 0; n < classes.size(); ++n) {
    const std::string& cls = classes[n];
    const cv::Rect area(static_cast<int>(n % cols) * pw, header + static_cast<int>(n / cols) * ph, pw, ph);
    PlotPanel panel(img, area, PlotAxis{0, 100, false, ticks, "recall (%)"},
                    PlotAxis{0, 100, false, ticks, "precision (%)"},
                    cls + ": " + std::to_string(single.classes.at(cls).truth) + " ground-truth boxes");
    auto draw = [&](const RecognitionScores& s, const cv::Scalar& colour, const std::string& name) {
      const auto it = s.classes.find(cls);
      if (it == s.classes.end()) return;
      std::vector<PrPoint> curve;
      const double ap = averagePrecision(it->second.ranked, it->second.truth, &curve);
      std::vector<cv::Point2d> points;
      if (!curve.empty() && curve[0].recall > 0) points.emplace_back(0, 100 * curve[0].precision);
      for (const auto& p : curve) points.emplace_back(100 * p.recall, 100 * p.precision);
      char label[96];
      std::snprintf(label, sizeof label, "%s AP %.1f", name.c_str(), 100 * ap);
      panel.curve(points, colour, label);
      // The reported label's operating point (argmax).
      const ClassTally& t = it->second;
      if (t.labelled > 0)
        panel.curve({{100.0 * t.labelled_tp / t.truth, 100.0 * t.labelled_tp / t.labelled}}, colour, "", 4);
    };
    draw(single, plot_colour::kBlue, "single view");
    draw(multi, plot_colour::kOrange, "multi-view");
  }
  writeImage(path, img);
}

// ---- Multi-view labels ------------------------------------------------------------------------

MultiViewLabeller::MultiViewLabeller(const ObjectMapOptions& options)
    : engine_(options), fusion_(options.fusion()) {}

void MultiViewLabeller::countRefusal(bool accepted, const char* channel, const std::string& why) {
  if (accepted) return;
  ++refused_;
  spdlog::debug("objectmap refused {}: {}", channel, why);
}
void MultiViewLabeller::onCameraInfo(const camera_info_t& m) {
  std::string why;
  countRefusal(engine_.onCameraInfo(m, &why), "CAMERA_INFO", why);
}
void MultiViewLabeller::onMap(const point_cloud_t& m) {
  std::string why;
  countRefusal(engine_.onMap(m, &why), "SLAM_MAP", why);
}
void MultiViewLabeller::onPose(const pose_t& m) {
  std::string why;
  countRefusal(engine_.onPose(m, &why), "SLAM_POSE", why);
}
void MultiViewLabeller::onProposals(const proposals_t& m) {
  std::string why;
  countRefusal(engine_.onProposals(m, &why), "PROPOSALS", why);
}

void MultiViewLabeller::onDetections(const detections_t& d) {
  std::string why;
  countRefusal(engine_.onDetections(d, &why), "DETECTIONS", why);
  // The candidate's own evidence, for the fallback: one box per frame (the most object-like), as the map.
  if (own_classes_.empty()) own_classes_ = d.class_names;
  std::vector<int> index(own_classes_.size(), -1);
  for (size_t k = 0; k < own_classes_.size(); ++k)
    for (size_t n = 0; n < d.class_names.size(); ++n)
      if (d.class_names[n] == own_classes_[k]) index[k] = static_cast<int>(n);
  const size_t nb = std::min({d.boxes.size(), d.candidate_ids.size(), d.log_prob.size()});
  for (size_t i = 0; i < nb; ++i) {
    const auto& row = d.log_prob[i];
    if (!usableBox(d.boxes[i]) || row.empty() ||
        std::any_of(row.begin(), row.end(), [](float v) { return std::isnan(v); }))
      continue;
    OwnView v;
    v.area = d.boxes[i].w * d.boxes[i].h;
    const float floor = *std::min_element(row.begin(), row.end());
    for (int n : index) v.log_p.push_back(n >= 0 && static_cast<size_t>(n) < row.size() ? row[n] : floor);
    auto& views = own_[{d.map_id, d.candidate_ids[i]}];
    auto it = views.find(d.seq);
    if (it == views.end() || moreObjectLikeView(v.log_p, v.area, it->second.log_p, it->second.area))
      views[d.seq] = std::move(v);
  }
}

std::vector<double> MultiViewLabeller::logPosterior(int32_t map_id, int32_t candidate,
                                                    const std::vector<std::string>& classes, bool* from_object) {
  std::vector<double> evidence;
  double weight = 0;
  std::vector<std::string> names;
  const Object* o = engine_.objectOfCandidate(map_id, candidate);
  if (o && !o->log_evidence.empty()) {
    evidence = o->log_evidence;
    weight = o->evidence_weight;
    names = engine_.classes();
  } else if (auto it = own_.find({map_id, candidate}); it != own_.end()) {
    // As the map fuses (procs/objectmap/fusion.h), each view clamped as the map clamps.
    std::vector<std::vector<float>> clamped;
    for (const auto& [seq, v] : it->second) {
      clamped.push_back(v.log_p);
      for (float& x : clamped.back()) x = std::clamp(x, static_cast<float>(kMinLogProb), 0.f);
    }
    std::vector<const std::vector<float>*> views;
    for (const auto& v : clamped) views.push_back(&v);
    evidence = sumLogProbabilities(views, own_classes_.size(), fusion_.objectness_weights, &weight);
    names = own_classes_;
  }
  if (from_object) *from_object = o && !o->log_evidence.empty();
  // As the map's posterior (posteriorFromLogEvidence), in logs.
  const std::vector<double> lp = logSoftmax(scaledLogEvidence(evidence, weight, fusion_.views_exponent));
  std::vector<double> out(classes.size(), kNegInf);
  for (size_t k = 0; k < classes.size(); ++k)
    for (size_t n = 0; n < names.size(); ++n)
      if (names[n] == classes[k]) out[k] = lp[n];
  if (names.empty() && !classes.empty()) std::fill(out.begin(), out.end(), -std::log(double(classes.size())));
  return out;
}

double logObjectness(const std::vector<double>& log_p) {
  if (log_p.empty()) return 0.0;
  // log(1 - p(background)), exact also for p(background) near 0 or 1.
  const double lb = std::min(0.0, log_p.back());
  return lb > -0.693 ? std::log(-std::expm1(lb)) : std::log1p(-std::exp(lb));
}

namespace {

// Adds `log_factors[c]` to each object class c of `log_p` (background last) and gives the
// background the rest of the probability.
void scaleObjectClasses(std::vector<double>* log_p, const std::vector<double>& log_factors) {
  if (log_p->empty()) return;
  const size_t bg = log_p->size() - 1;
  double object_sum = 0;
  for (size_t c = 0; c < bg; ++c) {
    (*log_p)[c] += log_factors[c];
    object_sum += std::exp((*log_p)[c]);
  }
  (*log_p)[bg] = std::log(std::max(1e-300, 1.0 - std::min(1.0, object_sum)));
}

void scaleObjectClasses(std::vector<double>* log_p, double log_factor) {
  scaleObjectClasses(log_p, std::vector<double>(log_p->size(), log_factor));
}

// The share of box a's area that lies inside box b (0 for an empty a).
double shareInside(const Box2& a, const Box2& b) {
  const double area = a.w * a.h;
  return area > 0 ? rectIntersection(a.x, a.y, a.w, a.h, b.x, b.y, b.w, b.h) / area : 0.0;
}

}  // namespace

std::vector<double> multiViewScores(const std::vector<double>& fused, const std::vector<double>& log_box) {
  std::vector<double> out = fused;
  if (log_box.size() == out.size()) scaleObjectClasses(&out, log_box);
  return out;
}

void scoreMultiView(std::map<int32_t, std::vector<RecognitionRecording::Box>>* frames) {
  // p(object | box) over the boxes of each candidate (their mean) and of each object (their median).
  using Key = std::pair<int32_t, int32_t>;  // (map, candidate) or (map, object)
  struct Views {
    std::vector<double> p;
    double logMean() const { return std::log(std::max(1e-300, std::accumulate(p.begin(), p.end(), 0.0) / p.size())); }
    double logMedian() const {
      std::vector<double> q = p;
      const size_t n = q.size(), m = n / 2;
      std::nth_element(q.begin(), q.begin() + m, q.end());
      const double upper = q[m];
      const double median = n % 2 ? upper : (*std::max_element(q.begin(), q.begin() + m) + upper) / 2;
      return std::log(std::max(1e-300, median));
    }
  };
  std::map<Key, Views> candidates, objects;
  for (auto& [seq, boxes] : *frames)
    for (auto& b : boxes) {
      b.log_objectness = logObjectness(b.single.log_p);
      candidates[{b.map_id, b.candidate}].p.push_back(std::exp(b.log_objectness));
      if (b.object >= 0) objects[{b.map_id, b.object}].p.push_back(std::exp(b.log_objectness));
    }
  // A box without an object: its candidate's median stands in for the object's.
  std::map<Key, double> candidate_mean, candidate_median, object_median;
  for (const auto& [key, views] : candidates) {
    candidate_mean[key] = views.logMean();
    candidate_median[key] = views.logMedian();
  }
  for (const auto& [key, views] : objects) object_median[key] = views.logMedian();
  for (auto& [seq, boxes] : *frames)
    for (auto& b : boxes) {
      const double views = candidate_mean.at({b.map_id, b.candidate}) +
                           (b.object >= 0 ? object_median.at({b.map_id, b.object})
                                          : candidate_median.at({b.map_id, b.candidate}));
      b.log_objectness = (b.log_objectness + views) / 3;
      // Per class c, the box's own view's p(c | box) in place of its 1 - p(background | box).
      std::vector<double> log_box(b.fused.log_p.size(), b.log_objectness);
      if (b.single.log_p.size() == log_box.size())
        for (size_t c = 0; c + 1 < log_box.size(); ++c) log_box[c] = (std::min(0.0, b.single.log_p[c]) + views) / 3;
      b.multi.log_p = multiViewScores(b.fused.log_p, log_box);
    }
}

int demoteDuplicateBoxes(std::vector<RecognitionRecording::Box>* boxes) {
  std::map<int32_t, size_t> best;  // object -> the box its own view finds most object-like
  // By log p(background | box) itself: 1 - p(background) rounds to 1 for the many boxes whose
  // view is sure (log p(background) of -800), and they would tie.
  const auto background = [](const RecognitionRecording::Box& b) {
    return b.single.log_p.empty() ? 0.0 : b.single.log_p.back();
  };
  for (size_t i = 0; i < boxes->size(); ++i) {
    const int32_t o = (*boxes)[i].object;
    if (o < 0) continue;
    const auto [it, added] = best.emplace(o, i);
    if (!added && background((*boxes)[i]) < background((*boxes)[it->second])) it->second = i;
  }
  int duplicates = 0;
  for (size_t i = 0; i < boxes->size(); ++i) {
    RecognitionRecording::Box& b = (*boxes)[i];
    if (b.object < 0 || best.at(b.object) == i || b.multi.log_p.empty()) continue;
    const double overlap = shareInside(b.multi.box, (*boxes)[best.at(b.object)].multi.box);
    if (!(overlap > 0)) continue;  // another part of the object, beside the kept box
    scaleObjectClasses(&b.multi.log_p, std::max(kMinLogProb, -overlap * overlap / kDuplicateSigma));
    ++duplicates;
  }
  return duplicates;
}

nlohmann::json objectMapSummary(const ObjectMapEngine& engine) {
  const std::vector<std::string>& classes = engine.classes();
  int objects = 0, labelled = 0;
  size_t best_union = 0, best_largest = 0;
  int best_objects = 0;
  int32_t best_segment = -1;
  for (const auto& [id, seg] : engine.segments()) {
    std::set<VoxelKey> all;
    size_t largest = 0;
    for (const auto& [oid, o] : seg->table.objects()) {
      ++objects;
      labelled += o.label >= 0 && static_cast<size_t>(o.label) < classes.size() &&
                  classes[static_cast<size_t>(o.label)] != kBackgroundClass;
      std::set<VoxelKey> own;
      for (int32_t c : o.candidates) {
        const auto& v = seg->table.candidates().at(c).voxels;
        own.insert(v.begin(), v.end());
      }
      largest = std::max(largest, own.size());
      all.insert(own.begin(), own.end());
    }
    if (all.size() > best_union) {
      best_union = all.size();
      best_largest = largest;
      best_objects = static_cast<int>(seg->table.objects().size());
      best_segment = id;
    }
  }
  nlohmann::json j;
  j["segments"] = engine.segments().size();
  j["objects"] = objects;
  j["labelled_objects"] = labelled;
  j["main_segment"] = best_segment;
  j["main_segment_objects"] = best_objects;
  j["main_segment_object_voxels"] = best_union;
  j["largest_object_voxels"] = best_largest;
  j["largest_object_share"] = percentOrNull(static_cast<double>(best_largest), static_cast<double>(best_union));
  return j;
}

// ---- A sequence ------------------------------------------------------------------------------

RecognitionRecording readRecognitionRecording(const std::string& log_path, const Channels& ch,
                                              const ObjectMapOptions& options) {
  RecognitionRecording run;
  {
    // Replaying the object map costs a map rebuild per full cloud: only for logs with DETECTIONS.
    LogReader scan(log_path);
    bool any = false;
    while (auto r = scan.next())
      if (r->channel == ch.detections) {
        any = true;
        break;
      }
    if (!any) return run;
  }
  MultiViewLabeller labeller(options);
  LogReader reader(log_path);
  object_map_t node_map;
  bool have_node_map = false;
  while (auto r = reader.next()) {
    if (r->channel == ch.object_map) {
      have_node_map = decodeRecord(*r, &node_map) || have_node_map;
    } else if (r->channel == ch.camera_info) {
      camera_info_t m;
      if (decodeRecord(*r, &m)) labeller.onCameraInfo(m);
    } else if (r->channel == ch.slam_map) {
      point_cloud_t m;
      if (decodeRecord(*r, &m)) labeller.onMap(m);
    } else if (r->channel == ch.slam_pose) {
      pose_t m;
      if (decodeRecord(*r, &m)) labeller.onPose(m);
    } else if (r->channel == ch.proposals) {
      proposals_t m;
      if (decodeRecord(*r, &m)) labeller.onProposals(m);
    } else if (r->channel == ch.detections) {
      detections_t m;
      if (!decodeRecord(*r, &m)) continue;
      labeller.onDetections(m);
      if (run.classes.empty()) run.classes = m.class_names;
      auto& boxes = run.frames[m.seq];
      boxes.clear();
      const size_t nb = std::min({m.boxes.size(), m.candidate_ids.size(), m.log_prob.size()});
      for (size_t i = 0; i < nb; ++i) {
        RecognitionRecording::Box b;
        b.single.box = {m.boxes[i].x, m.boxes[i].y, m.boxes[i].w, m.boxes[i].h};
        // Classes by name in the first message's order (one model per run).
        b.single.log_p.assign(run.classes.size(), kNegInf);
        for (size_t k = 0; k < run.classes.size(); ++k)
          for (size_t n = 0; n < m.class_names.size() && n < m.log_prob[i].size(); ++n)
            if (m.class_names[n] == run.classes[k]) b.single.log_p[k] = m.log_prob[i][n];
        b.map_id = m.map_id;
        b.candidate = m.candidate_ids[i];
        b.multi.box = b.single.box;
        boxes.push_back(std::move(b));
      }
    }
  }
  if (run.classes.empty()) return run;
  // The labels at the end of the sequence.
  struct Label {
    std::vector<double> log_p;
    bool from_object = false;
    int32_t object = -1;
  };
  std::map<std::pair<int32_t, int32_t>, Label> cache;  // (map, candidate) -> its label
  for (auto& [seq, boxes] : run.frames)
    for (auto& b : boxes) {
      auto it = cache.find({b.map_id, b.candidate});
      if (it == cache.end()) {
        Label l;
        l.log_p = labeller.logPosterior(b.map_id, b.candidate, run.classes, &l.from_object);
        const Object* o = labeller.engine().objectOfCandidate(b.map_id, b.candidate);
        l.object = o && l.from_object ? o->id : -1;
        it = cache.emplace(std::make_pair(b.map_id, b.candidate), std::move(l)).first;
      }
      b.fused.box = b.single.box;
      b.fused.log_p = it->second.log_p;
      b.multi.label = argmaxOf(b.fused.log_p);
      b.multi_from_object = it->second.from_object;
      b.object = it->second.object;
    }
  scoreMultiView(&run.frames);
  for (auto& [seq, boxes] : run.frames) run.duplicates += demoteDuplicateBoxes(&boxes);
  run.objects = static_cast<int>(labeller.engine().numObjects());
  run.object_map = objectMapSummary(labeller.engine());
  run.candidates = static_cast<int>(labeller.engine().numCandidates());
  if (have_node_map) {
    // The node fused the same messages in lockstep: the replay must give its objects (labels,
    // views and voxels).
    auto summary = [](const object_map_t& m) {
      std::vector<std::tuple<std::string, int32_t, int32_t>> s;
      for (const auto& o : m.objects) s.emplace_back(o.label, o.num_views, o.num_voxels);
      std::sort(s.begin(), s.end());
      return s;
    };
    run.matches_node = summary(labeller.engine().objectMap()) == summary(node_map) ? 1 : 0;
    if (!run.matches_node)
      spdlog::warn("{}: the replayed object map differs from the objectmap node's last OBJECT_MAP ({} / {} objects)",
                   log_path, run.objects, node_map.num_objects);
  }
  if (labeller.refused() > 0) spdlog::warn("{}: the object map refused {} messages", log_path, labeller.refused());
  return run;
}

std::vector<std::string> evaluatedClasses(const std::vector<std::string>& model_classes,
                                          const SequenceFolder& sequence) {
  std::vector<std::string> out;
  for (const auto& c : model_classes) {
    if (c == kBackgroundClass) continue;
    const auto& listed = sequence.info().classes;
    if (std::find(listed.begin(), listed.end(), c) != listed.end()) out.push_back(c);
  }
  return out;
}

RecognitionResult scoreRecognition(const RecognitionRecording& run, const SequenceFolder& seq,
                                   const RecognitionEvalOptions& o) {
  RecognitionResult r;
  r.classes = evaluatedClasses(run.classes, seq);
  r.single = emptyScores(r.classes);
  r.multi = emptyScores(r.classes);
  r.fused = emptyScores(r.classes);
  if (r.classes.empty()) return r;
  std::map<int, std::vector<GroundTruthBox>> truth;
  if (seq.hasBoxes())
    for (const auto& b : seq.boxes()) truth[b.frame].push_back(b);
  static const std::vector<GroundTruthBox> no_truth;
  const int stride = std::max(1, o.stride);
  for (int f = 0; f < static_cast<int>(seq.size()); f += stride) {
    std::vector<LabelledBox> single, multi, fused;
    if (auto it = run.frames.find(f); it != run.frames.end())
      for (const auto& b : it->second) {
        single.push_back(b.single);
        multi.push_back(b.multi);
        fused.push_back(b.fused);
        r.multi.fallback_boxes += !b.multi_from_object;
      }
    const auto t = truth.find(f);
    const std::vector<GroundTruthBox>& gt = t == truth.end() ? no_truth : t->second;
    scoreFrame(run.classes, single, gt, o.iou, &r.single);
    scoreFrame(run.classes, multi, gt, o.iou, &r.multi);
    scoreFrame(run.classes, fused, gt, o.iou, &r.fused);
  }
  return r;
}

}  // namespace slamaware
