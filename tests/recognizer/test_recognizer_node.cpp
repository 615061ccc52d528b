// slamaware-recognizer as a process, in a private network namespace: it answers every PROPOSALS
// message in lockstep, keeps running on a proposal for a frame it never saw, boxes outside the
// image, zero-size and non-finite boxes, a corrupt JPEG, undecodable messages, a model lacking
// classes the config names, and a missing model; RECOGNIZER_STATUS counts each of them.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <thread>

#include "common/bus/bus.h"
#include "common/bus/image_msg.h"
#include "procs/recognizer/model.h"
#include "slamaware/detections_t.hpp"
#include "slamaware/image_t.hpp"
#include "slamaware/proposals_t.hpp"
#include "slamaware/status_t.hpp"
#include "tests/recognizer/synthetic_data.h"
#include "tests/support/test_support.h"
#include "tools/train/trainer.h"

using namespace slamaware;
using namespace slamaware::recognizer;
using namespace std::chrono_literals;

namespace {

std::string writeConfig(const std::string& dir, const std::string& model,
                        const std::string& expected) {
  const std::string path = dir + "/recognizer.yaml";
  std::ofstream f(path);
  f << "recognizer:\n  model: " << model << "\n  expected_classes: " << expected
    << "\n  pending_timeout_s: 0.5\n  model_retry_s: 0.5\n";
  return path;
}

// PROPOSALS of frame `seq`: every candidate seen from `degrees` round the vertical axis; by default
// 34 degrees further round at every seq, so that every frame is a new view of every candidate.
proposals_t proposals(int32_t seq, const std::vector<std::array<float, 4>>& boxes,
                      float degrees = NAN) {
  const float a = (std::isnan(degrees) ? 34.4f * static_cast<float>(seq) : degrees) *
                  static_cast<float>(M_PI) / 180.f;
  proposals_t p;
  p.utime = 1000000 + seq * 33333;
  p.seq = seq;
  p.map_id = 1;
  p.num_boxes = static_cast<int32_t>(boxes.size());
  for (size_t i = 0; i < boxes.size(); ++i) {
    box_t b;
    b.x = boxes[i][0];
    b.y = boxes[i][1];
    b.w = boxes[i][2];
    b.h = boxes[i][3];
    p.boxes.push_back(b);
    p.candidate_ids.push_back(100 + static_cast<int32_t>(i));
    p.median_depth.push_back(1.f);
    p.view_direction.push_back({std::sin(a), 0.f, std::cos(a)});
  }
  return p;
}

// 150 boxes of many sizes spread over a 640 x 480 frame: a frame that takes a while to classify.
std::vector<std::array<float, 4>> manyBoxes() {
  std::vector<std::array<float, 4>> boxes;
  for (int i = 0; i < 150; ++i)
    boxes.push_back({static_cast<float>(7 * (i % 50)),
                     static_cast<float>(20 * (i / 50) + 5 * i % 17),
                     static_cast<float>(60 + i % 7 * 30), static_cast<float>(50 + i % 5 * 40)});
  return boxes;
}

int64_t counter(const status_t& s, const std::string& name) {
  for (int i = 0; i < s.num_counters; ++i)
    if (s.counter_names[static_cast<size_t>(i)] == name)
      return s.counter_values[static_cast<size_t>(i)];
  return 0;
}

struct Listener {
  Bus bus{test::testUrl()};
  std::map<int32_t, detections_t> detections;
  std::vector<int32_t> order;  ///< seqs in the order their DETECTIONS came
  int answers = 0;
  status_t last_status{};
  bool have_status = false;
  int statuses = 0;
  Listener() {
    bus.subscribe<detections_t>("DETECTIONS", [this](const detections_t& d) {
      detections[d.seq] = d;
      order.push_back(d.seq);
      ++answers;
    });
    bus.subscribe<status_t>("RECOGNIZER_STATUS", [this](const status_t& s) {
      last_status = s;
      have_status = true;
      ++statuses;
    });
  }
  bool pump(const std::function<bool()>& done, std::chrono::milliseconds timeout) {
    return test::waitUntil(
        [&] {
          bus.handle(10);
          return done();
        },
        timeout);
  }
};

// A small model of the synthetic object set (quick options; seed and epochs tell two apart).
RecognizerModel smallModel(const std::string& objects, int seed = 7, int epochs = 5) {
  TrainOptions o;
  o.vocabulary_descriptors = 5000;
  o.kmeans_iterations = 10;
  o.sgd.epochs = epochs;
  o.seed = seed;
  o.validation = false;
  return trainModel({objects}, {}, o, nullptr);
}

// A small model of "bar" and "disc" (no background class: the node appends it) in dir/model.bin,
// and a config naming it and the `expected` classes; returns the config's path.
std::string configWithSmallModel(const std::string& dir, const std::string& expected) {
  saveModel(smallModel(test::makeSyntheticObjectSet(dir + "/objects", 2, 6)), dir + "/model.bin");
  return writeConfig(dir, dir + "/model.bin", expected);
}

}  // namespace

