// The single_view / multi_view sections of the eval report: VOC all-point AP on hand-computed
// examples (ties, no ground truth), the matching of boxes to ground truth (one match per ground-truth
// box, distractors), pooling over sequences, the report keys of DESIGN.md §7, and the multi-view
// labels through the object map library (a hand-made recording, merged candidates, the fallback).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>

#include "tests/eval/eval_test_data.h"
#include "tests/objectmap/synthetic_world.h"
#include "tests/support/test_support.h"
#include "tools/eval/recognition_metrics.h"

using namespace slamaware;
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
  const double ap =
      averagePrecision(hits({{0.5, false}, {0.9, true}, {0.6, false}, {0.7, true}, {0.8, false}}), 3, &curve);
  EXPECT_NEAR(ap, 5.0 / 9.0, 1e-12);
  ASSERT_EQ(curve.size(), 5u);
  EXPECT_NEAR(curve[0].precision, 1.0, 1e-12);
  EXPECT_NEAR(curve[2].recall, 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(curve[2].precision, 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(curve[4].precision, 0.4, 1e-12);
  // Every box found, the best first: AP 1. A false positive above all of them: the precision at
  // every recall is the precision after it is passed.
  EXPECT_NEAR(averagePrecision(hits({{0.9, true}, {0.8, true}}), 2), 1.0, 1e-12);
  EXPECT_NEAR(averagePrecision(hits({{0.99, false}, {0.9, true}, {0.8, true}}), 2), 2.0 / 3.0, 1e-12);
}

// Equal scores are one step of the curve, so their order does not matter: a TP and an FP tied at
// 0.8 give 5/9 (recall 1/3 at precision 1, then 2/3 at precision 2/3) in either order, where the
// TP taken first alone would give 2/3. A TP tied with two FPs is one step to recall 1/2 at
// precision 1/3, wherever the TP is among them.
TEST(AveragePrecision, TiedScoresAreOneStepWhateverTheirOrder) {
  const double a = averagePrecision(hits({{0.9, true}, {0.8, true}, {0.8, false}, {0.5, false}}), 3);
  const double b = averagePrecision(hits({{0.9, true}, {0.8, false}, {0.8, true}, {0.5, false}}), 3);
  EXPECT_NEAR(a, 5.0 / 9.0, 1e-12);
  EXPECT_NEAR(b, 5.0 / 9.0, 1e-12);
  EXPECT_NEAR(averagePrecision(hits({{0.9, true}, {0.81, true}, {0.8, false}, {0.5, false}}), 3), 2.0 / 3.0,
              1e-12);
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
  scoreFrame(kModel, {box(102, 102, 50, 50, {0.7, 0.2, 0.1}), box(100, 100, 50, 50, {0.8, 0.1, 0.1})},
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
  EXPECT_EQ(s.classes.at("coffee_mug").ranked.size(), 2u) << "every box is a detection of every class";
  EXPECT_EQ(s.boxes_on_objects, 2);
  EXPECT_EQ(s.correct_on_objects, 2);
  const nlohmann::json j = recognitionSection(s);
  EXPECT_DOUBLE_EQ(j["per_class"]["cap"]["AP"].get<double>(), 100.0);
  EXPECT_DOUBLE_EQ(j["per_class"]["cap"]["precision"].get<double>(), 50.0);
  EXPECT_DOUBLE_EQ(j["per_class"]["cap"]["recall"].get<double>(), 100.0);
}

// A box is matched to the unmatched box of its class that it overlaps most (DESIGN.md §7: "an
// unmatched ground-truth box"), so the second box of two overlapping caps is found by the second
// detection even though that detection overlaps the first cap more.
TEST(RecognitionMatching, TheUnmatchedBoxOverlappingMostIsTaken) {
  RecognitionScores s = emptyScores({"cap"});
  scoreFrame(kModel, {box(120, 100, 50, 50, {0.9, 0.05, 0.05}), box(115, 100, 50, 50, {0.8, 0.1, 0.1})},
             {truth(0, 100, 100, 50, 50, "cap"), truth(0, 120, 100, 50, 50, "cap")}, 0.5, &s);
  const ClassTally& cap = s.classes.at("cap");
  EXPECT_EQ(cap.truth, 2);
  EXPECT_TRUE(cap.ranked[0].true_positive);
  EXPECT_TRUE(cap.ranked[1].true_positive) << "IoU 0.54 with the free cap";
  EXPECT_EQ(cap.labelled_tp, 2);
  // Below the threshold nothing matches.
  RecognitionScores t = emptyScores({"cap"});
  scoreFrame(kModel, {box(140, 100, 50, 50, {0.9, 0.05, 0.05})}, {truth(0, 100, 100, 50, 50, "cap")}, 0.5, &t);
  EXPECT_FALSE(t.classes.at("cap").ranked[0].true_positive) << "IoU 10/90";
  EXPECT_EQ(t.boxes_elsewhere, 1);
}

// Ground-truth boxes of classes that are not evaluated (the scene's distractors, or a model class the
// sequence does not list) are not ground truth: they are never missed, and a box on one that is
// called a cap is a false positive of cap.
TEST(RecognitionMatching, ADistractorIsNotGroundTruth) {
  RecognitionScores s = emptyScores({"cap"});  // coffee_mug: a model class this sequence does not list
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
  EXPECT_FALSE(cap.ranked[0].true_positive) << "p(cap) 0.9 on the calculator ranks first and is false";
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
  scoreFrame(kModel, {box(100, 100, 50, 50, {0.8, 0.1, 0.1}), box(300, 300, 50, 50, {0.3, 0.6, 0.1})},
             {truth(0, 100, 100, 50, 50, "cap")}, 0.5, &s);
  scoreFrame(kModel, {}, {truth(5, 100, 100, 50, 50, "cap")}, 0.5, &s);  // a frame without boxes: a miss
  const nlohmann::json j = recognitionSection(s);
  for (const char* key : {"mAP", "recall", "per_class"}) EXPECT_TRUE(j.contains(key)) << key;
  ASSERT_TRUE(j["per_class"].is_object());
  for (const char* cls : {"cap", "coffee_mug"}) {
    ASSERT_TRUE(j["per_class"].contains(cls)) << cls;
    for (const char* key : {"AP", "precision", "recall"}) EXPECT_TRUE(j["per_class"][cls].contains(key)) << key;
  }
  EXPECT_NEAR(j["per_class"]["cap"]["AP"].get<double>(), 50.0, 1e-9);
  EXPECT_DOUBLE_EQ(j["per_class"]["cap"]["recall"].get<double>(), 50.0);
  EXPECT_DOUBLE_EQ(j["per_class"]["cap"]["precision"].get<double>(), 100.0);
  // No ground truth: no AP, no recall, and not in the mAP; precision of the one box called a mug: 0.
  EXPECT_TRUE(j["per_class"]["coffee_mug"]["AP"].is_null());
  EXPECT_TRUE(j["per_class"]["coffee_mug"]["recall"].is_null());
  EXPECT_DOUBLE_EQ(j["per_class"]["coffee_mug"]["precision"].get<double>(), 0.0);
  EXPECT_NEAR(j["mAP"].get<double>(), 50.0, 1e-9);
  EXPECT_DOUBLE_EQ(j["recall"].get<double>(), 50.0);
  EXPECT_EQ(j["frames_evaluated"], 2);
  EXPECT_EQ(j["ground_truth_boxes"], 2);
}

// A ground-truth box that no box overlaps at the threshold is missed whatever the labels: the share
// of boxed ground truth bounds recall and AP, per class and (mean over classes) the mAP. Three caps:
// one boxed and found, one boxed but called background, one overlapped at IoU 0.33 only; and a
// frame without boxes. A mug nobody boxed makes the class bound 0.
TEST(RecognitionSection, TheBoxedShareBoundsRecallAndAp) {
  RecognitionScores s = emptyScores({"cap", "coffee_mug"});
  scoreFrame(kModel,
             {box(100, 100, 50, 50, {0.8, 0.1, 0.1}), box(300, 100, 50, 50, {0.1, 0.1, 0.8}),
              box(525, 100, 50, 50, {0.7, 0.2, 0.1})},
             {truth(0, 100, 100, 50, 50, "cap"), truth(0, 300, 100, 50, 50, "cap"), truth(0, 500, 100, 50, 50, "cap")},
             0.5, &s);
  scoreFrame(kModel, {}, {truth(5, 100, 100, 50, 50, "cap"), truth(5, 300, 300, 40, 60, "coffee_mug")}, 0.5, &s);
  EXPECT_EQ(s.classes.at("cap").boxed, 2);
  EXPECT_EQ(s.classes.at("coffee_mug").boxed, 0);
  const nlohmann::json j = recognitionSection(s);
  EXPECT_DOUBLE_EQ(j["per_class"]["cap"]["boxed"].get<double>(), 50.0);
  EXPECT_DOUBLE_EQ(j["per_class"]["coffee_mug"]["boxed"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(j["boxed"].get<double>(), 40.0) << "2 of 5 ground-truth boxes";
  EXPECT_DOUBLE_EQ(j["mAP_bound"].get<double>(), 25.0) << "the mean of 50 and 0";
  // p(cap) 0.1 on the second cap still ranks it, after the partial box: AP 1/4 + 1/4 x 2/3 = 5/12.
  EXPECT_LE(j["per_class"]["cap"]["AP"].get<double>(), j["per_class"]["cap"]["boxed"].get<double>());
  EXPECT_NEAR(j["per_class"]["cap"]["AP"].get<double>(), 500.0 / 12.0, 1e-9);
  EXPECT_LE(j["mAP"].get<double>(), j["mAP_bound"].get<double>());
  EXPECT_DOUBLE_EQ(j["per_class"]["cap"]["recall"].get<double>(), 25.0) << "at the argmax label, 1 of 4";
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
  scoreFrame(kModel, {box(100, 100, 50, 50, {0.9, 0.05, 0.05})}, {truth(0, 100, 100, 50, 50, "cap")}, 0.5, &a);
  scoreFrame(kModel, {box(300, 100, 50, 50, {0.95, 0.03, 0.02}), box(100, 100, 50, 50, {0.5, 0.3, 0.2})},
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

// One candidate seen in 3 frames: two views weakly say cap, one strongly says coffee_mug. The
// single-view labels are cap, cap, coffee_mug; every box gets the fused label coffee_mug
// (0.5·0.5·0.05 < 0.4·0.4·0.9), read from a recorded log and scored against a mug in each frame.
// The replay checks itself against the node's last OBJECT_MAP in the log.
TEST(MultiViewLabels, BoxesOfOneCandidateGetTheFusedLabel) {
  const std::string dir = test::tempDir("eval_multiview");
  const std::string log_path = dir + "/run.lcm";
  const Channels ch;
  const auto weak_cap = logs({0.5, 0.4, 0.1}), strong_mug = logs({0.05, 0.9, 0.05});
  const std::vector<detections_t> messages = {
      detections(0, 1, kModel, {{5, weak_cap}, {6, logs({0.1, 0.1, 0.8})}}),
      detections(5, 1, kModel, {{5, weak_cap}}), detections(10, 1, kModel, {{5, strong_mug}})};
  // The node's OBJECT_MAP after each DETECTIONS, as the lockstep node publishes it.
  ObjectMapEngine node(plainSum());
  auto record = [&](const std::string& path, bool tamper) {
    lcm::LogFile log(path, "w");
    int64_t n = 0;
    for (const auto& d : messages) {
      std::string why;
      writeEvent(log, ch.detections, d, n++);
      ASSERT_TRUE(node.onDetections(d, &why)) << why;
      object_map_t m = node.objectMap();
      if (tamper && &d == &messages.back()) m.objects[0].label = "cap";
      writeEvent(log, ch.object_map, m, n++);
    }
  };
  record(log_path, false);
  const RecognitionRecording run = readRecognitionRecording(log_path, ch, plainSum());
  EXPECT_EQ(run.matches_node, 1) << "the replay gives the node's objects";
  EXPECT_EQ(run.objects, 2);
  node = ObjectMapEngine(plainSum());
  record(dir + "/tampered.lcm", true);
  EXPECT_EQ(readRecognitionRecording(dir + "/tampered.lcm", ch, plainSum()).matches_node, 0);
  ASSERT_EQ(run.classes, kModel);
  ASSERT_EQ(run.frames.size(), 3u);
  const double cap = std::log(0.5) * 2 + std::log(0.05), mug = std::log(0.4) * 2 + std::log(0.9),
               bg = std::log(0.1) * 2 + std::log(0.05);
  const double norm = std::log(std::exp(cap) + std::exp(mug) + std::exp(bg));
  for (int f : {0, 5, 10}) {
    const auto& b = run.frames.at(f)[0];
    EXPECT_EQ(b.candidate, 5);
    EXPECT_TRUE(b.multi_from_object);
    ASSERT_EQ(b.fused.log_p.size(), 3u);
    EXPECT_NEAR(b.fused.log_p[0], cap - norm, 1e-5);
    EXPECT_NEAR(b.fused.log_p[1], mug - norm, 1e-5);
    EXPECT_NEAR(b.fused.log_p[2], bg - norm, 1e-5);
    // Labelled by the fused evidence, scored with the box's own view's p(mug) and the objectness
    // of its candidate's three views (0.9, 0.9, 0.95: mean 0.9167), which are also all of its
    // object's (median 0.9).
    EXPECT_EQ(b.multi.label, 1);
    ASSERT_EQ(b.multi.log_p.size(), 3u);
    const double views = (0.9 + 0.9 + 0.95) / 3 * 0.9;
    EXPECT_NEAR(b.log_objectness, std::log(std::cbrt((f == 10 ? 0.95 : 0.9) * views)), 1e-5);
    const double box_class = std::cbrt((f == 10 ? 0.9 : 0.4) * views);
    EXPECT_NEAR(b.multi.log_p[1], mug - norm + std::log(box_class), 1e-5);
    EXPECT_NEAR(b.single.log_p[1], std::log(f == 10 ? 0.9 : 0.4), 1e-6);
  }
  // The other candidate keeps its own (background) evidence.
  EXPECT_NEAR(std::exp(run.frames.at(0)[1].fused.log_p[2]), 0.8, 1e-6);
  // The posterior of the average view (posterior_views_exponent 1): the sum over 3 views / 3.
  ObjectMapOptions average = plainSum();
  average.posterior_views_exponent = 1;
  const RecognitionRecording avg = readRecognitionRecording(log_path, ch, average);
  const double avg_norm = std::log(std::exp(cap / 3) + std::exp(mug / 3) + std::exp(bg / 3));
  EXPECT_NEAR(avg.frames.at(0)[0].fused.log_p[1], mug / 3 - avg_norm, 1e-5);
  EXPECT_EQ(avg.frames.at(0)[0].multi.label, 1);

  const std::string seq = makeSequence("eval_multiview_seq", 11, {"cap", "coffee_mug"},
                                       {truth(0, 100, 100, 50, 50, "coffee_mug"),
                                        truth(5, 100, 100, 50, 50, "coffee_mug"),
                                        truth(10, 100, 100, 50, 50, "coffee_mug")});
  const RecognitionResult r = scoreRecognition(run, SequenceFolder::open(seq), RecognitionEvalOptions{});
  EXPECT_EQ(r.classes, (std::vector<std::string>{"cap", "coffee_mug"}));
  EXPECT_EQ(r.single.frames, 3) << "frames 0, 5, 10";
  EXPECT_EQ(r.single.classes.at("coffee_mug").labelled_tp, 1);
  EXPECT_EQ(r.single.classes.at("cap").labelled, 2);
  EXPECT_EQ(r.multi.classes.at("coffee_mug").labelled_tp, 3);
  EXPECT_EQ(r.multi.classes.at("cap").labelled, 0);
  EXPECT_EQ(r.multi.fallback_boxes, 0);
  EXPECT_NEAR(recognitionSection(r.multi)["per_class"]["coffee_mug"]["recall"].get<double>(), 100.0, 1e-9);
  EXPECT_NEAR(recognitionSection(r.single)["per_class"]["coffee_mug"]["recall"].get<double>(), 100.0 / 3, 1e-9);
}

// Multi-view scores: p(c | object) x (1 - p(background | box)) for the object classes, the rest to
// background; a confident object seen through a box that its own view calls background ranks below
// the same object through a box that frames it, but keeps its label.
TEST(MultiViewLabels, AFusedLabelIsScoredByTheBoxsOwnObjectness) {
  auto lg = [](std::vector<double> p) {
    for (double& v : p) v = std::log(v);
    return p;
  };
  const std::vector<double> fused = lg({0.02, 0.97, 0.01});  // the object is a mug
  const auto every = [](double log_factor) { return std::vector<double>(3, log_factor); };
  const std::vector<double> framed = multiViewScores(fused, every(logObjectness(lg({0.1, 0.8, 0.1}))));
  const std::vector<double> part = multiViewScores(fused, every(logObjectness(lg({0.05, 0.05, 0.9}))));
  ASSERT_EQ(framed.size(), 3u);
  EXPECT_NEAR(std::exp(framed[1]), 0.97 * 0.9, 1e-9);
  EXPECT_NEAR(std::exp(framed[0]), 0.02 * 0.9, 1e-9);
  EXPECT_NEAR(std::exp(framed[0]) + std::exp(framed[1]) + std::exp(framed[2]), 1.0, 1e-9);
  EXPECT_NEAR(std::exp(part[1]), 0.97 * 0.1, 1e-9);
  // A box whose view is sure it frames an object (log p(background) = -800) scores as the object.
  EXPECT_NEAR(multiViewScores(fused, every(logObjectness({-1, -0.5, -800})))[1], std::log(0.97), 1e-9);
  EXPECT_EQ(multiViewScores({}, std::vector<double>{}), std::vector<double>{});
  EXPECT_EQ(logObjectness({}), 0.0);

  // Both boxes over a mug in one frame: the framing one is ranked first and matched; the part
  // (IoU < 0.5) is a false positive ranked below it, and both are still labelled mug.
  RecognitionScores s = emptyScores({"cap", "coffee_mug"});
  LabelledBox a{{100, 100, 50, 50}, framed, 1}, b{{100, 100, 20, 20}, part, 1};
  scoreFrame(kModel, {b, a}, {truth(0, 100, 100, 50, 50, "coffee_mug")}, 0.5, &s);
  const ClassTally& mug = s.classes.at("coffee_mug");
  ASSERT_EQ(mug.ranked.size(), 2u);
  EXPECT_TRUE(mug.ranked[0].true_positive);
  EXPECT_FALSE(mug.ranked[1].true_positive);
  EXPECT_EQ(mug.labelled, 2) << "the label is the fused one, not the argmax of the scores";
  EXPECT_DOUBLE_EQ(averagePrecision(mug.ranked, mug.truth), 1.0);
}

// A box's p(object | box) is the geometric mean of its own view's, its candidate's mean over every
// box of the candidate, and its object's median over every box of the object: a part that one view
// takes for a whole object is held back by the candidate's other views, and a distractor whose views
// mostly call it background by the object's views, however well one box frames it (the median: its
// one sure view of four does not lift it, as it would lift a mean).
TEST(MultiViewLabels, ObjectnessIsTheBoxsViewWithItsCandidatesAndItsObjectsViews) {
  auto box = [](int32_t candidate, int32_t object, double p_background) {
    RecognitionRecording::Box b;
    b.map_id = 1;
    b.candidate = candidate;
    b.object = object;
    b.single.log_p = {std::log((1 - p_background) / 2), std::log((1 - p_background) / 2), std::log(p_background)};
    b.fused.log_p = {std::log(0.1), std::log(0.9), -100};
    return b;
  };
  std::map<int32_t, std::vector<RecognitionRecording::Box>> frames;
  frames[0] = {box(3, 7, 0.2), box(5, 7, 0.2), box(9, 8, 0.1)};
  frames[1] = {box(3, 7, 0.9), box(9, 8, 0.95)};
  frames[2] = {box(3, 7, 0.9), box(5, 7, 0.4), box(9, 8, 0.95), box(11, -1, 0.5)};
  frames[3] = {box(9, 8, 0.95)};
  scoreMultiView(&frames);
  // Candidate 3: views 0.8, 0.1, 0.1 -> mean 1/3; candidate 5: 0.8, 0.6 -> 0.7; their object 7:
  // 0.1, 0.1, 0.6, 0.8, 0.8 -> median 0.6. Candidate 9, alone in object 8: 0.9, 0.05, 0.05, 0.05 ->
  // mean 0.2625, median 0.05 (the mean of the middle two). Candidate 11 has no object: its own
  // median stands in.
  const auto mean3 = [](double a, double b, double c) { return (std::log(a) + std::log(b) + std::log(c)) / 3; };
  EXPECT_NEAR(frames[0][0].log_objectness, mean3(0.8, 1.0 / 3, 0.6), 1e-9);
  EXPECT_NEAR(frames[0][1].log_objectness, mean3(0.8, 0.7, 0.6), 1e-9);
  EXPECT_NEAR(frames[2][1].log_objectness, mean3(0.6, 0.7, 0.6), 1e-9);
  EXPECT_NEAR(frames[0][2].log_objectness, mean3(0.9, 0.2625, 0.05), 1e-9);
  EXPECT_NEAR(frames[2][3].log_objectness, std::log(0.5), 1e-9);
  // Scored with the box's own view's p(mug | box), 0.4, in place of its 1 - p(background), 0.8.
  EXPECT_NEAR(std::exp(frames[0][1].multi.log_p[1]), 0.9 * std::cbrt(0.4 * 0.7 * 0.6), 1e-9);
  EXPECT_NEAR(std::exp(frames[0][1].multi.log_p[0]), 0.1 * std::cbrt(0.4 * 0.7 * 0.6), 1e-9);
  EXPECT_LT(frames[0][0].multi.log_p[1], frames[0][1].multi.log_p[1])
      << "the same view, but the candidate's other views say it is not a whole object";
  EXPECT_LT(frames[0][2].multi.log_p[1], frames[0][1].multi.log_p[1])
      << "a surer view and the same fused class, but the object's other views call it background";
}

// Two boxes of one candidate in one frame, both sure they frame an object (p(background) 0.1): the
// one whose own view gives the object's fused class 0.85 ranks above the one whose view gives it
// 0.3 (a box on the mug and its neighbour, which the view takes partly for a cap). Labels stay.
TEST(MultiViewLabels, ABoxsOwnViewOfTheFusedClassRanksItAmongTheObjectsBoxes) {
  auto box = [](std::vector<double> p) {
    RecognitionRecording::Box b;
    b.map_id = 1;
    b.candidate = 3;
    b.object = 7;
    for (double& v : p) v = std::log(v);
    b.single.log_p = p;
    b.fused.log_p = {std::log(0.05), std::log(0.9), std::log(0.05)};
    return b;
  };
  std::map<int32_t, std::vector<RecognitionRecording::Box>> frames;
  frames[0] = {box({0.05, 0.85, 0.1}), box({0.6, 0.3, 0.1})};
  scoreMultiView(&frames);
  const auto& framed = frames[0][0].multi.log_p;
  const auto& joined = frames[0][1].multi.log_p;
  EXPECT_DOUBLE_EQ(frames[0][0].log_objectness, frames[0][1].log_objectness) << "both equally sure of an object";
  EXPECT_NEAR(std::exp(framed[1]), 0.9 * std::cbrt(0.85 * 0.9 * 0.9), 1e-9);
  EXPECT_NEAR(std::exp(joined[1]), 0.9 * std::cbrt(0.3 * 0.9 * 0.9), 1e-9);
  EXPECT_GT(framed[1], joined[1]);
  EXPECT_NEAR(std::exp(framed[0]) + std::exp(framed[1]) + std::exp(framed[2]), 1.0, 1e-9);
}

// One object, one detection per frame: of the boxes of one object in a frame, the one its own view
// finds most object-like keeps its scores; the others are demoted by a Gaussian of the share of
// them inside it (Soft-NMS): a box framing the object as the kept one does, or a part of it inside
// the kept box (a sliver with an IoU of only 0.2), ranks below the detections; a box on another
// part of the object beside the kept one keeps its score. Their label stays the object's, and a box
// of another object (or of none) is untouched.
TEST(MultiViewLabels, DuplicatesOfAnObjectInAFrameAreDemotedByTheirOverlap) {
  auto box = [](int32_t object, double log_bg, std::vector<double> multi, Box2 where) {
    RecognitionRecording::Box b;
    b.object = object;
    b.single.log_p = {-3.0, -3.0, log_bg};
    b.multi.log_p = std::move(multi);
    b.multi.label = 1;
    b.multi.box = where;
    return b;
  };
  const std::vector<double> mug{std::log(0.02), std::log(0.9), std::log(0.08)};
  const Box2 whole{100, 100, 50, 50}, shifted{105, 100, 50, 50}, beside{150, 100, 20, 50}, side{110, 100, 10, 50};
  std::vector<RecognitionRecording::Box> boxes{box(4, std::log(0.6), mug, shifted), box(4, std::log(0.1), mug, whole),
                                               box(4, std::log(0.7), mug, beside), box(7, std::log(0.9), mug, whole),
                                               box(-1, std::log(0.9), mug, whole),  box(4, std::log(0.3), mug, side)};
  EXPECT_EQ(demoteDuplicateBoxes(&boxes), 2);
  EXPECT_EQ(boxes[1].multi.log_p, mug) << "the most object-like box of object 4 keeps its scores";
  EXPECT_EQ(boxes[3].multi.log_p, mug);
  EXPECT_EQ(boxes[4].multi.log_p, mug);
  const double overlap = 45.0 * 50 / 2500;  // 90 % of the shifted box inside the whole (IoU 9/11)
  const double demoted = -overlap * overlap / kDuplicateSigma;
  EXPECT_NEAR(boxes[5].multi.log_p[1], std::log(0.9) - 1 / kDuplicateSigma, 1e-9)
      << "the side of the object, wholly inside the kept box: demoted as a duplicate, not by its IoU (0.2)";
  EXPECT_NEAR(boxes[0].multi.log_p[1], std::log(0.9) + demoted, 1e-9);
  EXPECT_NEAR(boxes[0].multi.log_p[0], std::log(0.02) + demoted, 1e-9);
  EXPECT_NEAR(std::exp(boxes[0].multi.log_p[2]), 1 - (0.92 * std::exp(demoted)), 1e-9);
  EXPECT_EQ(boxes[2].multi.log_p, mug) << "no overlap with the kept box: another part, its score stays";
  EXPECT_EQ(boxes[0].multi.label, 1) << "a duplicate keeps its object's label";

  // Scored: the kept box matches the mug; the shifted duplicate and the side are false positives
  // ranked after every other box.
  RecognitionScores s = emptyScores({"cap", "coffee_mug"});
  std::vector<LabelledBox> frame;
  for (auto& b : boxes) frame.push_back(b.multi);
  scoreFrame(kModel, frame, {truth(0, 100, 100, 50, 50, "coffee_mug")}, 0.5, &s);
  const ClassTally& t = s.classes.at("coffee_mug");
  ASSERT_EQ(t.ranked.size(), 6u);
  EXPECT_EQ(std::count_if(t.ranked.begin(), t.ranked.end(), [](const ScoredDetection& d) { return d.true_positive; }), 1);
  std::vector<ScoredDetection> ranked = t.ranked;
  std::sort(ranked.begin(), ranked.end(), [](const auto& x, const auto& y) { return x.score < y.score; });
  EXPECT_FALSE(ranked[0].true_positive);
  EXPECT_FALSE(ranked[1].true_positive);
  EXPECT_LT(ranked[1].score, ranked[2].score - 5) << "the shifted duplicate and the side rank last, far below";
}

// Two candidates of one object (the proposals stage over-segments; here two clusters of the same
// mug) are grouped by the object map: the boxes of both get the object's posterior, over the union
// of their views, the same for both.
TEST(MultiViewLabels, CandidatesOfOneObjectShareItsPosterior) {
  test::SyntheticWorldOptions wo;
  wo.frames = 30;
  auto objects = test::SyntheticWorld::defaultObjects();
  test::SyntheticObject twin = objects[0];  // the mug again, under another candidate id
  twin.candidate = 21;
  objects.push_back(twin);
  const test::SyntheticWorld w(wo, objects);
  MultiViewLabeller labeller{plainSum()};
  labeller.onCameraInfo(w.cameraInfo());
  const auto clouds = w.keyframeClouds(1);
  for (int f = 0; f < wo.frames; ++f) {
    for (const auto& c : clouds)
      if (c.seq == f) labeller.onMap(c);
    labeller.onPose(w.poseMessage(f, 1));
    labeller.onProposals(w.proposals(f, 1));
    labeller.onDetections(w.detections(f, 1));
  }
  EXPECT_EQ(labeller.refused(), 0);
  const Object* a = labeller.engine().objectOfCandidate(1, objects[0].candidate);
  const Object* b = labeller.engine().objectOfCandidate(1, 21);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a, b) << "one object";
  EXPECT_EQ(a->candidates, (std::vector<int32_t>{objects[0].candidate, 21}));
  const std::vector<std::string>& classes = test::SyntheticWorld::classNames();
  bool from_a = false, from_b = false;
  const std::vector<double> pa = labeller.logPosterior(1, objects[0].candidate, classes, &from_a);
  const std::vector<double> pb = labeller.logPosterior(1, 21, classes, &from_b);
  EXPECT_TRUE(from_a && from_b);
  EXPECT_EQ(pa, pb);
  ASSERT_EQ(pa.size(), a->posterior.size());
  for (size_t k = 0; k < pa.size(); ++k) EXPECT_NEAR(std::exp(pa[k]), a->posterior[k], 1e-9);
  EXPECT_EQ(std::max_element(pa.begin(), pa.end()) - pa.begin(), objects[0].cls);
  // The bowl is an object of its own.
  EXPECT_NE(labeller.engine().objectOfCandidate(1, objects[1].candidate), a);

  // The object map summary: every object labelled, none dominant (several objects apart).
  const nlohmann::json summary = objectMapSummary(labeller.engine());
  EXPECT_EQ(summary["objects"].get<int>(), static_cast<int>(labeller.engine().numObjects()));
  EXPECT_EQ(summary["labelled_objects"], summary["objects"]);
  EXPECT_EQ(summary["segments"].get<int>(), 1);
  const double share = summary["largest_object_share"].get<double>();
  EXPECT_GT(share, 0.0);
  EXPECT_LT(share, 70.0) << "the mug is not most of a scene of several objects";
  EXPECT_GE(summary["largest_object_voxels"].get<int>(), a->num_voxels);
  EXPECT_GT(summary["main_segment_object_voxels"].get<int>(), summary["largest_object_voxels"].get<int>());
}

// A candidate the object map does not hold (its only box was refused: a log-probability above 0)
// is labelled by its own evidence (log-probabilities clamped to [-100, 0]); one never seen gets a
// uniform distribution.
TEST(MultiViewLabels, ACandidateTheMapDoesNotHoldFallsBackToItsOwnEvidence) {
  MultiViewLabeller labeller{plainSum()};
  std::vector<float> bad = logs({0.2, 0.7, 0.1});
  bad[2] = 0.01f;  // not a log-probability: the object map refuses the box
  labeller.onDetections(detections(0, 1, kModel, {{7, bad}, {8, logs({0.6, 0.3, 0.1})}}));
  EXPECT_EQ(labeller.engine().objectOfCandidate(1, 7), nullptr);
  ASSERT_NE(labeller.engine().objectOfCandidate(1, 8), nullptr);
  bool from_object = true;
  const std::vector<double> p = labeller.logPosterior(1, 7, kModel, &from_object);
  EXPECT_FALSE(from_object);
  ASSERT_EQ(p.size(), 3u);
  EXPECT_NEAR(p[2] - p[1], -std::log(0.7), 1e-6) << "0.01 counts as 0";
  double sum = 0;
  for (double v : p) sum += std::exp(v);
  EXPECT_NEAR(sum, 1.0, 1e-9);
  const std::vector<double> none = labeller.logPosterior(1, 99, kModel, &from_object);
  EXPECT_FALSE(from_object);
  for (double v : none) EXPECT_NEAR(v, std::log(1.0 / 3), 1e-12);
}

// A sequence whose classes the model does not know (the real sequences: temple, cabinet) has no
// recognition sections.
TEST(RecognitionSection, ASequenceWithoutAModelClassIsNotEvaluated) {
  const std::string seq = makeSequence("eval_foreign_classes", 3, {"temple"}, {truth(0, 1, 1, 30, 30, "temple")});
  EXPECT_TRUE(evaluatedClasses(kModel, SequenceFolder::open(seq)).empty());
}
