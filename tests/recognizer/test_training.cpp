// Training separates two categories (synthetic ones always; a subset of the real UW RGB-D crops
// when ../shared/data is there); a saved model reloads to identical predictions; a truncated,
// bit-flipped or otherwise wrong model file is refused with a message that names it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <sstream>

#include "common/atomic_file.h"
#include "common/config.h"
#include "common/dataset.h"
#include "common/image_codec.h"
#include "procs/recognizer/recognizer.h"
#include "tests/recognizer/synthetic_data.h"
#include "tests/support/test_support.h"
#include "tools/synth/synth_options.h"
#include "tools/synth/writers.h"
#include "tools/train/trainer.h"

using namespace slamaware;
using namespace slamaware::recognizer;
namespace fs = std::filesystem;

namespace {

// Options small enough for a test (the encoding itself keeps the paper's parameters).
TrainOptions testOptions() {
  TrainOptions o;
  o.vocabulary_descriptors = 20000;
  o.kmeans_iterations = 25;
  o.sgd.epochs = 12;
  o.negatives_per_frame = 8;
  o.mining_candidates_per_frame = 30;
  o.mining_max_per_round = 60;
  o.scene_positive_every = 2;  // frame 0 (held out) gives its object's boxes
  return o;
}

struct Trained {
  std::string objects, scenes, model_path;
  TrainReport report;
  RecognizerModel model;
};

// One synthetic model shared by the tests of this file (training is the slow part).
const Trained& synthetic() {
  static Trained t = [] {
    Trained t;
    // A folder per test: each test of this file runs in a process of its own, in parallel.
    const std::string dir =
        test::tempDir(std::string("recognizer_training_") +
                      ::testing::UnitTest::GetInstance()->current_test_info()->name());
    t.objects = test::makeSyntheticObjectSet(dir + "/objects", 3, 14);
    t.scenes = test::makeSyntheticScenes(dir + "/scenes", 6);
    t.model = trainModel({t.objects}, {t.scenes}, testOptions(), &t.report);
    t.model_path = dir + "/model.bin";
    saveModel(t.model, t.model_path);
    return t;
  }();
  return t;
}

// A textured frame with a disc at (100, 100) and a bar at (400, 250), 72 px each.
cv::Mat frameWithDiscAndBar(int seed) {
  cv::Mat frame = test::texturedFrame(seed, 640, 480);
  test::syntheticObjectView("disc", 3, 777, 72).copyTo(frame(cv::Rect(100, 100, 72, 72)));
  test::syntheticObjectView("bar", 3, 778, 72).copyTo(frame(cv::Rect(400, 250, 72, 72)));
  return frame;
}

std::vector<char> readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<char>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void writeBytes(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string loadError(const std::string& path) {
  try {
    loadModel(path);
  } catch (const ModelError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(Training, SeparatesTwoSyntheticCategoriesOnHeldOutInstances) {
  const Trained& t = synthetic();
  EXPECT_EQ(t.model.classifier.classes, (std::vector<std::string>{"bar", "disc", "background"}));
  const ValidationSummary& v = t.report.validation;
  ASSERT_TRUE(v.available);
  EXPECT_EQ(v.held_out_instances.size(), 2u);  // one instance of each category
  // 28 held-out crops, each also pasted into a scene frame, and the object of the held-out scene
  // frame 0 boxed as it is plus 2 jittered boxes.
  EXPECT_EQ(v.crops, 2 * 28 + 3);
  EXPECT_GE(v.object_accuracy, 90.0) << t.report.toText();
  EXPECT_GE(v.background_accuracy, 90.0) << t.report.toText();
  EXPECT_GT(t.model.classifier.temperature, 0.f);
  EXPECT_EQ(t.report.mined.size() <= 2u, true);
  EXPECT_GT(t.report.train_negatives, 0);
}

TEST(Training, TheModelIsTheSameForAnyNumberOfThreads) {
  const Trained& t = synthetic();  // one thread per core
  TrainOptions o = testOptions();
  o.threads = 1;
  const RecognizerModel one = trainModel({t.objects}, {t.scenes}, o, nullptr);
  o.threads = 3;
  const RecognizerModel three = trainModel({t.objects}, {t.scenes}, o, nullptr);
  for (const RecognizerModel* m : {&t.model, &three}) {
    EXPECT_TRUE(m->pca.mean == one.pca.mean && m->pca.basis == one.pca.basis) << "PCA";
    EXPECT_TRUE(m->vocabulary.centers == one.vocabulary.centers) << "codewords";
    EXPECT_TRUE(m->classifier.weights == one.classifier.weights) << "classifier weights";
    EXPECT_TRUE(m->classifier.bias == one.classifier.bias) << "classifier biases";
    EXPECT_EQ(m->classifier.temperature, one.classifier.temperature);
    EXPECT_EQ(m->classifier.uniform_mix, one.classifier.uniform_mix);
    EXPECT_EQ(m->exemplars.size(), one.exemplars.size());
  }
}

TEST(Training, JitteredPositivesOverlapTheirObjectAndStayInTheImage) {
  auto overlap = [](const cv::Rect2d& a, const cv::Rect2d& b) {
    const double inter = (a & b).area();
    return inter / (a.area() + b.area() - inter);
  };
  const cv::Rect2d image(0, 0, 640, 480);
  // One object in the middle, one cut by the image corner.
  for (const cv::Rect2d object : {cv::Rect2d(200, 150, 120, 90), cv::Rect2d(-20, -10, 80, 60)}) {
    const cv::Rect2d visible = object & image;
    const auto boxes = jitteredBoxes(visible, 640, 480, 20, 0.6, 42);
    ASSERT_EQ(boxes.size(), 20u);
    int moved = 0;
    for (const auto& b : boxes) {
      EXPECT_GE(overlap(b, visible), 0.6);
      EXPECT_EQ((b & image).area(), b.area()) << "box leaves the image";
      moved += overlap(b, visible) < 0.95;
    }
    EXPECT_GE(moved, 10) << "the boxes are not jittered";
    EXPECT_EQ(boxes, jitteredBoxes(visible, 640, 480, 20, 0.6, 42)) << "not deterministic";
  }
}

TEST(Training, PartialBoxesCutOrOverhangTheirObjectAndNoOtherObject) {
  auto overlap = [](const cv::Rect2d& a, const cv::Rect2d& b) {
    const double inter = (a & b).area();
    return inter / (a.area() + b.area() - inter);
  };
  const cv::Rect2d image(0, 0, 640, 480);
  // Two neighbours: a part of one must not be a whole of the other.
  const std::vector<cv::Rect2d> objects{cv::Rect2d(200, 150, 120, 90),
                                        cv::Rect2d(330, 160, 60, 80)};
  const auto boxes = partialBoxes(objects, 0, 640, 480, 30, 0.1, 0.4, 42);
  ASSERT_EQ(boxes.size(), 30u);
  int inside = 0, overhanging = 0;
  for (const auto& b : boxes) {
    EXPECT_GE(overlap(b, objects[0]), 0.1);
    EXPECT_LT(overlap(b, objects[0]), 0.4);
    EXPECT_LT(overlap(b, objects[1]), 0.4);
    EXPECT_EQ((b & image).area(), b.area()) << "box leaves the image";
    inside += (b & objects[0]).area() > 0.95 * b.area();
    overhanging += b.area() > objects[0].area();
  }
  EXPECT_GT(inside, 0) << "no box on a part of the object";
  EXPECT_GT(overhanging, 0) << "no box overhanging the object";
  EXPECT_EQ(boxes, partialBoxes(objects, 0, 640, 480, 30, 0.1, 0.4, 42)) << "not deterministic";
  EXPECT_TRUE(partialBoxes(objects, 2, 640, 480, 5, 0.1, 0.4, 42).empty())
      << "an object index out of range";
}

TEST(Training, ProposalBoxesAreLabelledByTheirOverlapWithTheGroundTruth) {
  SceneFrame frame;
  frame.objects = {cv::Rect2d(100, 100, 100, 100), cv::Rect2d(300, 100, 60, 60)};
  frame.object_classes = {"mug", "calculator"};  // the model has no calculator class
  frame.proposals = {
      cv::Rect2d(105, 100, 100, 100),  // on the mug (IoU 0.90)
      cv::Rect2d(100, 100, 100, 60),   // the top of the mug (IoU 0.60)
      cv::Rect2d(100, 100, 100, 45),   // a smaller part of it (IoU 0.45): neither
      cv::Rect2d(100, 100, 50, 70),    // a corner of it (IoU 0.35): background
      cv::Rect2d(300, 100, 60, 62),    // on the calculator: background
      cv::Rect2d(500, 300, 80, 80),    // on the table: background
  };
  const std::vector<std::string> classes{"bowl", "mug", "background"};
  TrainOptions o;  // positives from IoU 0.5, background below 0.4
  // Suppression at IoU 0.5 in rank order: the top of the mug overlaps the first box by IoU 0.55.
  EXPECT_EQ(labelProposals(frame, classes, 2, o), (std::vector<int>{1, -1, -1, 2, 2, 2}));
  o.proposal_nms_iou = 1;  // every box
  std::vector<double> offsets;
  EXPECT_EQ(labelProposals(frame, classes, 2, o, &offsets), (std::vector<int>{1, 1, -1, 2, 2, 2}));
  // The views of an object (IoU >= 0.5, whatever their label) give their log aspect ratio minus
  // their object's: the mug's whole box and its top, and the calculator's.
  ASSERT_EQ(offsets.size(), 3u);
  EXPECT_DOUBLE_EQ(offsets[0], 0.0);
  EXPECT_NEAR(offsets[1], std::log(100.0 / 60.0), 1e-12);
  EXPECT_NEAR(offsets[2], std::log(60.0 / 62.0), 1e-12);
  o.proposal_background_iou = 0.5;  // no gap: every box is an example
  EXPECT_EQ(labelProposals(frame, classes, 2, o), (std::vector<int>{1, 1, 2, 2, 2, 2}));
}

TEST(Training, ProposalBoxFilesAreReadPerFrameAndAMalformedLineIsNamed) {
  const std::string dir = test::tempDir("recognizer_proposal_boxes");
  {
    std::ofstream(dir + "/scene.csv")
        << "frame,rank,x,y,w,h\n0,0,10,20,30,40\n0,1,1.5,2,3,4\n7,0,5,5,50,60\n";
  }
  const auto boxes = readProposalBoxes(dir + "/scene.csv");
  ASSERT_EQ(boxes.size(), 2u);
  EXPECT_EQ(boxes.at(0),
            (std::vector<cv::Rect2d>{cv::Rect2d(10, 20, 30, 40), cv::Rect2d(1.5, 2, 3, 4)}));
  EXPECT_EQ(boxes.at(7), (std::vector<cv::Rect2d>{cv::Rect2d(5, 5, 50, 60)}));
  for (const char* bad :
       {"0,0,10,20,30\n", "0,0,10,20,x,40\n", "0,0,10,20,0,40\n", "0,0,10,20,nan,40\n"}) {
    std::ofstream(dir + "/bad.csv") << "frame,rank,x,y,w,h\n" << bad;
    try {
      readProposalBoxes(dir + "/bad.csv");
      ADD_FAILURE() << "accepted " << bad;
    } catch (const DatasetError& e) {
      EXPECT_NE(std::string(e.what()).find("bad.csv:2"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(readProposalBoxes(dir + "/missing.csv"), DatasetError);
}

TEST(Training, RecognizerLabelsObjectsInAFrameAndBackgroundAroundThem) {
  const Trained& t = synthetic();
  auto model = std::make_shared<const RecognizerModel>(t.model);
  RecognizerOptions opts;
  Recognizer rec(model, opts);
  const cv::Mat frame = frameWithDiscAndBar(900);
  const FrameDetections d =
      rec.recognize(frame, {{100, 100, 72, 72, 1}, {400, 250, 72, 72, 2}, {250, 20, 100, 80, 3}});
  ASSERT_EQ(d.boxes.size(), 3u);
  auto best = [&](const BoxDetection& b) {
    return d.classes[static_cast<size_t>(std::max_element(b.log_prob.begin(), b.log_prob.end()) -
                                         b.log_prob.begin())];
  };
  EXPECT_EQ(best(d.boxes[0]), "disc");
  EXPECT_EQ(best(d.boxes[1]), "bar");
  EXPECT_EQ(best(d.boxes[2]), "background");
  for (const auto& b : d.boxes) {
    double sum = 0;
    for (float lp : b.log_prob) sum += std::exp(static_cast<double>(lp));
    EXPECT_NEAR(sum, 1.0, 1e-4);
  }
}

// A box that carries its candidate's last result is checked and clipped like any other but not
// classified; the boxes classified beside it get the same scores as in a frame where every box is
// classified; a carried row of another model's class count is not taken (the box is classified).
TEST(Recognizer, CarriedBoxesTakeTheirResultAndTheOthersAreClassifiedAsAlways) {
  const Trained& t = synthetic();
  Recognizer rec(std::make_shared<const RecognizerModel>(t.model), RecognizerOptions{});
  const cv::Mat frame = frameWithDiscAndBar(901);
  const FrameDetections all = rec.recognize(frame, {{100, 100, 72, 72, 1}, {400, 250, 72, 72, 2}});
  ASSERT_EQ(all.boxes.size(), 2u);
  CarriedView earlier{41,
                      std::vector<float>(all.classes.size(),
                                         std::log(1.f / static_cast<float>(all.classes.size())))};
  CarriedView foreign{40, {-0.1f, -2.5f}};  // two classes: another model's
  const FrameDetections d =
      rec.recognize(frame, {{-30, 100, 72, 72, 1, &earlier},  // clipped, carried
                            {400, 250, 72, 72, 2},
                            {700, 10, 50, 50, 3, &earlier},     // outside: rejected
                            {100, 100, 72, 72, 4, &foreign}});  // classified
  ASSERT_EQ(d.boxes.size(), 3u);
  EXPECT_EQ(d.carried, 1);
  EXPECT_EQ(d.rejected_outside, 1);
  EXPECT_EQ(d.clipped, 1);
  EXPECT_EQ(d.boxes[0].carried_seq, 41);
  EXPECT_EQ(d.boxes[0].log_prob, earlier.log_prob);
  EXPECT_FLOAT_EQ(d.boxes[0].x, 0.f);
  EXPECT_FLOAT_EQ(d.boxes[0].w, 42.f);
  EXPECT_EQ(d.boxes[1].carried_seq, -1);
  EXPECT_EQ(d.boxes[2].carried_seq, -1);
  for (size_t c = 0; c < all.classes.size(); ++c) {
    EXPECT_NEAR(d.boxes[1].log_prob[c], all.boxes[1].log_prob[c], 1e-4);
    EXPECT_NEAR(d.boxes[2].log_prob[c], all.boxes[0].log_prob[c], 1e-4);
  }
  // Every box carried: nothing is encoded.
  const FrameDetections none = rec.recognize(frame, {{100, 100, 72, 72, 1, &earlier}});
  ASSERT_EQ(none.boxes.size(), 1u);
  EXPECT_EQ(none.carried, 1);
  EXPECT_EQ(none.stats.features_ms, 0.0);  // no features computed
}

// A frame with more boxes than one pass encodes (Recognizer::kRowsPerPass) is classified in
// several passes through one buffer of that many rows: every box gets the scores it gets when it
// is classified alone, before and after the buffer is made by warmUp.
TEST(Recognizer, ManyBoxesAreClassifiedInPassesWithTheScoresOfEachBoxAlone) {
  const Trained& t = synthetic();
  Recognizer rec(std::make_shared<const RecognizerModel>(t.model), RecognizerOptions{});
  const cv::Mat frame = frameWithDiscAndBar(902);
  std::vector<BoxRequest> requests;
  const int n = 2 * static_cast<int>(Recognizer::kRowsPerPass) + 5;
  for (int i = 0; i < n; ++i)
    requests.push_back({static_cast<double>(20 + (i * 37) % 500),
                        static_cast<double>(15 + (i * 53) % 380), 40.0 + i % 7 * 10,
                        30.0 + i % 5 * 12, i + 1});
  requests[3] = {100, 100, 72, 72, 4};
  requests[2 * Recognizer::kRowsPerPass + 1] = {400, 250, 72, 72, 66};
  for (const bool warm : {false, true}) {
    if (warm) {
      EXPECT_GT(rec.warmUp(640, 480), 0.0);
    }
    const FrameDetections all = rec.recognize(frame, requests);
    ASSERT_EQ(all.boxes.size(), requests.size());
    for (size_t i = 0; i < requests.size(); i += 11) {
      const FrameDetections alone = rec.recognize(frame, {requests[i]});
      ASSERT_EQ(alone.boxes.size(), 1u);
      for (size_t c = 0; c < all.classes.size(); ++c)
        ASSERT_NEAR(all.boxes[i].log_prob[c], alone.boxes[0].log_prob[c], 1e-4)
            << "box " << i << (warm ? " after warmUp" : "");
    }
    auto best = [&](size_t i) {
      const auto& lp = all.boxes[i].log_prob;
      return all.classes[static_cast<size_t>(std::max_element(lp.begin(), lp.end()) - lp.begin())];
    };
    EXPECT_EQ(best(3), "disc");
    EXPECT_EQ(best(2 * Recognizer::kRowsPerPass + 1), "bar");  // in the third pass
  }
}

// Suppression after classification: of two boxes overlapping by IoU > 0.5 the one surer of an
// object class stays, whatever the order of the request; the background's probability does not
// count; IoU 0.5 itself is not suppressed; the survivors keep the request's order.
TEST(Recognizer, SuppressionKeepsTheSurerOfTwoOverlappingBoxes) {
  auto box = [](float x, float y, float w, float h, float p_object) {
    BoxDetection b;
    b.x = x, b.y = y, b.w = w, b.h = h;
    b.log_prob = {std::log(p_object), std::log(0.01f),
                  std::log(0.99f - p_object)};  // a, b, background
    return b;
  };
  FrameDetections d;
  d.classes = {"a", "b", "background"};
  d.boxes = {box(0, 0, 100, 60, 0.6f),     // 0: a part ranked first: IoU 0.6 with 1
             box(0, 0, 100, 100, 0.9f),    // 1: the whole, surer: kept
             box(0, 0, 100, 100, 0.9f),    // 2: the same box, as sure: the earlier (1) stays
             box(0, 50, 100, 100, 0.95f),  // 3: IoU 1/3 with 1, the surest: kept
             box(200, 0, 50, 50, 0.02f),   // 4: background 0.97, object 0.02: suppressed by 5
             box(200, 0, 50, 40, 0.05f),   // 5: IoU 0.8 with 4; background 0.94, object 0.05: kept
             box(300, 0, 100, 50, 0.5f),   // 6: IoU exactly 0.5 with 7: both kept
             box(300, 0, 50, 50, 0.4f)};   // 7
  for (size_t i = 0; i < d.boxes.size(); ++i) d.boxes[i].candidate_id = static_cast<int32_t>(i);
  FrameDetections none = d;
  EXPECT_EQ(suppressOverlaps(&none, 1.0), 0);
  EXPECT_EQ(none.boxes.size(), d.boxes.size());
  EXPECT_EQ(suppressOverlaps(&d, 0.5), 3);
  EXPECT_EQ(d.suppressed, 3);
  std::vector<int32_t> kept;
  for (const auto& b : d.boxes) kept.push_back(b.candidate_id);
  EXPECT_EQ(kept, (std::vector<int32_t>{1, 3, 5, 6, 7}));
}

// Suppression per class: a box is suppressed only by a surer box of the same most probable object
// class. A bowl behind a mug keeps its own box beside the pair's box that is surer of a mug; two
// boxes both surer of a mug still suppress each other.
TEST(Recognizer, SuppressionPerClassKeepsAnOverlappingBoxOfAnotherClass) {
  auto box = [](float x, float w, float p_a, float p_b) {
    BoxDetection b;
    b.x = x, b.y = 0, b.w = w, b.h = 100;
    b.log_prob = {std::log(p_a), std::log(p_b), std::log(1.f - p_a - p_b)};  // a, b, background
    return b;
  };
  FrameDetections d;
  d.classes = {"a", "b", "background"};
  d.boxes = {box(0, 100, 0.2f, 0.7f),   // 0: the pair, surest of b: kept
             box(0, 70, 0.6f, 0.1f),    // 1: IoU 0.7 with 0, surest of a: kept per class only
             box(10, 100, 0.1f, 0.6f),  // 2: IoU 0.82 with 0, also b, less sure: suppressed
             box(0, 65, 0.5f, 0.1f)};   // 3: IoU 0.93 with 1, also a, less sure: suppressed
  for (size_t i = 0; i < d.boxes.size(); ++i) d.boxes[i].candidate_id = static_cast<int32_t>(i);
  FrameDetections any_class = d;
  EXPECT_EQ(suppressOverlaps(&any_class, 0.5), 3);
  ASSERT_EQ(any_class.boxes.size(), 1u);
  EXPECT_EQ(any_class.boxes[0].candidate_id, 0);
  EXPECT_EQ(suppressOverlaps(&d, 0.5, /*per_class=*/true), 2);
  std::vector<int32_t> kept;
  for (const auto& b : d.boxes) kept.push_back(b.candidate_id);
  EXPECT_EQ(kept, (std::vector<int32_t>{0, 1}));
}

TEST(ModelFile, ReloadsToIdenticalPredictions) {
  const Trained& t = synthetic();
  const RecognizerModel loaded = loadModel(t.model_path);
  EXPECT_EQ(loaded.classifier.classes, t.model.classifier.classes);
  EXPECT_EQ(loaded.provenance, t.model.provenance);
  EXPECT_GT(loaded.params.shape_bins, 0);
  EXPECT_EQ(loaded.params.shape_bins, t.model.params.shape_bins);
  Recognizer a(std::make_shared<const RecognizerModel>(t.model), RecognizerOptions());
  Recognizer b(std::make_shared<const RecognizerModel>(loaded), RecognizerOptions());
  const cv::Mat frame = test::texturedFrame(31);
  const std::vector<BoxRequest> boxes = {
      {10, 20, 200, 150, 0}, {300, 100, 64, 64, 1}, {0, 0, 640, 480, 2}};
  const FrameDetections da = a.recognize(frame, boxes), db = b.recognize(frame, boxes);
  ASSERT_EQ(da.boxes.size(), 3u);
  ASSERT_EQ(db.boxes.size(), 3u);
  for (size_t i = 0; i < 3; ++i)
    EXPECT_EQ(da.boxes[i].log_prob, db.boxes[i].log_prob);  // bit for bit
}

// A model of format version 2 (no shape block) still loads and classifies as before: the version
// 3 file of a model without shape bins, rewritten as version 2 (its shape_bins field cut out).
TEST(ModelFile, AVersion2ModelWithoutShapeBlockStillLoads) {
  const Trained& t = synthetic();
  RecognizerModel plain = t.model;
  plain.params.shape_bins = 0;
  plain.classifier.weights = MatrixRM(t.model.classifier.weights.leftCols(plain.params.vladDims()));
  plain.exemplars = ExampleSet(plain.params.vladDims(), plain.params.pca_dims);
  const std::string dir = test::tempDir("model_v2");
  saveModel(plain, dir + "/v3.model");
  std::ifstream in(dir + "/v3.model", std::ios::binary);
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
  // Header 28 bytes; then step_px (4), bin_sizes_px (8 + 4 each), smoothing_magnif,
  // contrast_threshold, rgb_weight (8 each), pool_cell_px, pca_dims, vocabulary_size (4 each).
  const size_t at = 28 + 4 + 8 + 4 * plain.params.features.bin_sizes_px.size() + 24 + 12;
  int32_t field = -1;
  std::memcpy(&field, bytes.data() + at, 4);
  ASSERT_EQ(field, 0) << "the shape_bins field is not where version 3 puts it";
  std::vector<uint8_t> payload(bytes.begin() + 28, bytes.end());
  payload.erase(payload.begin() + static_cast<std::ptrdiff_t>(at - 28),
                payload.begin() + static_cast<std::ptrdiff_t>(at - 28 + 4));
  std::vector<uint8_t> v2 = modelFileBytes(payload);
  const uint32_t version = 2;
  std::memcpy(v2.data() + 8, &version, 4);
  const uint32_t header_crc = crc32(v2.data() + 16, 12, crc32(v2.data(), 12));
  std::memcpy(v2.data() + 12, &header_crc, 4);
  std::ofstream(dir + "/v2.model", std::ios::binary)
      .write(reinterpret_cast<const char*>(v2.data()), static_cast<std::streamsize>(v2.size()));
  const RecognizerModel loaded = loadModel(dir + "/v2.model");
  EXPECT_EQ(loaded.params.shape_bins, 0);
  Recognizer a(std::make_shared<const RecognizerModel>(plain), RecognizerOptions());
  Recognizer b(std::make_shared<const RecognizerModel>(loaded), RecognizerOptions());
  const cv::Mat frame = test::texturedFrame(32);
  const std::vector<BoxRequest> boxes = {{10, 20, 200, 150, 0}, {300, 100, 64, 96, 1}};
  const FrameDetections da = a.recognize(frame, boxes), db = b.recognize(frame, boxes);
  ASSERT_EQ(db.boxes.size(), 2u);
  for (size_t i = 0; i < 2; ++i) EXPECT_EQ(da.boxes[i].log_prob, db.boxes[i].log_prob);
}

TEST(ModelFile, TruncatedBitFlippedAndForeignFilesAreRefusedNamingTheFile) {
  const Trained& t = synthetic();
  const std::string dir = test::tempDir("recognizer_model_corrupt");
  const std::vector<char> good = readBytes(t.model_path);
  ASSERT_GT(good.size(), 1000u);

  const std::string truncated = dir + "/truncated.model";
  writeBytes(truncated,
             std::vector<char>(good.begin(), good.begin() + static_cast<long>(good.size() / 2)));
  std::string e = loadError(truncated);
  EXPECT_NE(e.find(truncated), std::string::npos) << e;
  EXPECT_NE(e.find("truncated"), std::string::npos) << e;

  const std::string flipped = dir + "/flipped.model";
  std::vector<char> bytes = good;
  bytes[bytes.size() / 3] ^= 0x10;
  writeBytes(flipped, bytes);
  e = loadError(flipped);
  EXPECT_NE(e.find(flipped), std::string::npos) << e;
  EXPECT_NE(e.find("checksum"), std::string::npos) << e;

  const std::string header = dir + "/header.model";
  bytes = good;
  bytes[17] ^= 0x01;  // payload size field
  writeBytes(header, bytes);
  e = loadError(header);
  EXPECT_NE(e.find("checksum"), std::string::npos) << e;

  const std::string foreign = dir + "/foreign.model";
  writeBytes(foreign, std::vector<char>(good.size(), 'x'));
  e = loadError(foreign);
  EXPECT_NE(e.find("not a slamaware recognizer model"), std::string::npos) << e;

  e = loadError(dir + "/missing.model");
  EXPECT_NE(e.find("missing.model"), std::string::npos) << e;
}

TEST(ModelFile, WritesAtomicallyOverAnOldModel) {
  const Trained& t = synthetic();
  const std::string dir = test::tempDir("recognizer_model_atomic");
  const std::string path = dir + "/m.model";
  writeBytes(path, std::vector<char>(10, 'o'));
  saveModel(t.model, path);
  EXPECT_EQ(readBytes(path), readBytes(t.model_path));
  for (const auto& entry : fs::directory_iterator(dir))
    EXPECT_EQ(entry.path().filename(), "m.model");  // no temp left
}

// Object sets of other categories (--background-objects) are background: a model of discs alone
// learns that bars are not discs; the other set's own discs are left out.
TEST(Training, ObjectsOfOtherCategoriesAreBackground) {
  const std::string dir = test::tempDir("recognizer_background_objects");
  const std::string objects = test::makeSyntheticObjectSet(dir + "/objects", 3, 10);
  fs::remove_all(objects + "/bar");
  const std::string others = test::makeSyntheticObjectSet(dir + "/others", 3, 10);
  TrainOptions o = testOptions();
  o.validation = false;
  o.background_views_per_instance = 6;
  TrainReport report;
  const RecognizerModel model = trainModel({objects}, {}, o, &report, "", {others});
  ASSERT_EQ(model.classifier.classes, (std::vector<std::string>{"disc", "background"}));
  EXPECT_EQ(report.train_crops, 3 * 10 * 2);     // the discs of --objects, mirrored
  EXPECT_EQ(report.train_negatives, 3 * 6 * 2);  // the bars: 6 views per instance, mirrored
  EXPECT_NE(model.provenance.find("\"role\":\"background\""), std::string::npos)
      << model.provenance;

  // Instances neither set holds.
  const std::string unseen = test::makeSyntheticObjectSet(dir + "/unseen", 5, 10);
  std::vector<LabeledCrop> crops;
  for (const auto& c : collectCrops({unseen}, 10))
    if (c.instance.back() == '4' || c.instance.back() == '5') crops.push_back(c);
  ASSERT_EQ(crops.size(), 40u);
  FrameEncoder enc(model.params, model.pca, model.vocabulary);
  const ExampleSet test_set = encodeCrops(crops, model.classifier.classes, {}, enc, false, {}, 1);
  int right = 0, bars = 0;
  MatrixRM x(1, test_set.dims()), s;
  for (int64_t i = 0; i < test_set.size(); ++i) {
    test_set.get(i, x.data());
    model.classifier.scores(x, &s);
    right += (s(0, 0) > s(0, 1) ? 0 : 1) == test_set.label(i);
    bars += test_set.label(i) == 1;
  }
  EXPECT_EQ(bars, 20);
  EXPECT_GE(right, 36) << "of 40 crops of discs and bars";

  // One category and nothing else: no background to tell it from.
  EXPECT_THROW(trainModel({objects}, {}, o, nullptr), DatasetError);
}

// train.classes: the model learns those categories; the object sets' others are background.
TEST(Training, CategoriesOutsideTheClassesOptionAreBackground) {
  const std::string dir = test::tempDir("recognizer_classes_option");
  const std::string objects = test::makeSyntheticObjectSet(dir + "/objects", 3, 10);
  TrainOptions o = testOptions();
  o.validation = false;
  o.classes = {"disc"};
  TrainReport report;
  const RecognizerModel model = trainModel({objects}, {}, o, &report);
  ASSERT_EQ(model.classifier.classes, (std::vector<std::string>{"disc", "background"}));
  EXPECT_EQ(report.train_crops, 3 * 10 * 2);      // the discs, mirrored
  EXPECT_EQ(report.train_negatives, 3 * 10 * 2);  // the bars, mirrored
  o.classes = {"disc", "cap"};
  EXPECT_THROW(trainModel({objects}, {}, o, nullptr), DatasetError) << "no crops of cap";
}

// The provenance names every set and scene with what was used of it and whether it is rendered
// or photographed, and its options are a config that trains the same model again.
TEST(Training, ProvenanceNamesTheDataAndItsOptionsTrainAgain) {
  const std::string dir = test::tempDir("recognizer_provenance");
  const std::string photographed = test::makeSyntheticObjectSet(dir + "/photographed", 2, 6);
  const std::string rendered = test::makeSyntheticObjectSet(dir + "/rendered", 2, 6);
  std::ofstream(rendered + "/set.yaml") << "name: rendered\nsource: synth (written by a test)\n";
  EXPECT_TRUE(ObjectSet::open(rendered).rendered());
  EXPECT_FALSE(ObjectSet::open(photographed).rendered());
  const std::string scenes = test::makeSyntheticScenes(dir + "/scenes", 6);
  TrainOptions o = testOptions();
  o.real_share = 0.4;
  o.real_copies = 1;
  const RecognizerModel model = trainModel({rendered, photographed}, {scenes}, o, nullptr);
  const nlohmann::json j = nlohmann::json::parse(model.provenance);
  ASSERT_EQ(j["object_sets"].size(), 2u);
  EXPECT_EQ(j["object_sets"][0]["kind"], "rendered");
  EXPECT_EQ(j["object_sets"][1]["kind"], "photographed");
  EXPECT_EQ(j["object_sets"][1]["crops_used"].get<int>(), 2 * 2 * 6);
  EXPECT_EQ(j["scenes"][0]["frames"].get<int>(), 6);
  EXPECT_GT(j["peak_rss_mb"].get<double>(), 0);
  // The printed report, and its config read back as the options it was trained with.
  const std::string text = provenanceText(model);
  EXPECT_NE(text.find(photographed), std::string::npos) << text;
  EXPECT_NE(text.find("validation"), std::string::npos) << text;
  const std::string config = dir + "/again.yaml";
  std::ofstream(config) << j["config"].get<std::string>();
  TrainOptions again = loadConfig<TrainOptions>(config, "train", false);
  EXPECT_TRUE(optionsEqual(again, o)) << j["config"].get<std::string>();
}

// Photographed and rendered examples of a class weigh real_share and 1 - real_share of it.
TEST(Training, PhotographsWeighTheSameShareOfEveryClass) {
  ExampleSet set(4, 2);
  const float x[4] = {1, 0, 0, 1};
  // class 0: 8 rendered, 2 photographed; class 1: 3 rendered only; class 2: 1 of each.
  for (int i = 0; i < 8; ++i) set.add(x, 0, -1, 0);
  for (int i = 0; i < 2; ++i) set.add(x, 0, -1, 1);
  for (int i = 0; i < 3; ++i) set.add(x, 1, -1, 0);
  set.add(x, 2, -1, 0);
  set.add(x, 2, -1, 1);
  balanceDomains(&set, 3, 0.25);
  EXPECT_FLOAT_EQ(set.weight(0), 0.75f * 10 / 8);
  EXPECT_FLOAT_EQ(set.weight(8), 0.25f * 10 / 2);
  EXPECT_FLOAT_EQ(set.weight(10), 1.f);
  EXPECT_FLOAT_EQ(set.weight(13), 0.75f * 2);
  EXPECT_FLOAT_EQ(set.weight(14), 0.25f * 2);
  double photographed = 0, all = 0;
  for (int64_t i = 0; i < 10; ++i) {
    all += set.weight(i);
    photographed += set.domain(i) ? set.weight(i) : 0;
  }
  EXPECT_NEAR(all, 10, 1e-5);
  EXPECT_NEAR(photographed / all, 0.25, 1e-6);
  balanceDomains(&set, 3, 0);  // off: unchanged
  EXPECT_FLOAT_EQ(set.weight(8), 0.25f * 10 / 2);
}

// Held-out evaluation with extra training sets (slamaware-eval-objects --extra-training): their
// crops join the training data of every fold, under their own instance names, and are never tested.
TEST(Training, ExtraTrainingSetsJoinEveryFoldAndAreNeverTested) {
  const std::string dir = test::tempDir("recognizer_extra_training");
  const std::string set = test::makeSyntheticObjectSet(dir + "/set", 2, 8);
  const std::string extra = test::makeSyntheticObjectSet(dir + "/extra", 3, 8);
  TrainOptions o = testOptions();
  o.vocabulary_descriptors = 10000;
  const HeldOutResult plain = leaveOneInstanceOut(set, o);
  const HeldOutResult with = leaveOneInstanceOut(set, o, {}, {extra});
  EXPECT_EQ(plain.extra_crops, 0);
  EXPECT_EQ(with.extra_crops, 3 * 2 * 8);  // 3 instances of bar and disc, 8 views each
  EXPECT_EQ(with.crops, 2 * 2 * 8);        // only the evaluated set's crops are tested...
  EXPECT_EQ(with.instances, plain.instances);
  ASSERT_EQ(with.instance_accuracy.size(), 4u);  // ...one fold per instance of it
  for (const auto& [instance, accuracy] : with.instance_accuracy)
    EXPECT_EQ(instance.find('/'), std::string::npos) << instance;
  // A fold of the plain set learns each category from one instance; three more help.
  EXPECT_GE(with.accuracy(), plain.accuracy());
  EXPECT_GE(with.accuracy(), 90.0);
  EXPECT_EQ(collectNamedCrops(extra, 1).front().instance, "extra/bar_1");
}

// A loose crop (a small object on a cloth, as UMD's) is boxed around its object; a set whose
// objects fill their crops (as UW RGB-D's) is left whole, even where its object is inside.
TEST(Training, LooseCropsAreBoxedAroundTheirObjectAndTightOnesKeptWhole) {
  const std::string dir = test::tempDir("loose_crops");
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> jitter(-30, 30);
  std::map<std::string, cv::Rect> truth;
  for (int v = 0; v < 6; ++v) {
    // 220 x 180: a grey wall strip, a blue cloth with noise, a yellow mug-like block with stripes.
    cv::Mat loose(180, 220, CV_8UC3, cv::Scalar(120, 40, 40));
    loose(cv::Rect(0, 0, 220, 20)).setTo(cv::Scalar(150, 150, 150));
    cv::Mat noise(loose.size(), CV_8UC3);
    cv::randn(noise, 0, 8);
    loose += noise;
    const cv::Rect object(80 + jitter(rng), 60 + jitter(rng) / 2, 56, 64);
    loose(object).setTo(cv::Scalar(40, 200, 230));
    for (int y = object.y + 8; y < object.br().y; y += 16)
      loose(cv::Rect(object.x, y, object.width, 4)).setTo(cv::Scalar(30, 30, 160));
    const std::string name = dir + "/loose/coffee_mug/coffee_mug_101/coffee_mug_101_1_" +
                             std::to_string(v) + "_crop.png";
    fs::create_directories(fs::path(name).parent_path());
    writeImage(name, loose);
    truth[name] = object;
    // The same object filling a crop of its own, with a little table at one corner.
    cv::Mat tight = loose(object + cv::Size(6, 6) - cv::Point(3, 3)).clone();
    const std::string tight_dir = dir + "/tight/coffee_mug/coffee_mug_1";
    fs::create_directories(tight_dir);
    writeImage(tight_dir + "/coffee_mug_1_1_" + std::to_string(v) + "_crop.png", tight);
  }
  for (const LabeledCrop& c : collectCrops({dir + "/loose"}, 0)) {
    const cv::Rect t = truth.at(c.path);
    EXPECT_GE((c.object_box & t).area(), 0.8 * (c.object_box | t).area())
        << c.path << ": boxed at " << c.object_box << ", the object is at " << t;
  }
  for (const LabeledCrop& c : collectCrops({dir + "/tight"}, 0))
    EXPECT_TRUE(c.object_box.empty())
        << c.path << ": a crop framed by its object, boxed at " << c.object_box;
}

// Real data: train on two apples and two balls, classify two other instances.
TEST(Training, SeparatesApplesFromBallsOnUnseenUwInstances) {
  const std::string uw = test::sharedData("objects/uw_rgbd_apple_ball");
  SKIP_WITHOUT_SHARED_DATA(uw);
  const std::string dir = test::tempDir("recognizer_uw_subset");
  auto link = [&](const std::string& set, const std::string& category,
                  const std::string& instance) {
    fs::create_directories(dir + "/" + set + "/" + category);
    fs::create_directory_symlink(uw + "/" + category + "/" + instance,
                                 dir + "/" + set + "/" + category + "/" + instance);
  };
  link("train", "apple", "apple_1");
  link("train", "apple", "apple_3");
  link("train", "ball", "ball_1");
  link("train", "ball", "ball_2");
  link("test", "apple", "apple_5");
  link("test", "ball", "ball_3");
  TrainOptions o = testOptions();
  o.max_views_per_instance = 40;
  o.validation = false;
  TrainReport report;
  const RecognizerModel model = trainModel({dir + "/train"}, {}, o, &report);
  EXPECT_EQ(model.classifier.classes, (std::vector<std::string>{"apple", "ball"}));
  FrameEncoder enc(model.params, model.pca, model.vocabulary);
  const auto crops = collectCrops({dir + "/test"}, 30);
  ASSERT_EQ(crops.size(), 60u);
  const ExampleSet test_set = encodeCrops(crops, model.classifier.classes, {}, enc);
  int right = 0;
  MatrixRM x(1, test_set.dims()), s;
  for (int64_t i = 0; i < test_set.size(); ++i) {
    test_set.get(i, x.data());
    model.classifier.scores(x, &s);
    right += (s(0, 0) > s(0, 1) ? 0 : 1) == test_set.label(i);
  }
  EXPECT_GE(right, 54) << "of 60 crops of apple_5 and ball_3";
}

// Real data, the fold of make eval's leave-one-instance-out that fails without rendered objects:
// the UW set's ball_1 (a brown American football) when "ball" is learnt from its two white balls
// alone is called apple in most views. config/objects/apple_ball.yaml's rendered apples and balls
// (make eval's --extra-training for this set) must bring it over the 61 % the set's 95 % needs.
TEST(Training, RenderedApplesAndBallsTeachTheUwBallCategory) {
  const std::string uw = test::sharedData("objects/uw_rgbd_apple_ball");
  SKIP_WITHOUT_SHARED_DATA(uw);
  const std::string dir = test::tempDir("recognizer_uw_rendered");
  const std::string rendered = dir + "/apple_ball";
  const auto set_options =
      synth::loadObjectSetOptions(test::sourcePath("config/objects/apple_ball.yaml"));
  synth::writeObjectSet(set_options, rendered, -1, false);
  const TrainOptions o;  // as make eval trains each fold
  const HeldOutResult plain = leaveOneInstanceOut(uw, o, {}, {}, {"ball_1"});
  const HeldOutResult with = leaveOneInstanceOut(uw, o, {}, {rendered}, {"ball_1"});
  ASSERT_EQ(with.instance_accuracy.count("ball_1"), 1u);
  EXPECT_EQ(with.crops, 72);
  EXPECT_EQ(with.extra_crops, 2 * 30 * 72);
  EXPECT_GE(with.instance_accuracy.at("ball_1"), 61.0)
      << "without the rendered ones: " << plain.accuracy() << " %";
  EXPECT_GE(with.instance_accuracy.at("ball_1"), plain.instance_accuracy.at("ball_1") + 20.0);
  EXPECT_THROW(leaveOneInstanceOut(uw, o, {}, {}, {"ball_9"}), DatasetError);
}

// make eval's command line: `slamaware-eval-objects ... --extra-training SET=DIR <sequences>`. Each
// of the repeatable options takes one value, so the sequence folders after them stay sequences
// (a list option swallowed them, and make eval read the suite's scenes as object sets).
TEST(EvalObjectsCommandLine, SequenceFoldersAfterARepeatableOptionAreSequences) {
  const std::string dir = test::tempDir("eval_objects_cli");
  const std::string scene = dir + "/kitchen";
  const std::string synth = test::binPath("slamaware-synth") + " scene --quiet --config " +
                            test::sourcePath("config/scenes/kitchen_wood.yaml") +
                            " --frames 5 --out " + scene + " > " + dir + "/synth.log 2>&1";
  ASSERT_EQ(std::system(synth.c_str()), 0);
  const std::string out = dir + "/objects.json";
  const std::string cmd =
      test::binPath("slamaware-eval-objects") + " --out " + out + " --no-object-sets --model " +
      test::sourcePath("models/recognizer.model") + " --hold-out ball_1 --hold-out cap_1" +
      " --extra-training " + dir + "/extra " + scene + " > " + dir + "/eval.log 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << "see " << dir << "/eval.log";
  std::ifstream in(out);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"kitchen\""), std::string::npos)
      << "the scene was not evaluated as a sequence: " << text;
  EXPECT_NE(text.find("\"gt_boxes\""), std::string::npos) << text;
}

// A sequence of separate views (boxes, no ground-truth poses, as uw_scenes_v2_public) has every
// boxed frame's boxes classified; the same frames as a video (with poses) only every 5th frame's.
TEST(EvalObjectsCommandLine, EveryBoxedFrameOfASequenceOfSeparateViewsIsClassified) {
  const std::string dir = test::tempDir("eval_objects_views");
  const std::string video = dir + "/kitchen", views = dir + "/kitchen_views";
  const std::string synth = test::binPath("slamaware-synth") + " scene --quiet --config " +
                            test::sourcePath("config/scenes/kitchen_wood.yaml") +
                            " --frames 7 --out " + video + " > " + dir + "/synth.log 2>&1";
  ASSERT_EQ(std::system(synth.c_str()), 0);
  fs::copy(video, views, fs::copy_options::recursive);
  fs::remove(views + "/groundtruth.txt");
  // Taken for a photographed sequence (no depth, another source), so selective search runs on it
  // too.
  fs::remove_all(views + "/depth");
  SequenceInfo info = readSequenceInfo(views + "/sequence.yaml");
  info.source = "frames copied by a test";
  writeSequenceInfo(views + "/sequence.yaml", info);
  const std::vector<GroundTruthBox> boxes = readBoxes(video + "/boxes.csv");
  const int64_t all = static_cast<int64_t>(boxes.size());
  const int64_t first = std::count_if(boxes.begin(), boxes.end(),
                                      [](const GroundTruthBox& b) { return b.frame % 5 == 0; });
  ASSERT_GT(all, first) << "the test needs boxes on frames other than 0 and 5";
  const std::string out = dir + "/objects.json";
  const std::string cmd =
      test::binPath("slamaware-eval-objects") + " --out " + out + " --no-object-sets --model " +
      test::sourcePath("models/recognizer.model") + " --ss-boxes 50 " + "--boxes-csv " + dir +
      "/boxes.csv " + video + " " + views + " > " + dir + "/eval.log 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << "see " << dir << "/eval.log";
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(out));
  EXPECT_EQ(j["sequences"]["kitchen"]["gt_boxes"]["boxes"].get<int64_t>(), first);
  EXPECT_EQ(j["sequences"]["kitchen_views"]["gt_boxes"]["boxes"].get<int64_t>(), all);
  int64_t per_class = 0;
  for (const auto& [c, v] : j["sequences"]["kitchen_views"]["gt_boxes"]["per_class"].items())
    per_class += v["boxes"].get<int64_t>();
  EXPECT_EQ(per_class, all);
  EXPECT_FALSE(j["sequences"]["kitchen"].contains("single_view_ss"))
      << "a rendered video has the pipeline's mAP";
  ASSERT_TRUE(j["sequences"]["kitchen_views"].contains("single_view_ss"));
  EXPECT_EQ(j["sequences"]["kitchen_views"]["single_view_ss"]["frames_evaluated"].get<int>(), 7);
  // --boxes-csv: every scored box once, called what the confusion matrix counts, by the best of
  // its class probabilities.
  std::ifstream csv(dir + "/boxes.csv");
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  EXPECT_EQ(line.rfind("sequence,frame,x,y,w,h,class,instance,called,p_", 0), 0u) << line;
  const std::vector<std::string> classes =
      j["sequences"]["kitchen_views"]["gt_boxes"]["classes"].get<std::vector<std::string>>();
  std::map<std::string, int64_t> rows, right;
  while (std::getline(csv, line)) {
    std::vector<std::string> f;
    std::stringstream in(line);
    for (std::string v; std::getline(in, v, ',');) f.push_back(v);
    ASSERT_EQ(f.size(), 9 + classes.size()) << line;
    ++rows[f[0]];
    const auto called = std::find(classes.begin(), classes.end(), f[8]);
    ASSERT_NE(called, classes.end()) << line;
    for (size_t c = 0; c < classes.size(); ++c)
      EXPECT_GE(std::stod(f[9 + static_cast<size_t>(called - classes.begin())]),
                std::stod(f[9 + c]))
          << line;
    const bool known = std::find(classes.begin(), classes.end(), f[6]) != classes.end();
    right[f[0]] += f[8] == (known ? f[6] : std::string("background"));
  }
  EXPECT_EQ(rows["kitchen"], first);
  EXPECT_EQ(rows["kitchen_views"], all);
  int64_t diagonal = 0;
  const auto confusion = j["sequences"]["kitchen_views"]["gt_boxes"]["confusion"];
  for (size_t c = 0; c < classes.size(); ++c) diagonal += confusion[c][c].get<int64_t>();
  EXPECT_EQ(right["kitchen_views"], diagonal);
}

namespace {

// A third category for adding classes: yellow-violet checkerboards (corners, no curves).
std::string writeCheckerSet(const std::string& dir, int first_instance, int instances, int views) {
  for (int i = first_instance; i < first_instance + instances; ++i) {
    const std::string folder = dir + "/checker/checker_" + std::to_string(i);
    fs::create_directories(folder);
    for (int v = 0; v < views; ++v) {
      std::mt19937 rng(static_cast<uint32_t>(7000 * i + v));
      std::uniform_real_distribution<double> u(0, 1);
      cv::Mat img(72, 72, CV_8UC3,
                  cv::Scalar(150 + 20 * u(rng), 150 + 20 * u(rng), 150 + 20 * u(rng)));
      const int cell = 7 + (i % 3) + static_cast<int>(3 * u(rng));
      const cv::Scalar a(30 + 20 * u(rng), 200 + 30 * u(rng), 220),
          b(160, 40 + 30 * u(rng), 120 + 40 * u(rng));
      const int x0 = 8 + static_cast<int>(8 * u(rng)), y0 = 8 + static_cast<int>(8 * u(rng));
      for (int y = 0; y * cell + y0 < 64; ++y)
        for (int x = 0; x * cell + x0 < 64; ++x)
          cv::rectangle(img, cv::Rect(x0 + x * cell, y0 + y * cell, cell, cell),
                        (x + y) % 2 ? a : b, cv::FILLED);
      cv::Mat noise(72, 72, CV_8UC3);
      cv::randn(noise, 0, 6);
      img += noise;
      cv::imwrite(
          folder + "/checker_" + std::to_string(i) + "_1_" + std::to_string(v) + "_crop.png", img);
    }
  }
  return dir;
}

// Share of `images` the recognizer calls `want` (each image one box covering it).
double calledAs(Recognizer& r, const std::vector<cv::Mat>& images, const std::string& want) {
  int right = 0;
  for (const cv::Mat& img : images) {
    const FrameDetections d =
        r.recognize(img, {{0, 0, static_cast<float>(img.cols), static_cast<float>(img.rows), 0}});
    if (d.boxes.empty()) continue;
    const auto& lp = d.boxes[0].log_prob;
    right +=
        d.classes[static_cast<size_t>(std::max_element(lp.begin(), lp.end()) - lp.begin())] == want;
  }
  return 100.0 * right / static_cast<double>(images.size());
}

}  // namespace

// slamaware-train --base: a class is added from its views alone (the base model's exemplars stand
// in for its training data as negatives). The new class is recognised on unseen instances, the old
// classifiers are kept as they were (and their classes recognised as well as before), a class the
// base has is refused without --replace, and a model without exemplars (an older file) is refused
// with what to do.
TEST(AddClasses, ANewClassFromItsViewsAloneIsRecognisedAndTheOldOnesKeep) {
  const Trained& t = synthetic();
  ASSERT_GT(t.model.exemplars.size(), 0);
  const std::string dir = test::tempDir("recognizer_add_classes");
  writeCheckerSet(dir + "/new", 1, 3, 10);
  AddClassesReport report;
  TrainOptions o = testOptions();
  const RecognizerModel added = addClasses(t.model, {dir + "/new"}, o, false, &report);
  EXPECT_EQ(added.classifier.classes,
            (std::vector<std::string>{"bar", "disc", "checker", "background"}));
  EXPECT_EQ(report.added, (std::vector<std::string>{"checker"}));
  EXPECT_EQ(report.positives, 60);  // 30 views, mirrored
  EXPECT_GT(added.exemplars.size(), t.model.exemplars.size());
  for (int c = 0; c < 2; ++c) {  // the base's classifiers are kept as they were
    EXPECT_EQ(added.classifier.weights.row(c), t.model.classifier.weights.row(c)) << c;
    EXPECT_EQ(added.classifier.bias[c], t.model.classifier.bias[c]) << c;
  }
  EXPECT_EQ(added.classifier.weights.row(3), t.model.classifier.weights.row(2)) << "background";
  saveModel(added, dir + "/added.model");
  EXPECT_NE(provenanceText(loadModel(dir + "/added.model")).find("classes checker added"),
            std::string::npos);

  std::vector<cv::Mat> checkers, bars, discs;
  writeCheckerSet(dir + "/unseen", 11, 3, 6);
  for (const auto& c : collectNamedCrops(dir + "/unseen", 0))
    checkers.push_back(cv::imread(c.path));
  for (int i = 4; i < 6; ++i)  // instances the base model did not see (it has 1-3)
    for (int v = 0; v < 9; ++v) {
      bars.push_back(test::syntheticObjectView("bar", i, v, 72));
      discs.push_back(test::syntheticObjectView("disc", i, v, 72));
    }
  Recognizer before(std::make_shared<const RecognizerModel>(t.model), RecognizerOptions());
  Recognizer after(std::make_shared<const RecognizerModel>(added), RecognizerOptions());
  EXPECT_GE(calledAs(after, checkers, "checker"), 90.0);
  for (const auto& [name, views] : {std::pair{"bar", &bars}, std::pair{"disc", &discs}}) {
    const double was = calledAs(before, *views, name), is = calledAs(after, *views, name);
    std::printf("%s: %.1f %% before, %.1f %% after; checker %.1f %%\n", name, was, is,
                calledAs(after, checkers, "checker"));
    EXPECT_GE(is, was - 10.0) << name;
    EXPECT_GE(is, 80.0) << name;
  }

  const std::string again = test::makeSyntheticObjectSet(dir + "/discs", 1, 4);
  try {
    addClasses(added, {again}, o, false, nullptr);
    ADD_FAILURE() << "a class the model has was added again";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("already in the base model"), std::string::npos)
        << e.what();
  }
  RecognizerModel old = t.model;
  old.exemplars = ExampleSet(old.params.encodedDims(), old.params.pca_dims);
  try {
    addClasses(old, {dir + "/new"}, o, false, nullptr);
    ADD_FAILURE() << "a model without exemplars was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no exemplars"), std::string::npos) << e.what();
  }
}