TEST(RecognizerNode, SurvivesBadInputAndCountsIt) {
  const std::string dir = test::tempDir("recognizer_node");
  const std::string config = configWithSmallModel(dir, "[disc, bar, mug]");

  Listener l;
  test::ChildProcess node({test::binPath("slamaware-recognizer"), "--config", config, "--lcm-url",
                           test::testUrl(), "--lockstep"},
                          dir + "/node.log");
  ASSERT_TRUE(l.pump([&] { return l.have_status; }, 10s)) << node.log();

  cv::Mat frame = test::texturedFrame(4);
  test::syntheticObjectView("disc", 1, 3, 96).copyTo(frame(cv::Rect(200, 150, 96, 96)));
  image_t good0 = makeImageMessage(frame, 1000000, 0, image_t::PIXEL_FORMAT_JPEG);
  image_t corrupt1 = good0;
  corrupt1.seq = 1;
  corrupt1.utime += 33333;
  for (size_t i = corrupt1.data.size() / 4; i < corrupt1.data.size(); ++i)
    corrupt1.data[i] = 0;  // JPEG body wiped
  image_t good2 = makeImageMessage(frame, 1066666, 2, image_t::PIXEL_FORMAT_JPEG);
  image_t good4 =
      makeImageMessage(frame, 1133332, 4, image_t::PIXEL_FORMAT_JPEG);  // seq 3 never sent

  l.bus.publish("CAMERA", good0);
  l.bus.publish("CAMERA", corrupt1);
  l.bus.publish("CAMERA", good2);
  l.bus.publish("CAMERA", good4);
  l.bus.handle(50);
  const float nan = std::nanf("");
  // seq 0: one good box, one partly outside (clipped), and four unusable ones.
  l.bus.publish("PROPOSALS", proposals(0, {{200, 150, 96, 96},
                                           {-20, -20, 60, 60},
                                           {700, 10, 50, 50},
                                           {10, 10, 0, 20},
                                           {10, 10, 20, -5},
                                           {nan, 10, 20, 20}}));
  l.bus.publish("PROPOSALS", proposals(1, {{200, 150, 96, 96}}));  // its JPEG is corrupt
  l.bus.publish("PROPOSALS", proposals(2, {}));                    // no boxes
  l.bus.publish("PROPOSALS", proposals(3, {{200, 150, 96, 96}}));  // frame 3 was never sent
  l.bus.publish("PROPOSALS", proposals(9, {{200, 150, 96, 96}}));  // frame 9 never comes (time-out)
  const std::vector<uint8_t> junk(100, 0xAB);
  l.bus.publishRaw("PROPOSALS", junk.data(), junk.size());  // not a proposals_t at all
  // seq 4: two boxes overlapping by IoU 0.98: the less confident is not published.
  l.bus.publish("PROPOSALS", proposals(4, {{0, 0, 640, 480}, {0, 0, 640, 470}}));

  ASSERT_TRUE(l.pump([&] { return l.answers >= 6; }, 20s)) << l.answers << " answers\n"
                                                           << node.log();
  for (int32_t seq : {0, 1, 2, 3, 4, 9})
    ASSERT_TRUE(l.detections.count(seq)) << "no DETECTIONS for seq " << seq;
  EXPECT_EQ(l.answers, 6);  // exactly one per PROPOSALS message

  const detections_t& d0 = l.detections[0];
  EXPECT_EQ(d0.class_names, (std::vector<std::string>{"bar", "disc", "background"}));
  ASSERT_EQ(d0.num_boxes, 2);
  EXPECT_EQ(d0.candidate_ids, (std::vector<int32_t>{100, 101}));
  EXPECT_FLOAT_EQ(d0.boxes[1].x, 0.f);  // clipped to the image
  EXPECT_FLOAT_EQ(d0.boxes[1].w, 40.f);
  EXPECT_EQ(d0.encode_ms, 0.f);  // lockstep: no timing in the output
  for (const auto& row : d0.log_prob) {
    double sum = 0;
    for (float lp : row) sum += std::exp(static_cast<double>(lp));
    EXPECT_NEAR(sum, 1.0, 1e-4);
  }
  EXPECT_EQ(l.detections[1].num_boxes, 0);
  EXPECT_EQ(l.detections[2].num_boxes, 0);
  EXPECT_EQ(l.detections[3].num_boxes, 0);
  EXPECT_EQ(l.detections[9].num_boxes, 0);
  EXPECT_EQ(l.detections[4].num_boxes, 1);

  // The heartbeat counts every reject (it is published once a second).
  ASSERT_TRUE(l.pump(
      [&] {
        return l.have_status && counter(l.last_status, "boxes_rejected") >= 4 &&
               counter(l.last_status, "proposals_without_frame") >= 2;
      },
      5s))
      << node.log();
  const status_t& s = l.last_status;
  EXPECT_EQ(counter(s, "boxes_rejected"), 4);
  EXPECT_EQ(counter(s, "boxes_rejected.outside_image"), 1);
  EXPECT_EQ(counter(s, "boxes_rejected.zero_size"), 2);
  EXPECT_EQ(counter(s, "boxes_rejected.not_finite"), 1);
  EXPECT_EQ(counter(s, "boxes_clipped"), 1);
  EXPECT_EQ(counter(s, "boxes_suppressed"), 1);
  EXPECT_EQ(counter(s, "proposals_without_frame"), 2);
  EXPECT_EQ(counter(s, "frames_corrupt"), 1);
  EXPECT_EQ(counter(s, "classes_missing"), 1);
  EXPECT_EQ(counter(s, "rejected.CAMERA"), 1);
  EXPECT_EQ(counter(s, "rejected.PROPOSALS"), 3);  // 2 without frame + 1 undecodable
  EXPECT_EQ(s.frames_processed, 3);                // seq 0, 2 and 4 had a decodable frame
  EXPECT_EQ(s.state, status_t::STATE_DEGRADED);    // the model lacks "mug"
  EXPECT_NE(s.message.find("mug"), std::string::npos) << s.message;
  EXPECT_TRUE(node.running()) << node.log();
  EXPECT_EQ(node.stop(), 0) << node.log();
}

