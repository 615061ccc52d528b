#include "tools/eval/recognition_metrics.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <opencv2/imgproc.hpp>
#include <set>
#include <tuple>

#include "common/bus/log_reader.h"
#include "common/geometry.h"
#include "common/image_codec.h"
#include "procs/objectmap/frame_labels.h"
#include "procs/objectmap/object_map.h"
#include "tools/eval/plot.h"

namespace slamaware {

using namespace objectmap;

namespace {

constexpr double kNegInf = -std::numeric_limits<double>::infinity();

nlohmann::json percentOrNull(double num, double den) {
  return den > 0 ? nlohmann::json(100.0 * num / den) : nlohmann::json(nullptr);
}

nlohmann::json numberOrNull(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

int argmaxOf(const std::vector<double>& v) {
  int best = -1;
  for (size_t i = 0; i < v.size(); ++i)
    if (!std::isnan(v[i]) && (best < 0 || v[i] > v[static_cast<size_t>(best)]))
      best = static_cast<int>(i);
  return best;
}

// log(p / (1 - p)) of class k from log-probabilities of all classes: log p_k - log sum_{j != k}
// p_j. Monotone in p_k, so it ranks boxes as p_k does, but without the ties that rounding makes of
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

}  // namespace

// ---- Average precision ------------------------------------------------------------------------

double averagePrecision(std::vector<ScoredDetection> d, int num_truth,
                        std::vector<PrPoint>* curve) {
  if (curve) curve->clear();
  if (num_truth <= 0) return std::numeric_limits<double>::quiet_NaN();
  std::sort(d.begin(), d.end(),
            [](const ScoredDetection& a, const ScoredDetection& b) { return a.score > b.score; });
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

void scoreFrame(const std::vector<std::string>& model_classes,
                const std::vector<LabelledBox>& boxes, const std::vector<GroundTruthBox>& truth,
                double iou_threshold, RecognitionScores* s) {
  ++s->frames;
  s->boxes += static_cast<int>(boxes.size());
  const auto background =
      std::find(model_classes.begin(), model_classes.end(), std::string(kBackgroundClass));
  const int bg =
      background == model_classes.end() ? -1 : static_cast<int>(background - model_classes.begin());
  std::vector<int> label(boxes.size());
  for (size_t i = 0; i < boxes.size(); ++i)
    label[i] = boxes[i].label >= 0 ? boxes[i].label : argmaxOf(boxes[i].log_p);
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
      tally.boxed += std::any_of(boxes.begin(), boxes.end(), [&](const LabelledBox& b) {
        return iou(b.box, truth_boxes[g]) >= iou_threshold;
      });
    if (it == model_classes.end()) continue;  // the model cannot say it: no detections
    const size_t k = static_cast<size_t>(it - model_classes.begin());
    std::vector<size_t> order(boxes.size());
    std::iota(order.begin(), order.end(), 0);
    auto score = [&](size_t i) { return logOdds(boxes[i].log_p, k); };
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return score(a) > score(b); });
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
}

nlohmann::json recognitionSection(const RecognitionScores& s) {
  nlohmann::json j;
  j["per_class"] = nlohmann::json::object();
  double ap_sum = 0, boxed_sum = 0;
  int ap_classes = 0, truth = 0, tp = 0, boxed = 0;
  for (const auto& [cls, t] : s.classes) {
    const double ap = averagePrecision(t.ranked, t.truth);
    if (std::isfinite(ap))
      ap_sum += ap, boxed_sum += static_cast<double>(t.boxed) / t.truth, ++ap_classes;
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
  // What the boxes allow: a ground-truth box no box overlaps at the threshold is missed whatever
  // the labels, so a class's AP is at most its share of boxed ground truth, and the mAP at most
  // their mean.
  j["boxed"] = percentOrNull(boxed, truth);
  j["mAP_bound"] =
      ap_classes > 0 ? nlohmann::json(100.0 * boxed_sum / ap_classes) : nlohmann::json(nullptr);
  j["classes_with_ground_truth"] = ap_classes;
  j["frames_evaluated"] = s.frames;
  j["boxes"] = s.boxes;
  j["ground_truth_boxes"] = truth;
  nlohmann::json d;
  d["boxes_on_objects"] = s.boxes_on_objects;
  d["accuracy_on_objects"] = percentOrNull(s.correct_on_objects, s.boxes_on_objects);
  d["background_on_objects"] = percentOrNull(s.background_on_objects, s.boxes_on_objects);
  d["boxes_on_distractors"] = s.boxes_on_distractors;
  d["background_on_distractors"] =
      percentOrNull(s.background_on_distractors, s.boxes_on_distractors);
  d["boxes_elsewhere"] = s.boxes_elsewhere;
  d["background_elsewhere"] = percentOrNull(s.background_elsewhere, s.boxes_elsewhere);
  d["confusion"] = s.confusion;
  j["diagnostics"] = d;
  return j;
}

void drawPrCurves(const RecognitionScores& single, const RecognitionScores& online,
                  const RecognitionScores& final, const std::string& title,
                  const std::string& path) {
  std::vector<std::string> classes;
  for (const auto& [cls, t] : single.classes)
    if (t.truth > 0) classes.push_back(cls);
  if (classes.empty()) return;
  const int cols = std::min<int>(3, static_cast<int>(classes.size()));
  const int rows = (static_cast<int>(classes.size()) + cols - 1) / cols;
  const int pw = 420, ph = 340, header = 34;
  cv::Mat img(header + rows * ph, cols * pw, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::putText(img, title, cv::Point(12, 22), cv::FONT_HERSHEY_SIMPLEX, 0.55, plot_colour::kBlack, 1,
              cv::LINE_AA);
  const std::vector<double> ticks{0, 20, 40, 60, 80, 100};
  for (size_t n = 0; n < classes.size(); ++n) {
    const std::string& cls = classes[n];
    const cv::Rect area(static_cast<int>(n % cols) * pw, header + static_cast<int>(n / cols) * ph,
                        pw, ph);
    PlotPanel panel(
        img, area, PlotAxis{0, 100, false, ticks, "recall (%)"},
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
        panel.curve({{100.0 * t.labelled_tp / t.truth, 100.0 * t.labelled_tp / t.labelled}}, colour,
                    "", 4);
    };
    draw(single, plot_colour::kBlue, "single view");
    draw(online, plot_colour::kOrange, "multi-view online");
    draw(final, plot_colour::kRed, "multi-view final");
  }
  writeImage(path, img);
}

// ---- What the processes published ----------------------------------------------------------

ObjectMapOutputs readObjectMapOutputs(const std::string& log_path, const Channels& ch) {
  ObjectMapOutputs out;
  LogReader reader(log_path);
  while (auto r = reader.next()) {
    if (r->channel == ch.object_detections) {
      object_detections_t m;
      if (decodeRecord(*r, &m)) out.frames[m.seq] = std::move(m);
    } else if (r->channel == ch.object_map) {
      object_map_t m;
      if (decodeRecord(*r, &m)) {
        out.last_map = std::move(m);
        out.have_map = true;
      }
    }
  }
  return out;
}

ObjectMapOutputs rerunObjectMap(const std::string& log_path, const Channels& ch,
                                const ObjectMapOptions& options) {
  ObjectMapOutputs out;
  ObjectMapEngine engine(options);
  LogReader reader(log_path);
  std::string why;  // refusals are the node's status counters; the outputs are the same either way
  // In the node's lockstep order (LockstepInputs), whatever the order the logger received them in.
  LockstepInputs inputs;
  const LockstepInputs::Handler handle = [&](const LockstepInputs::Input& in) {
    if (const auto* m = std::get_if<point_cloud_t>(&in)) engine.onMap(*m, &why);
    if (const auto* m = std::get_if<pose_t>(&in)) engine.onPose(*m, &why);
    if (const auto* m = std::get_if<proposals_t>(&in)) engine.onProposals(*m, &why);
  };
  while (auto r = reader.next()) {
    if (r->channel == ch.camera_info) {
      camera_info_t m;
      if (decodeRecord(*r, &m)) engine.onCameraInfo(m, &why);
    } else if (r->channel == ch.slam_map) {
      point_cloud_t m;
      if (decodeRecord(*r, &m)) inputs.add(m.seq, std::move(m), handle);
    } else if (r->channel == ch.slam_pose) {
      pose_t m;
      if (decodeRecord(*r, &m)) inputs.add(m.seq, m, handle);
    } else if (r->channel == ch.proposals) {
      proposals_t m;
      if (decodeRecord(*r, &m)) inputs.add(m.seq, std::move(m), handle);
    } else if (r->channel == ch.detections) {
      detections_t m;
      if (!decodeRecord(*r, &m)) continue;
      inputs.releaseUpTo(m.seq, handle);
      engine.onDetections(m, &why);
      // As the lockstep node publishes them (objectmap_main.cpp).
      out.frames[m.seq] = engine.frameDetections(m);
      out.last_map = engine.objectMap();
      out.last_map.utime = m.utime;
      out.last_map.seq = m.seq;
      out.have_map = true;
    }
  }
  return out;
}

nlohmann::json objectMapSummary(const object_map_t& map) {
  int labelled = 0;
  std::map<int32_t, std::pair<int64_t, int64_t>> segments;  // map id -> (voxels, largest)
  std::map<int32_t, int> per_segment;
  for (const auto& o : map.objects) {
    labelled += !o.label.empty() && o.label != kBackgroundClass;
    auto& [sum, largest] = segments[o.map_id];
    sum += o.num_voxels;
    largest = std::max<int64_t>(largest, o.num_voxels);
    ++per_segment[o.map_id];
  }
  int32_t main = -1;
  for (const auto& [id, v] : segments)
    if (main < 0 || v.first > segments[main].first) main = id;
  nlohmann::json j;
  j["segments"] = segments.size();
  j["objects"] = map.objects.size();
  j["labelled_objects"] = labelled;
  j["main_segment"] = main;
  j["main_segment_objects"] = main >= 0 ? per_segment[main] : 0;
  j["main_segment_object_voxels"] = main >= 0 ? segments[main].first : 0;
  j["largest_object_voxels"] = main >= 0 ? segments[main].second : 0;
  j["largest_object_share"] = main >= 0 ? percentOrNull(static_cast<double>(segments[main].second),
                                                        static_cast<double>(segments[main].first))
                                        : nlohmann::json(nullptr);
  return j;
}

// ---- A sequence ------------------------------------------------------------------------------

namespace {

// Row `row` of a message's per-class values in `classes`' order (by name; -inf where absent).
std::vector<double> byName(const std::vector<std::string>& names, const std::vector<float>& row,
                           const std::vector<std::string>& classes) {
  std::vector<double> out(classes.size(), kNegInf);
  for (size_t k = 0; k < classes.size(); ++k)
    for (size_t n = 0; n < names.size() && n < row.size(); ++n)
      if (names[n] == classes[k]) out[k] = row[n];
  return out;
}

int indexOfName(const std::vector<std::string>& classes, const std::string& name) {
  const auto it = std::find(classes.begin(), classes.end(), name);
  return it == classes.end() ? -1 : static_cast<int>(it - classes.begin());
}

}  // namespace

RecognitionRecording readRecognitionRecording(const std::string& log_path, const Channels& ch,
                                              const ObjectMapOutputs& outputs) {
  RecognitionRecording run;
  std::map<int32_t, const object_t*> final_objects;
  for (const auto& o : outputs.last_map.objects) final_objects[o.id] = &o;
  LogReader reader(log_path);
  while (auto r = reader.next()) {
    if (r->channel != ch.detections) continue;
    detections_t m;
    if (!decodeRecord(*r, &m)) continue;
    if (run.classes.empty()) run.classes = m.class_names;  // one model per run: its order
    const auto od = outputs.frames.find(m.seq);
    const bool have = od != outputs.frames.end() && od->second.utime == m.utime &&
                      od->second.boxes.size() == m.boxes.size();
    // (The frame a map starts from is answered twice, empty and then late: its last outputs
    // count, and an empty DETECTIONS has nothing to score.)
    run.frames_without_object_detections += !have && !m.boxes.empty();
    auto& boxes = run.frames[m.seq];
    boxes.clear();
    const size_t nb = std::min({m.boxes.size(), m.candidate_ids.size(), m.log_prob.size()});
    for (size_t i = 0; i < nb; ++i) {
      RecognitionRecording::Box b;
      b.single.box = {m.boxes[i].x, m.boxes[i].y, m.boxes[i].w, m.boxes[i].h};
      b.single.log_p = byName(m.class_names, m.log_prob[i], run.classes);
      b.map_id = m.map_id;
      b.candidate = m.candidate_ids[i];
      b.carried = i < m.classified_seq.size() && m.classified_seq[i] != m.seq;
      b.online.box = b.final.box = b.single.box;
      if (have) {
        const object_detections_t& d = od->second;
        b.object = d.object_ids[i];
        b.role = d.roles[i];
        ++run.roles[b.role];
        b.online.log_p = byName(d.class_names, d.log_score[i], run.classes);
        b.online.label = indexOfName(run.classes, d.labels[i]);
        b.final = b.online;
        const auto fo = final_objects.find(b.object);
        if (b.object >= 0 && fo != final_objects.end()) {
          // The last OBJECT_MAP's posterior of the object, with the weights the map gave this box.
          const std::vector<double> post =
              byName(outputs.last_map.class_names, fo->second->log_posterior, run.classes);
          const std::vector<double> weight = byName(d.class_names, d.log_weight[i], run.classes);
          b.final.log_p = post;
          scaleObjectClasses(&b.final.log_p, weight);
          b.final.label = indexOfName(run.classes, fo->second->label);
        } else {
          run.final_without_object += b.object >= 0;
        }
      } else {
        // No OBJECT_DETECTIONS (an incomplete run): the box counts with nothing said of it.
        b.online.log_p = b.final.log_p = std::vector<double>(run.classes.size(), kNegInf);
        if (!b.online.log_p.empty()) b.online.log_p.back() = b.final.log_p.back() = 0;
      }
      boxes.push_back(std::move(b));
    }
  }
  run.objects = static_cast<int>(outputs.last_map.objects.size());
  run.object_map = objectMapSummary(outputs.last_map);
  if (run.frames_without_object_detections > 0)
    spdlog::warn("{}: {} DETECTIONS without their OBJECT_DETECTIONS", log_path,
                 run.frames_without_object_detections);
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

std::vector<int> framesToScore(const SequenceFolder& sequence, int stride) {
  const int step = sequence.hasGroundTruth() ? std::max(1, stride) : 1;
  std::vector<int> frames;
  for (int f = 0; f < static_cast<int>(sequence.size()); f += step) frames.push_back(f);
  return frames;
}

RecognitionResult scoreRecognition(const RecognitionRecording& run, const SequenceFolder& seq,
                                   const RecognitionEvalOptions& o) {
  RecognitionResult r;
  r.classes = evaluatedClasses(run.classes, seq);
  r.single = emptyScores(r.classes);
  r.online = emptyScores(r.classes);
  r.final = emptyScores(r.classes);
  if (r.classes.empty()) return r;
  std::map<int, std::vector<GroundTruthBox>> truth;
  if (seq.hasBoxes())
    for (const auto& b : seq.boxes()) truth[b.frame].push_back(b);
  static const std::vector<GroundTruthBox> no_truth;
  for (const int f : framesToScore(seq, o.stride)) {
    std::vector<LabelledBox> single, online, final;
    if (auto it = run.frames.find(f); it != run.frames.end())
      for (const auto& b : it->second) {
        single.push_back(b.single);
        online.push_back(b.online);
        final.push_back(b.final);
      }
    const auto t = truth.find(f);
    const std::vector<GroundTruthBox>& gt = t == truth.end() ? no_truth : t->second;
    scoreFrame(run.classes, single, gt, o.iou, &r.single);
    scoreFrame(run.classes, online, gt, o.iou, &r.online);
    scoreFrame(run.classes, final, gt, o.iou, &r.final);
  }
  return r;
}

}  // namespace slamaware
