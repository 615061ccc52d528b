// The single_view / multi_view_online / multi_view_final sections of the eval report: VOC all-point
// AP on hand-computed examples (ties, no ground truth), the matching of boxes to ground truth (one
// match per ground-truth box, distractors), pooling over sequences, the report keys of
// docs/architecture.md §7, and the multi-view sections scored from what the object map published
// (and nothing else).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <lcm/lcm-cpp.hpp>

#include "procs/objectmap/object_map.h"
#include "tests/eval/eval_test_data.h"
#include "tests/objectmap/synthetic_world.h"
#include "tests/support/test_support.h"
#include "tools/eval/recognition_metrics.h"

using namespace slamaware;
using namespace slamaware::objectmap;
using test::makeSequence;
using test::writeEvent;
namespace fs = std::filesystem;

namespace {

// The paper's plain sum of log p and its posterior (the labels below are computed by hand with it).
ObjectMapOptions plainSum() {
  ObjectMapOptions o;
  o.objectness_weights = false;
  o.posterior_views_exponent = 0;
  return o;
}

const std::vector<std::string> kModel = {"cap", "coffee_mug", "background"};

LabelledBox box(double x, double y, double w, double h, std::vector<double> p) {
  LabelledBox b;
  b.box = {x, y, w, h};
  for (double v : p) b.log_p.push_back(std::log(v));
  return b;
}

GroundTruthBox truth(int frame, double x, double y, double w, double h, const std::string& cls) {
  GroundTruthBox t;
  t.frame = frame;
  t.x = x, t.y = y, t.w = w, t.h = h;
  t.cls = cls;
  t.instance = cls + "_1";
  return t;
}

std::vector<ScoredDetection> hits(std::initializer_list<std::pair<double, bool>> list) {
  std::vector<ScoredDetection> d;
  for (const auto& [s, tp] : list) d.push_back({s, tp});
  return d;
}

std::vector<float> logs(std::initializer_list<double> p) {
  std::vector<float> out;
  for (double v : p) out.push_back(static_cast<float>(std::log(v)));
  return out;
}

detections_t detections(int32_t seq, int32_t map_id, const std::vector<std::string>& classes,
                        std::vector<std::pair<int32_t, std::vector<float>>> boxes, float x = 100) {
  detections_t d{};
  d.utime = 1000000 + seq * 33333;
  d.seq = seq;
  d.map_id = map_id;
  d.class_names = classes;
  d.num_classes = static_cast<int32_t>(classes.size());
  for (auto& [cid, row] : boxes) {
    box_t b{};
    b.x = x, b.y = 100, b.w = 50, b.h = 50;
    d.boxes.push_back(b);
    d.candidate_ids.push_back(cid);
    d.classified_seq.push_back(seq);
    d.log_prob.push_back(row);
    x += 100;
  }
  d.num_boxes = static_cast<int32_t>(d.boxes.size());
  return d;
}

}  // namespace

// ---- Average precision ------------------------------------------------------------------------