TEST(RecognizerNode, WithoutAModelItAnswersEmptyAndReportsIt) {
  const std::string dir = test::tempDir("recognizer_node_nomodel");
  const std::string config = writeConfig(dir, dir + "/absent.model", "[]");
  Listener l;
  test::ChildProcess node({test::binPath("slamaware-recognizer"), "--config", config, "--lcm-url",
                           test::testUrl(), "--lockstep"},
                          dir + "/node.log");
  ASSERT_TRUE(l.pump([&] { return l.have_status; }, 10s)) << node.log();
  l.bus.publish("CAMERA", makeImageMessage(test::texturedFrame(1, 320, 240), 5, 0,
                                           image_t::PIXEL_FORMAT_JPEG));
  l.bus.handle(50);
  l.bus.publish("PROPOSALS", proposals(0, {{10, 10, 50, 50}}));
  ASSERT_TRUE(l.pump([&] { return l.answers >= 1; }, 10s)) << node.log();
  EXPECT_EQ(l.detections[0].num_boxes, 0);
  ASSERT_TRUE(l.pump([&] { return counter(l.last_status, "model_load_failures") >= 1; }, 5s));
  EXPECT_EQ(l.last_status.state, status_t::STATE_DEGRADED);
  EXPECT_NE(l.last_status.message.find("absent.model"), std::string::npos) << l.last_status.message;
  EXPECT_TRUE(node.running());
  EXPECT_EQ(node.stop(), 0) << node.log();
}

namespace {

std::vector<uint8_t> bytesOf(const detections_t& d) {
  std::vector<uint8_t> b(static_cast<size_t>(d.getEncodedSize()));
  d.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

// Replaces `path` as an editor or a copy would not, but as saveModel does: written aside, renamed.
void replaceFile(const std::string& path, const std::string& bytes) {
  {
    std::ofstream f(path + ".new", std::ios::binary);
    f << bytes;
  }
  ASSERT_EQ(std::rename((path + ".new").c_str(), path.c_str()), 0);
}

}  // namespace

// Live reload: a model file replaced under the running node is swapped in between two frames (no
// frame is lost in lockstep) and what follows is byte-identical to a node started with the new
// model; a damaged replacement is refused with the reason and the previous model keeps answering;
// `slamaware-ctl reload recognizer` reloads on demand and says so.
TEST(RecognizerNode, AReplacedModelIsSwappedInLiveAndABadOneRefused) {
  const std::string dir = test::tempDir("recognizer_node_reload");
  const std::string objects = test::makeSyntheticObjectSet(dir + "/objects", 2, 6);
  const RecognizerModel a = smallModel(objects), b = smallModel(objects, 11, 3);
  const std::string model = dir + "/model.bin";
  saveModel(a, model);
  saveModel(b, dir + "/b.model");
  std::string b_bytes;
  {
    std::ifstream f(dir + "/b.model", std::ios::binary);
    b_bytes.assign(std::istreambuf_iterator<char>(f), {});
  }
  std::ofstream(dir + "/recognizer.yaml")
      << "recognizer:\n  model: " << model << "\n  model_watch_s: 0.01\n";

  cv::Mat frame = test::texturedFrame(5);
  test::syntheticObjectView("disc", 1, 3, 96).copyTo(frame(cv::Rect(200, 150, 96, 96)));
  const auto send = [&](Bus& bus, int32_t seq) {
    bus.publish("CAMERA",
                makeImageMessage(frame, 1000000 + seq * 33333, seq, image_t::PIXEL_FORMAT_JPEG));
    bus.handle(20);
    bus.publish("PROPOSALS", proposals(seq, {{200, 150, 96, 96}, {60, 40, 120, 90}}));
  };
  const auto start = [&](const std::string& config, const std::string& log) {
    return std::make_unique<test::ChildProcess>(
        std::vector<std::string>{test::binPath("slamaware-recognizer"), "--config", config,
                                 "--lcm-url", test::testUrl(), "--lockstep"},
        log);
  };

  Listener l;
  auto node = start(dir + "/recognizer.yaml", dir + "/node.log");
  ASSERT_TRUE(l.pump([&] { return l.have_status; }, 10s)) << node->log();
  send(l.bus, 0);
  ASSERT_TRUE(l.pump([&] { return l.answers >= 1; }, 10s)) << node->log();

  // Replaced under it; a frame sent at once is answered (by the old model or the new one).
  replaceFile(model, b_bytes);
  send(l.bus, 1);
  ASSERT_TRUE(l.pump([&] { return counter(l.last_status, "reloads") >= 1 && l.answers >= 2; }, 20s))
      << node->log();
  send(l.bus, 2);
  send(l.bus, 3);
  ASSERT_TRUE(l.pump([&] { return l.answers >= 4; }, 10s)) << node->log();
  // One replacement, one load: the watch (every 10 ms here, far shorter than a load) asking again
  // while the file is loading does not load it a second time.
  EXPECT_FALSE(l.pump([&] { return counter(l.last_status, "reloads") >= 2; }, 1500ms))
      << node->log();

  // A damaged replacement: refused, named, and the new model goes on answering.
  replaceFile(model, b_bytes.substr(0, b_bytes.size() / 2));
  ASSERT_TRUE(l.pump([&] { return counter(l.last_status, "reload_failures") >= 1; }, 10s))
      << node->log();
  EXPECT_NE(l.last_status.message.find("model.bin"), std::string::npos) << l.last_status.message;
  EXPECT_NE(l.last_status.message.find("previous model keeps running"), std::string::npos)
      << l.last_status.message;
  send(l.bus, 4);
  ASSERT_TRUE(l.pump([&] { return l.answers >= 5; }, 10s)) << node->log();
  EXPECT_TRUE(node->running()) << node->log();

  // On demand: the damaged file is refused again (exit 1, the reason printed); once it is good
  // again, reloaded (exit 0).
  const auto ctl = [&](const std::string& log) {
    test::ChildProcess c(
        {test::binPath("slamaware-ctl"), "--lcm-url", test::testUrl(), "reload", "recognizer"},
        log);
    return c.wait(30s);
  };
  EXPECT_EQ(ctl(dir + "/ctl-bad.log"), 1);
  {
    std::ifstream f(dir + "/ctl-bad.log");
    const std::string out((std::istreambuf_iterator<char>(f)), {});
    EXPECT_NE(out.find("model.bin"), std::string::npos) << out;
  }
  ASSERT_TRUE(l.pump([&] { return counter(l.last_status, "reload_failures") >= 2; }, 5s));
  replaceFile(model, b_bytes);
  ASSERT_TRUE(l.pump([&] { return counter(l.last_status, "reloads") >= 2; }, 10s)) << node->log();
  EXPECT_EQ(ctl(dir + "/ctl-good.log"), 0);
  ASSERT_TRUE(l.pump([&] { return counter(l.last_status, "reloads") >= 3; }, 5s));
  EXPECT_EQ(l.answers, 5);  // one answer per PROPOSALS: nothing dropped, nothing twice
  EXPECT_EQ(node->stop(), 0) << node->log();

  // The same frames through a node started with the new model: the same bytes after the reload,
  // other bytes than the old model's (so the comparison can tell the two apart).
  const std::map<int32_t, detections_t> live = l.detections;
  l.detections.clear();
  l.answers = 0;
  std::ofstream(dir + "/b.yaml") << "recognizer:\n  model: " << dir + "/b.model"
                                 << "\n";
  auto fresh = start(dir + "/b.yaml", dir + "/fresh.log");
  ASSERT_TRUE(l.pump([&] { return l.have_status && l.last_status.pid == fresh->pid(); }, 10s))
      << fresh->log();
  for (int32_t seq = 0; seq <= 4; ++seq) send(l.bus, seq);
  ASSERT_TRUE(l.pump([&] { return l.answers >= 5; }, 10s)) << fresh->log();
  EXPECT_NE(bytesOf(live.at(0)), bytesOf(l.detections.at(0))) << "models a and b answer alike";
  for (int32_t seq : {2, 3, 4})
    EXPECT_EQ(bytesOf(live.at(seq)), bytesOf(l.detections.at(seq))) << "seq " << seq;
  EXPECT_EQ(fresh->stop(), 0) << fresh->log();
}

// View selection in the process: a candidate seen again from about the same view carries the
// result of the frame it was classified in (same log-probabilities, classified_seq of that frame)
// even though the frame's pixels changed; a new view, a returning candidate and a node started
// without selection classify.
TEST(RecognizerNode, ARepeatedViewCarriesItsResultAndANewViewIsClassified) {
  const std::string dir = test::tempDir("recognizer_node_views");
  const std::string config = configWithSmallModel(dir, "[disc, bar]");
  std::ofstream(dir + "/off.yaml") << "recognizer:\n  model: " << dir + "/model.bin"
                                   << "\n  view_selection:\n    enabled: false\n";
  // Frame s shows the disc at 200 + 8 s px on its own background (made once: texturedFrame
  // draws from OpenCV's global RNG).
  std::vector<image_t> frames;
  for (int32_t s = 0; s < 4; ++s) {
    cv::Mat frame = test::texturedFrame(10 + s);
    test::syntheticObjectView("disc", 1, 3, 96).copyTo(frame(cv::Rect(200 + 8 * s, 150, 96, 96)));
    frames.push_back(makeImageMessage(frame, 1000000 + s * 33333, s, image_t::PIXEL_FORMAT_JPEG));
  }
  struct Run {
    std::map<int32_t, detections_t> detections;
    status_t last_status;
  };
  const auto run = [&](const std::string& cfg, const std::string& log) {
    Listener l;
    test::ChildProcess node({test::binPath("slamaware-recognizer"), "--config", cfg, "--lcm-url",
                             test::testUrl(), "--lockstep"},
                            log);
    EXPECT_TRUE(l.pump([&] { return l.have_status; }, 10s)) << node.log();
    // The view of candidate 100 (the disc) is 0, 3, 40, 42 degrees; 101 is out of view in frame 2.
    const float deg[] = {0, 3, 40, 42};
    for (int32_t s = 0; s < 4; ++s) {
      l.bus.publish("CAMERA", frames[static_cast<size_t>(s)]);
      l.bus.handle(20);
      std::vector<std::array<float, 4>> boxes{{200.f + 8 * s, 150, 96, 96}};
      if (s != 2) boxes.push_back({40, 300, 120, 90});
      l.bus.publish("PROPOSALS", proposals(s, boxes, deg[s]));
      EXPECT_TRUE(l.pump([&] { return l.answers >= s + 1; }, 10s)) << node.log();
    }
    EXPECT_TRUE(l.pump(
        [&] {
          return counter(l.last_status, "boxes_classified") +
                     counter(l.last_status, "boxes_carried") >=
                 7;
        },
        5s));
    EXPECT_EQ(node.stop(), 0) << node.log();
    return Run{l.detections, l.last_status};
  };
  const Run on = run(config, dir + "/on.log");
  ASSERT_EQ(on.detections.size(), 4u);
  const auto& d = on.detections;
  ASSERT_EQ(d.at(1).num_boxes, 2);
  EXPECT_EQ(d.at(0).classified_seq, (std::vector<int32_t>{0, 0}));
  EXPECT_EQ(d.at(1).classified_seq, (std::vector<int32_t>{0, 0}));  // 3 degrees on: both carried
  EXPECT_EQ(d.at(1).log_prob, d.at(0).log_prob);
  EXPECT_FLOAT_EQ(d.at(1).boxes[0].x, 208.f);                       // in this frame's box
  EXPECT_EQ(d.at(2).classified_seq, (std::vector<int32_t>{2}));     // 40 degrees: a new view
  EXPECT_EQ(d.at(3).classified_seq, (std::vector<int32_t>{2, 3}));  // 101 came back: classified
  EXPECT_EQ(counter(on.last_status, "boxes_carried"), 3);
  EXPECT_EQ(counter(on.last_status, "boxes_classified"), 4);

  const Run off = run(dir + "/off.yaml", dir + "/off.log");
  ASSERT_EQ(off.detections.size(), 4u);
  for (int32_t s = 0; s < 4; ++s) {
    std::vector<int32_t> own(static_cast<size_t>(off.detections.at(s).num_boxes), s);
    EXPECT_EQ(off.detections.at(s).classified_seq, own) << "seq " << s;
  }
  EXPECT_NE(off.detections.at(1).log_prob, d.at(1).log_prob);  // classified anew: other pixels
  EXPECT_EQ(off.detections.at(0).log_prob, d.at(0).log_prob);
  EXPECT_EQ(counter(off.last_status, "boxes_carried"), 0);
}

// Proposals sent late for an older frame (a map's reference keyframe) are classified in full and
// leave the selection alone: the next frame still carries the view of the frame before them.
TEST(RecognizerNode, LateProposalsAreClassifiedWithoutChangingWhatIsCarried) {
  const std::string dir = test::tempDir("recognizer_node_late");
  const std::string config = configWithSmallModel(dir, "[disc, bar]");
  Listener l;
  test::ChildProcess node({test::binPath("slamaware-recognizer"), "--config", config, "--lcm-url",
                           test::testUrl(), "--lockstep"},
                          dir + "/node.log");
  ASSERT_TRUE(l.pump([&] { return l.have_status; }, 10s)) << node.log();
  for (int32_t s = 0; s < 4; ++s)
    l.bus.publish("CAMERA", makeImageMessage(test::texturedFrame(20 + s), 1000000 + s * 33333, s,
                                             image_t::PIXEL_FORMAT_JPEG));
  l.bus.handle(20);
  const std::array<float, 4> box{200, 150, 96, 96};
  for (int32_t s : {0, 2, 1, 3}) {  // 1 comes late
    l.bus.publish("PROPOSALS", proposals(s, {box}, 0.f));
    ASSERT_TRUE(l.pump([&] { return l.detections.count(s) > 0; }, 10s)) << "seq " << s << "\n"
                                                                        << node.log();
  }
  EXPECT_EQ(l.detections.at(0).classified_seq, (std::vector<int32_t>{0}));
  EXPECT_EQ(l.detections.at(2).classified_seq, (std::vector<int32_t>{0}));
  EXPECT_EQ(l.detections.at(1).classified_seq, (std::vector<int32_t>{1}));  // late: classified
  EXPECT_EQ(l.detections.at(3).classified_seq, (std::vector<int32_t>{0}));  // still frame 0's view
  EXPECT_EQ(node.stop(), 0) << node.log();
}

// Real time: frames that arrive while the node classifies are overtaken by the newest one, which
// alone is classified; the overtaken frames are still answered, at once and without classifying:
// each box with its candidate's last result (classified_seq names its frame), and a box of a
// candidate never classified left out (counted in boxes_unlabelled). Every frame is answered.
TEST(RecognizerNode, RealTimeAnswersTheFramesItHadNoTimeToClassify) {
  const std::string dir = test::tempDir("recognizer_node_overtaken");
  const std::string config = configWithSmallModel(dir, "[disc, bar]");
  Listener l;
  test::ChildProcess node(
      {test::binPath("slamaware-recognizer"), "--config", config, "--lcm-url", test::testUrl()},
      dir + "/node.log");
  ASSERT_TRUE(l.pump([&] { return l.have_status; }, 10s)) << node.log();
  // 150 boxes over the frame: classifying frame 0 takes long enough for frames 1-3 to arrive.
  const std::vector<std::array<float, 4>> boxes = manyBoxes();
  for (int32_t s = 0; s < 4; ++s)
    l.bus.publish("CAMERA", makeImageMessage(test::texturedFrame(30 + s), 1000000 + s * 33333, s,
                                             image_t::PIXEL_FORMAT_JPEG));
  l.bus.handle(20);
  l.bus.publish("PROPOSALS", proposals(0, boxes, 0.f));
  std::this_thread::sleep_for(20ms);
  std::vector<std::array<float, 4>> with_new = boxes;
  with_new.push_back({500, 300, 100, 100});  // candidate 250, first seen in frame 2
  for (int32_t s = 1; s < 4; ++s)
    l.bus.publish("PROPOSALS", proposals(s, s == 2 ? with_new : boxes, 0.f));
  ASSERT_TRUE(l.pump([&] { return l.answers >= 4; }, 20s)) << node.log();
  const int statuses = l.statuses;  // the counters of every answer: a status published after them
  ASSERT_TRUE(l.pump([&] { return l.statuses >= statuses + 2; }, 5s));
  ASSERT_GE(counter(l.last_status, "frames_carried"), 1) << "no frame was overtaken\n"
                                                         << node.log();
  const detections_t& first = l.detections.at(0);
  ASSERT_GT(first.num_boxes, 0);
  int left_out = 0;
  for (int32_t s = 1; s < 4; ++s) {
    const detections_t& d = l.detections.at(s);
    SCOPED_TRACE("seq " + std::to_string(s));
    // Candidates 100-249 are seen from frame 0's view in every frame: frame 0's results.
    std::vector<float> known;
    std::vector<int32_t> from;
    bool has_new = false;
    for (int b = 0; b < d.num_boxes; ++b) {
      const size_t i = static_cast<size_t>(b);
      if (d.candidate_ids[i] == 250) {
        has_new = true;
        EXPECT_EQ(d.classified_seq[i], s);  // classified here: the frame was not overtaken
        continue;
      }
      from.push_back(d.classified_seq[i]);
      known.insert(known.end(), d.log_prob[i].begin(), d.log_prob[i].end());
    }
    EXPECT_EQ(from, std::vector<int32_t>(first.classified_seq.size(), 0));
    std::vector<float> expected;
    for (const auto& lp : first.log_prob) expected.insert(expected.end(), lp.begin(), lp.end());
    EXPECT_EQ(known, expected);
    if (s == 2 && !has_new) ++left_out;
  }
  EXPECT_EQ(counter(l.last_status, "boxes_unlabelled"), left_out);
  EXPECT_EQ(l.answers, 4);
  EXPECT_EQ(node.stop(), 0) << node.log();
}

// Real time: proposals sent late for an older frame (a map's reference keyframe) are classified in
// full on a background thread, and the live frame that comes after them does not wait: its
// DETECTIONS come first.
TEST(RecognizerNode, RealTimeClassifiesLateProposalsWithoutHoldingUpLiveFrames) {
  const std::string dir = test::tempDir("recognizer_node_late_realtime");
  const std::string config = configWithSmallModel(dir, "[disc, bar]");
  Listener l;
  test::ChildProcess node(
      {test::binPath("slamaware-recognizer"), "--config", config, "--lcm-url", test::testUrl()},
      dir + "/node.log");
  ASSERT_TRUE(l.pump([&] { return l.have_status; }, 10s)) << node.log();
  for (int32_t s = 0; s < 4; ++s)
    l.bus.publish("CAMERA", makeImageMessage(test::texturedFrame(40 + s), 1000000 + s * 33333, s,
                                             image_t::PIXEL_FORMAT_JPEG));
  l.bus.handle(20);
  const std::array<float, 4> box{200, 150, 96, 96};
  l.bus.publish("PROPOSALS", proposals(2, {box}));
  ASSERT_TRUE(l.pump([&] { return l.detections.count(2) > 0; }, 10s)) << node.log();
  // Frame 0's late proposals: 150 boxes, far more work than frame 3's one box.
  const std::vector<std::array<float, 4>> boxes = manyBoxes();
  l.bus.publish("PROPOSALS", proposals(0, boxes));
  l.bus.publish("PROPOSALS", proposals(3, {box}));
  ASSERT_TRUE(l.pump([&] { return l.detections.count(0) && l.detections.count(3); }, 20s))
      << node.log();
  EXPECT_EQ(l.order, (std::vector<int32_t>{2, 3, 0})) << "the live frame waited for the late one";
  const detections_t& late = l.detections.at(0);
  ASSERT_GT(late.num_boxes, 10);
  EXPECT_EQ(late.classified_seq, std::vector<int32_t>(static_cast<size_t>(late.num_boxes), 0))
      << "every box of the late frame classified from its own pixels";
  EXPECT_EQ(l.detections.at(3).classified_seq, (std::vector<int32_t>{3}));
  const int statuses = l.statuses;
  ASSERT_TRUE(l.pump([&] { return l.statuses >= statuses + 2; }, 5s));
  EXPECT_EQ(counter(l.last_status, "frames_late"), 1);
  EXPECT_EQ(l.answers, 3);
  EXPECT_EQ(node.stop(), 0) << node.log();
}