// 5 detections in score order TP, FP, TP, FP, FP against 3 ground-truth boxes:
// precision 1, 1/2, 2/3, 1/2, 2/5 at recall 1/3, 1/3, 2/3, 2/3, 2/3; interpolated precision is 1 up
// to recall 1/3 and 2/3 up to 2/3, and 0 beyond (the third box is never found):
// AP = 1/3 * 1 + 1/3 * 2/3 = 5/9.
TEST(AveragePrecision, HandComputedVocAllPointExample) {
  std::vector<PrPoint> curve;
  const double ap = averagePrecision(
      hits({{0.5, false}, {0.9, true}, {0.6, false}, {0.7, true}, {0.8, false}}), 3, &curve);
  EXPECT_NEAR(ap, 5.0 / 9.0, 1e-12);
  ASSERT_EQ(curve.size(), 5u);
  EXPECT_NEAR(curve[0].precision, 1.0, 1e-12);
  EXPECT_NEAR(curve[2].recall, 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(curve[2].precision, 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(curve[4].precision, 0.4, 1e-12);
  // Every box found, the best first: AP 1. A false positive above all of them: the precision at
  // every recall is the precision after it is passed.
  EXPECT_NEAR(averagePrecision(hits({{0.9, true}, {0.8, true}}), 2), 1.0, 1e-12);
  EXPECT_NEAR(averagePrecision(hits({{0.99, false}, {0.9, true}, {0.8, true}}), 2), 2.0 / 3.0,
              1e-12);
}

// Equal scores are one step of the curve, so their order does not matter: a TP and an FP tied at
// 0.8 give 5/9 (recall 1/3 at precision 1, then 2/3 at precision 2/3) in either order, where the
// TP taken first alone would give 2/3. A TP tied with two FPs is one step to recall 1/2 at
// precision 1/3, wherever the TP is among them.
TEST(AveragePrecision, TiedScoresAreOneStepWhateverTheirOrder) {
  const double a =
      averagePrecision(hits({{0.9, true}, {0.8, true}, {0.8, false}, {0.5, false}}), 3);
  const double b =
      averagePrecision(hits({{0.9, true}, {0.8, false}, {0.8, true}, {0.5, false}}), 3);
  EXPECT_NEAR(a, 5.0 / 9.0, 1e-12);
  EXPECT_NEAR(b, 5.0 / 9.0, 1e-12);
  EXPECT_NEAR(averagePrecision(hits({{0.9, true}, {0.81, true}, {0.8, false}, {0.5, false}}), 3),
              2.0 / 3.0, 1e-12);
  const double c = averagePrecision(hits({{0.7, true}, {0.7, false}, {0.7, false}}), 2);
  const double d = averagePrecision(hits({{0.7, false}, {0.7, false}, {0.7, true}}), 2);
  EXPECT_NEAR(c, 1.0 / 6.0, 1e-12);
  EXPECT_EQ(c, d);
}

TEST(AveragePrecision, AClassWithoutGroundTruthHasNoApAndOneWithoutDetectionsHasZero) {
  EXPECT_TRUE(std::isnan(averagePrecision(hits({{0.9, false}}), 0)));
  EXPECT_TRUE(std::isnan(averagePrecision({}, 0)));
  EXPECT_EQ(averagePrecision({}, 4), 0.0);
  EXPECT_EQ(averagePrecision(hits({{0.9, false}, {0.3, false}}), 4), 0.0);
}

// ---- Matching -------------------------------------------------------------------------------

// Two boxes on one cap: the better scored one matches it, the other is a false positive (it may
// not match a box that is already matched), both for AP and at the argmax label.
TEST(RecognitionMatching, ADetectionCannotMatchAnAlreadyMatchedBox) {
  RecognitionScores s = emptyScores({"cap", "coffee_mug"});
  scoreFrame(kModel,
             {box(102, 102, 50, 50, {0.7, 0.2, 0.1}), box(100, 100, 50, 50, {0.8, 0.1, 0.1})},
             {truth(0, 100, 100, 50, 50, "cap")}, 0.5, &s);
  const ClassTally& cap = s.classes.at("cap");
  EXPECT_EQ(cap.truth, 1);
  ASSERT_EQ(cap.ranked.size(), 2u);
  EXPECT_GT(cap.ranked[0].score, cap.ranked[1].score);
  EXPECT_TRUE(cap.ranked[0].true_positive) << "the higher p(cap) is matched";
  EXPECT_FALSE(cap.ranked[1].true_positive) << "the box is already matched";
  EXPECT_EQ(cap.labelled, 2);
  EXPECT_EQ(cap.labelled_tp, 1);
  EXPECT_EQ(s.classes.at("coffee_mug").truth, 0);
  EXPECT_EQ(s.classes.at("coffee_mug").ranked.size(), 2u)
      << "every box is a detection of every class";
  EXPECT_EQ(s.boxes_on_objects, 2);
  EXPECT_EQ(s.correct_on_objects, 2);
  const nlohmann::json j = recognitionSection(s);
  EXPECT_DOUBLE_EQ(j["per_class"]["cap"]["AP"].get<double>(), 100.0);
  EXPECT_DOUBLE_EQ(j["per_class"]["cap"]["precision"].get<double>(), 50.0);
  EXPECT_DOUBLE_EQ(j["per_class"]["cap"]["recall"].get<double>(), 100.0);
}

// A box is matched to the unmatched box of its class that it overlaps most
// (docs/architecture.md §7: "an unmatched ground-truth box"), so the second box of two overlapping
// caps is found by the second detection even though that detection overlaps the first cap more.
TEST(RecognitionMatching, TheUnmatchedBoxOverlappingMostIsTaken) {
  RecognitionScores s = emptyScores({"cap"});
  scoreFrame(kModel,
             {box(120, 100, 50, 50, {0.9, 0.05, 0.05}), box(115, 100, 50, 50, {0.8, 0.1, 0.1})},
             {truth(0, 100, 100, 50, 50, "cap"), truth(0, 120, 100, 50, 50, "cap")}, 0.5, &s);
  const ClassTally& cap = s.classes.at("cap");
  EXPECT_EQ(cap.truth, 2);
  EXPECT_TRUE(cap.ranked[0].true_positive);
  EXPECT_TRUE(cap.ranked[1].true_positive) << "IoU 0.54 with the free cap";
  EXPECT_EQ(cap.labelled_tp, 2);
  // Below the threshold nothing matches.
  RecognitionScores t = emptyScores({"cap"});
  scoreFrame(kModel, {box(140, 100, 50, 50, {0.9, 0.05, 0.05})},
             {truth(0, 100, 100, 50, 50, "cap")}, 0.5, &t);
  EXPECT_FALSE(t.classes.at("cap").ranked[0].true_positive) << "IoU 10/90";
  EXPECT_EQ(t.boxes_elsewhere, 1);
}

// Ground-truth boxes of classes that are not evaluated (the scene's distractors, or a model class
// the sequence does not list) are not ground truth: they are never missed, and a box on one that is
// called a cap is a false positive of cap.
TEST(RecognitionMatching, ADistractorIsNotGroundTruth) {
  RecognitionScores s =
      emptyScores({"cap"});  // coffee_mug: a model class this sequence does not list
  scoreFrame(kModel,
             {box(300, 100, 60, 40, {0.9, 0.05, 0.05}), box(300, 100, 60, 41, {0.1, 0.1, 0.8}),
              box(400, 100, 50, 50, {0.2, 0.7, 0.1}), box(100, 100, 50, 50, {0.6, 0.3, 0.1})},
             {truth(0, 300, 100, 60, 40, "calculator"), truth(0, 400, 100, 50, 50, "coffee_mug"),
              truth(0, 100, 100, 50, 50, "cap")},
             0.5, &s);
  EXPECT_EQ(s.classes.size(), 1u);
  const ClassTally& cap = s.classes.at("cap");
  EXPECT_EQ(cap.truth, 1) << "only the cap is ground truth";
  EXPECT_EQ(cap.labelled, 2);
  EXPECT_EQ(cap.labelled_tp, 1) << "the cap on the calculator is a false positive";
  int tps = 0;
  for (const auto& d : cap.ranked) tps += d.true_positive;
  EXPECT_EQ(tps, 1);
  EXPECT_FALSE(cap.ranked[0].true_positive)
      << "p(cap) 0.9 on the calculator ranks first and is false";
  EXPECT_EQ(s.boxes_on_distractors, 3);
  EXPECT_EQ(s.background_on_distractors, 1);
  EXPECT_EQ(s.boxes_on_objects, 1);
  const nlohmann::json j = recognitionSection(s);
  EXPECT_DOUBLE_EQ(j["recall"].get<double>(), 100.0);
  EXPECT_DOUBLE_EQ(j["per_class"]["cap"]["precision"].get<double>(), 50.0);
  EXPECT_NEAR(j["per_class"]["cap"]["AP"].get<double>(), 50.0, 1e-9);
}

// ---- The report section ----------------------------------------------------------------------

TEST(RecognitionSection, HasTheKeysOfDesignSection7InPercent) {
  RecognitionScores s = emptyScores({"cap", "coffee_mug"});
  scoreFrame(kModel,
             {box(100, 100, 50, 50, {0.8, 0.1, 0.1}), box(300, 300, 50, 50, {0.3, 0.6, 0.1})},
             {truth(0, 100, 100, 50, 50, "cap")}, 0.5, &s);
  scoreFrame(kModel, {}, {truth(5, 100, 100, 50, 50, "cap")}, 0.5,
             &s);  // a frame without boxes: a miss
  const nlohmann::json j = recognitionSection(s);
  for (const char* key : {"mAP", "recall", "per_class"}) EXPECT_TRUE(j.contains(key)) << key;
  ASSERT_TRUE(j["per_class"].is_object());
  for (const char* cls : {"cap", "coffee_mug"}) {
    ASSERT_TRUE(j["per_class"].contains(cls)) << cls;
    for (const char* key : {"AP", "precision", "recall"})
      EXPECT_TRUE(j["per_class"][cls].contains(key)) << key;
  }
  EXPECT_NEAR(j["per_class"]["cap"]["AP"].get<double>(), 50.0, 1e-9);
  EXPECT_DOUBLE_EQ(j["per_class"]["cap"]["recall"].get<double>(), 50.0);
  EXPECT_DOUBLE_EQ(j["per_class"]["cap"]["precision"].get<double>(), 100.0);
  // No ground truth: no AP, no recall, and not in the mAP; precision of the one box called a mug:
  // 0.
  EXPECT_TRUE(j["per_class"]["coffee_mug"]["AP"].is_null());
  EXPECT_TRUE(j["per_class"]["coffee_mug"]["recall"].is_null());
  EXPECT_DOUBLE_EQ(j["per_class"]["coffee_mug"]["precision"].get<double>(), 0.0);
  EXPECT_NEAR(j["mAP"].get<double>(), 50.0, 1e-9);
  EXPECT_DOUBLE_EQ(j["recall"].get<double>(), 50.0);
  EXPECT_EQ(j["frames_evaluated"], 2);
  EXPECT_EQ(j["ground_truth_boxes"], 2);
}

// A ground-truth box that no box overlaps at the threshold is missed whatever the labels: the share
// of boxed ground truth bounds recall and AP, per class and (mean over classes) the mAP. Three
// caps: one boxed and found, one boxed but called background, one overlapped at IoU 0.33 only; and
// a frame without boxes. A mug nobody boxed makes the class bound 0.
TEST(RecognitionSection, TheBoxedShareBoundsRecallAndAp) {
  RecognitionScores s = emptyScores({"cap", "coffee_mug"});
  scoreFrame(kModel,
             {box(100, 100, 50, 50, {0.8, 0.1, 0.1}), box(300, 100, 50, 50, {0.1, 0.1, 0.8}),
              box(525, 100, 50, 50, {0.7, 0.2, 0.1})},
             {truth(0, 100, 100, 50, 50, "cap"), truth(0, 300, 100, 50, 50, "cap"),
              truth(0, 500, 100, 50, 50, "cap")},
             0.5, &s);
  scoreFrame(kModel, {},
             {truth(5, 100, 100, 50, 50, "cap"), truth(5, 300, 300, 40, 60, "coffee_mug")}, 0.5,
             &s);
  EXPECT_EQ(s.classes.at("cap").boxed, 2);
  EXPECT_EQ(s.classes.at("coffee_mug").boxed, 0);
  const nlohmann::json j = recognitionSection(s);
  EXPECT_DOUBLE_EQ(j["per_class"]["cap"]["boxed"].get<double>(), 50.0);
  EXPECT_DOUBLE_EQ(j["per_class"]["coffee_mug"]["boxed"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(j["boxed"].get<double>(), 40.0) << "2 of 5 ground-truth boxes";
  EXPECT_DOUBLE_EQ(j["mAP_bound"].get<double>(), 25.0) << "the mean of 50 and 0";
  // p(cap) 0.1 on the second cap still ranks it, after the partial box: AP 1/4 + 1/4 x 2/3 = 5/12.
  EXPECT_LE(j["per_class"]["cap"]["AP"].get<double>(),
            j["per_class"]["cap"]["boxed"].get<double>());
  EXPECT_NEAR(j["per_class"]["cap"]["AP"].get<double>(), 500.0 / 12.0, 1e-9);
  EXPECT_LE(j["mAP"].get<double>(), j["mAP_bound"].get<double>());
  EXPECT_DOUBLE_EQ(j["per_class"]["cap"]["recall"].get<double>(), 25.0)
      << "at the argmax label, 1 of 4";
  // Pooled over a suite, the counts add up.
  RecognitionScores suite;
  mergeRecognition(&suite, s);
  mergeRecognition(&suite, s);
  EXPECT_EQ(suite.classes.at("cap").boxed, 4);
  EXPECT_DOUBLE_EQ(recognitionSection(suite)["mAP_bound"].get<double>(), 25.0);
}

// The suite's AP is the AP of the pooled detections, not the mean of the sequences' APs:
// A: one cap found first (AP 1); B: a false positive above its cap (AP 1/2). Pooled: FP (B) 0.95,
// TP (A) 0.9, TP (B) 0.5 -> precision 2/3 up to recall 1: AP 2/3 (the mean would be 3/4).
TEST(RecognitionSection, TheSuiteIsScoredOnPooledDetections) {
  RecognitionScores a = emptyScores({"cap"}), b = emptyScores({"cap"});
  scoreFrame(kModel, {box(100, 100, 50, 50, {0.9, 0.05, 0.05})},
             {truth(0, 100, 100, 50, 50, "cap")}, 0.5, &a);
  scoreFrame(kModel,
             {box(300, 100, 50, 50, {0.95, 0.03, 0.02}), box(100, 100, 50, 50, {0.5, 0.3, 0.2})},
             {truth(0, 100, 100, 50, 50, "cap")}, 0.5, &b);
  EXPECT_NEAR(recognitionSection(a)["mAP"].get<double>(), 100.0, 1e-9);
  EXPECT_NEAR(recognitionSection(b)["mAP"].get<double>(), 50.0, 1e-9);
  RecognitionScores suite;
  mergeRecognition(&suite, a);
  mergeRecognition(&suite, b);
  const nlohmann::json j = recognitionSection(suite);
  EXPECT_NEAR(j["mAP"].get<double>(), 200.0 / 3.0, 1e-9);
  EXPECT_EQ(j["ground_truth_boxes"], 2);
  EXPECT_EQ(j["boxes"], 3);
}

// ---- Multi-view labels --------------------------------------------------------------------------

// ---- What the processes published ------------------------------------------------------------

namespace {

template <class Msg>
std::vector<uint8_t> bytes(const Msg& m) {
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

// One candidate seen in 3 frames: two views weakly say cap, one strongly says coffee_mug, so its
// object is a cap after frames 0 and 5 and a mug after frame 10 (0.5·0.5·0.05 < 0.4·0.4·0.9);
// candidate 6 is seen once, as background. Recorded as the lockstep node publishes: DETECTIONS,
// then the map's OBJECT_DETECTIONS and OBJECT_MAP of each frame. `edit` may change an
// OBJECT_DETECTIONS before it is written.
const std::vector<detections_t>& threeFrames() {
  static const std::vector<detections_t> messages = {
      detections(0, 1, kModel, {{5, logs({0.5, 0.4, 0.1})}, {6, logs({0.1, 0.1, 0.8})}}),
      detections(5, 1, kModel, {{5, logs({0.5, 0.4, 0.1})}}),
      detections(10, 1, kModel, {{5, logs({0.05, 0.9, 0.05})}})};
  return messages;
}

std::string recordThreeFrames(const std::string& path,
                              const std::function<void(object_detections_t&)>& edit = {}) {
  const Channels ch;
  ObjectMapEngine node(plainSum());
  lcm::LogFile log(path, "w");
  int64_t n = 0;
  for (const auto& d : threeFrames()) {
    std::string why;
    writeEvent(log, ch.detections, d, n++);
    EXPECT_TRUE(node.onDetections(d, &why)) << why;
    object_detections_t od = node.frameDetections(d);
    if (edit) edit(od);
    writeEvent(log, ch.object_detections, od, n++);
    object_map_t m = node.objectMap();
    m.utime = d.utime;
    m.seq = d.seq;
    writeEvent(log, ch.object_map, m, n++);
  }
  return path;
}

}  // namespace

// The multi-view sections score what the object map published: online, each box's published score
// and label at its frame (the object a cap until the mug's view came); final, its object's
// posterior in the last OBJECT_MAP (a mug, in every frame) with the weights the map published.
TEST(PublishedLabels, BoxesAreScoredAsTheObjectMapPublishedThem) {
  const std::string log = recordThreeFrames(test::tempDir("eval_published") + "/run.lcm");
  const Channels ch;
  const ObjectMapOutputs outputs = readObjectMapOutputs(log, ch);
  ASSERT_EQ(outputs.frames.size(), 3u);
  ASSERT_TRUE(outputs.have_map);
  const RecognitionRecording run = readRecognitionRecording(log, ch, outputs);
  ASSERT_EQ(run.classes, kModel);
  EXPECT_EQ(run.frames_without_object_detections, 0);
  EXPECT_EQ(run.objects, 2);
  const object_t* mug_object = nullptr;
  for (const auto& o : outputs.last_map.objects)
    if (std::find(o.candidate_ids.begin(), o.candidate_ids.end(), 5) != o.candidate_ids.end())
      mug_object = &o;
  ASSERT_NE(mug_object, nullptr) << "OBJECT_MAP names the candidates of each object";
  EXPECT_EQ(mug_object->label, "coffee_mug");
  for (int f : {0, 5, 10}) {
    const auto& b = run.frames.at(f)[0];
    const object_detections_t& od = outputs.frames.at(f);
    EXPECT_EQ(b.object, mug_object->id);
    EXPECT_EQ(b.role, object_detections_t::PRIMARY);
    for (size_t c = 0; c < 3; ++c)
      EXPECT_EQ(b.online.log_p[c], static_cast<double>(od.log_score[0][c]));
    EXPECT_EQ(b.online.label, f == 10 ? 1 : 0) << "frame " << f << ": what the map knew then";
    EXPECT_EQ(b.final.label, 1) << "frame " << f << ": the last map's label";
    for (size_t c = 0; c < 2; ++c)
      EXPECT_NEAR(b.final.log_p[c], mug_object->log_posterior[c] + od.log_weight[0][c], 1e-6);
    EXPECT_NEAR(
        std::exp(b.final.log_p[0]) + std::exp(b.final.log_p[1]) + std::exp(b.final.log_p[2]), 1.0,
        1e-6);
  }

  const std::string seq = makeSequence(
      "eval_published_seq", 11, {"cap", "coffee_mug"},
      {truth(0, 100, 100, 50, 50, "coffee_mug"), truth(5, 100, 100, 50, 50, "coffee_mug"),
       truth(10, 100, 100, 50, 50, "coffee_mug")});
  const RecognitionResult r =
      scoreRecognition(run, SequenceFolder::open(seq), RecognitionEvalOptions{});
  EXPECT_EQ(r.single.frames, 3) << "frames 0, 5, 10";
  EXPECT_EQ(r.single.classes.at("coffee_mug").labelled_tp, 1);
  EXPECT_EQ(r.online.classes.at("coffee_mug").labelled_tp, 1)
      << "frames 0 and 5 were labelled cap then";
  EXPECT_EQ(r.online.classes.at("cap").labelled, 2);
  EXPECT_EQ(r.final.classes.at("coffee_mug").labelled_tp, 3);
  EXPECT_NEAR(recognitionSection(r.final)["per_class"]["coffee_mug"]["recall"].get<double>(), 100.0,
              1e-9);
}

// The evaluator relabels nothing: a label or score changed in the recorded OBJECT_DETECTIONS is
// what it scores, and a DETECTIONS without its OBJECT_DETECTIONS counts as a box the map said
// nothing of.
TEST(PublishedLabels, TheEvaluatorScoresTheRecordedLabelsWhateverTheyAre) {
  const std::string dir = test::tempDir("eval_published_edit");
  const std::string log = recordThreeFrames(dir + "/edited.lcm", [](object_detections_t& od) {
    if (od.seq != 10) return;
    od.labels[0] = "cap";
    od.log_score[0] = logs({0.6, 0.3, 0.1});
  });
  const Channels ch;
  const RecognitionRecording run = readRecognitionRecording(log, ch, readObjectMapOutputs(log, ch));
  EXPECT_EQ(run.frames.at(10)[0].online.label, 0)
      << "the recorded label, not one of the evaluator's";
  EXPECT_NEAR(run.frames.at(10)[0].online.log_p[0], std::log(0.6), 1e-6);

  ObjectMapOutputs missing = readObjectMapOutputs(log, ch);
  missing.frames.erase(5);
  const RecognitionRecording gap = readRecognitionRecording(log, ch, missing);
  EXPECT_EQ(gap.frames_without_object_detections, 1);
  EXPECT_EQ(gap.frames.at(5)[0].role, -1);
  EXPECT_EQ(gap.frames.at(5)[0].online.log_p.back(), 0.0) << "no object said: background";
}

// Re-running the object map on a recording's inputs with the node's options gives the node's
// messages byte for byte (so option sweeps on recordings score what the node would publish), and
// other options give other messages.
TEST(PublishedLabels, ReRunningTheObjectMapGivesTheNodesMessages) {
  const std::string log = recordThreeFrames(test::tempDir("eval_rerun") + "/run.lcm");
  const Channels ch;
  const ObjectMapOutputs recorded = readObjectMapOutputs(log, ch);
  const ObjectMapOutputs again = rerunObjectMap(log, ch, plainSum());
  ASSERT_EQ(again.frames.size(), recorded.frames.size());
  for (const auto& [seq, m] : recorded.frames)
    EXPECT_EQ(bytes(again.frames.at(seq)), bytes(m)) << "seq " << seq;
  EXPECT_EQ(bytes(again.last_map), bytes(recorded.last_map));
  ObjectMapOptions average = plainSum();
  average.posterior_views_exponent = 1;
  EXPECT_NE(bytes(rerunObjectMap(log, ch, average).frames.at(10)), bytes(recorded.frames.at(10)));
}

// A sequence whose classes the model does not know (the real sequences: temple, cabinet) has no
// recognition sections.
TEST(RecognitionSection, ASequenceWithoutAModelClassIsNotEvaluated) {
  const std::string seq =
      makeSequence("eval_foreign_classes", 3, {"temple"}, {truth(0, 1, 1, 30, 30, "temple")});
  EXPECT_TRUE(evaluatedClasses(kModel, SequenceFolder::open(seq)).empty());
}

// A sequence of separate views (boxes, no ground-truth poses: uw_scenes_v2_public) is scored on
// every frame, a video on every stride-th; a detection on a frame that is not scored counts
// nowhere.
TEST(RecognitionEval, EveryFrameOfASequenceOfSeparateViewsIsScored) {
  std::vector<GroundTruthBox> boxes;
  for (int f = 0; f < 7; ++f) boxes.push_back(truth(f, 100, 100, 50, 50, "coffee_mug"));
  const std::string views =
      makeSequence("eval_separate_views_seq", 7, {"coffee_mug"}, boxes, false);
  const std::string video = makeSequence("eval_video_seq", 7, {"coffee_mug"}, boxes, true);
  EXPECT_EQ(framesToScore(SequenceFolder::open(views), 5), (std::vector<int>{0, 1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(framesToScore(SequenceFolder::open(video), 5), (std::vector<int>{0, 5}));

  RecognitionRecording run;
  run.classes = {"coffee_mug", "background"};
  for (int f = 0; f < 7; ++f) {
    RecognitionRecording::Box b;
    b.single = {Box2{100, 100, 50, 50}, {std::log(0.9), std::log(0.1)}, -1};
    b.online = b.final = b.single;
    run.frames[f].push_back(b);
  }
  const RecognitionResult r =
      scoreRecognition(run, SequenceFolder::open(views), RecognitionEvalOptions{});
  EXPECT_EQ(r.single.frames, 7);
  EXPECT_EQ(r.single.classes.at("coffee_mug").truth, 7);
  EXPECT_EQ(r.single.classes.at("coffee_mug").labelled_tp, 7);
  const RecognitionResult v =
      scoreRecognition(run, SequenceFolder::open(video), RecognitionEvalOptions{});
  EXPECT_EQ(v.single.frames, 2);
  EXPECT_EQ(v.single.classes.at("coffee_mug").truth, 2);
}
