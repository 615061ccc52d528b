// The proposals section's account of the ground-truth boxes no proposal covers: a hand-made
// recording (a cylinder on a table seen from above) replayed through the proposals stage, with
// ground-truth boxes placed to fall in each cause.
#include <gtest/gtest.h>

#include <filesystem>

#include "procs/proposals/proposal_engine.h"
#include "procs/proposals/synthetic_map.h"
#include "tests/eval/eval_test_data.h"
#include "tests/support/test_support.h"
#include "tools/eval/proposal_metrics.h"
#include "tools/train/trainer.h"

using namespace slamaware;
using namespace slamaware::proposals;
using namespace slamaware::synthmap;

namespace {

GroundTruthBox truth(int frame, double x, double y, double w, double h) {
  GroundTruthBox t;
  t.frame = frame;
  t.x = x, t.y = y, t.w = w, t.h = h;
  t.cls = "soda_can";
  t.instance = "soda_can_1";
  return t;
}

// Lengths in map units; every map change clustered at the next pose.
ProposalOptions metricOptions() {
  ProposalOptions o;
  o.relative_lengths = false;
  o.recluster_interval_s = 0;
  return o;
}

}  // namespace

TEST(ProposalMisses, EachUncoveredBoxHasItsCause) {
  const ProposalOptions o = metricOptions();
  const SE3 T = lookingDown(1.0);
  const auto scene = join(table(0.8f, 0.004f), cylinder(-0.1f, 0, 0.04f, 0.12f, 0.004f));
  // The box the stage gives the cylinder.
  ProposalEngine engine(o);
  std::string why;
  ASSERT_TRUE(engine.onCameraInfo(vgaInfo(), &why)) << why;
  ASSERT_TRUE(engine.onMap(cloudMessage(1, scene), &why)) << why;
  const proposals_t p = engine.onPose(poseMessage(5, pose_t::STATE_TRACKING, T), &why);
  ASSERT_EQ(p.num_boxes, 1);
  const box_t& b = p.boxes[0];

  // Frame 0: SLAM initialising, no map. Frame 5: tracking. Frame 10: no pose at all.
  const std::string log_path = test::tempDir("eval_proposal_misses") + "/run.lcm";
  const Channels ch;
  {
    lcm::LogFile log(log_path, "w");
    int64_t n = 0;
    test::writeEvent(log, ch.camera_info, vgaInfo(), n++);
    test::writeEvent(log, ch.slam_pose, poseMessage(0, pose_t::STATE_INITIALIZING, T), n++);
    test::writeEvent(log, ch.slam_map, cloudMessage(1, scene), n++);
    test::writeEvent(log, ch.slam_pose, poseMessage(5, pose_t::STATE_TRACKING, T), n++);
  }
  const std::vector<GroundTruthBox> boxes = {
      truth(0, b.x, b.y, b.w, b.h),        // before the first proposal
      truth(5, b.x, b.y, b.w, b.h),        // covered
      truth(5, b.x, b.y, b.w * 2.2, b.h),  // IoU 1 / 2.2: partial
      truth(5, 10, 10, 40, 40),            // nothing there
      truth(10, b.x, b.y, b.w, b.h),       // SLAM gave no pose
  };
  const SequenceFolder seq =
      SequenceFolder::open(test::makeSequence("eval_proposal_misses_seq", 11, {"soda_can"}, boxes));
  ProposalMisses m;
  const ProposalRecording run = rerunProposals(log_path, ch, o, &seq, 5, &m);
  EXPECT_EQ(run.boxes.at(5).size(), 1u);
  EXPECT_EQ(m.boxes, 5);
  EXPECT_EQ(m.covered, 1);
  EXPECT_EQ(m.before_first, 1);
  EXPECT_EQ(m.partial, 1);
  EXPECT_EQ(m.no_candidate, 1);
  EXPECT_EQ(m.not_localized, 1);
  EXPECT_EQ(m.suppressed + m.occluded, 0);
  EXPECT_EQ(m.boxes, m.covered + m.before_first + m.not_localized + m.suppressed + m.occluded +
                         m.partial + m.no_candidate);
  const nlohmann::json j = missesSection(m);
  EXPECT_EQ(j["partial"], 1);
  EXPECT_EQ(j["ground_truth_boxes"], 5);
}

TEST(ProposalMisses, ABoxTheRankingSuppressedIsCountedAsSuppressed) {
  // A can and a small one 2.5 cm beside it: apart at the fine density scales, one cluster at the
  // coarse ones. The pair's box overlaps the can's by IoU > 0.5, so only the can's (found at more
  // scales alike) is published; ground truth around the pair is covered by a candidate but
  // suppressed.
  ProposalOptions o = metricOptions();
  o.nms_iou = 0.5;  // the stage's own suppression (off by default: the recognizer's, by confidence)
  const SE3 T = lookingDown(1.0);
  const auto scene = join(table(0.8f, 0.004f), join(cylinder(-0.1f, 0, 0.04f, 0.12f, 0.004f),
                                                    cylinder(-0.015f, 0, 0.02f, 0.12f, 0.004f)));
  ProposalOptions loose = o;
  loose.nms_iou = 2;
  const CameraModel camera = vga();
  ProposalEngine engine(o);
  std::string why;
  ASSERT_TRUE(engine.onCameraInfo(vgaInfo(), &why));
  ASSERT_TRUE(engine.onMap(cloudMessage(1, scene), &why));
  const proposals_t p = engine.onPose(poseMessage(5, pose_t::STATE_TRACKING, T), &why);
  const auto all = projectCandidates(engine.map().candidates(), camera, T, loose);
  // Ground truth that an unpublished candidate box covers (IoU >= 0.5) and no published one does:
  // that box, or it grown away from the published ones (IoU is not transitive).
  std::vector<GroundTruthBox> boxes;
  auto covered = [&](const Box2& g) {
    for (const auto& q : p.boxes)
      if (iou(Box2{q.x, q.y, q.w, q.h}, g) >= 0.5) return true;
    return false;
  };
  for (const auto& c : all) {
    const Box2 cb{c.x, c.y, c.w, c.h};
    for (const Box2& g :
         {cb, Box2{c.x - 0.4 * c.w, c.y, 1.4 * c.w, c.h}, Box2{c.x, c.y, 1.4 * c.w, c.h},
          Box2{c.x, c.y - 0.4 * c.h, c.w, 1.4 * c.h}, Box2{c.x, c.y, c.w, 1.4 * c.h}})
      if (!covered(g) && iou(g, cb) >= 0.5) {
        boxes.push_back(truth(5, g.x, g.y, g.w, g.h));
        break;
      }
  }
  ASSERT_FALSE(boxes.empty()) << "the scene should give a candidate box that NMS removes";
  const std::string log_path = test::tempDir("eval_proposal_suppressed") + "/run.lcm";
  const Channels ch;
  {
    lcm::LogFile log(log_path, "w");
    test::writeEvent(log, ch.camera_info, vgaInfo(), 0);
    test::writeEvent(log, ch.slam_map, cloudMessage(1, scene), 1);
    test::writeEvent(log, ch.slam_pose, poseMessage(5, pose_t::STATE_TRACKING, T), 2);
  }
  const SequenceFolder seq = SequenceFolder::open(
      test::makeSequence("eval_proposal_suppressed_seq", 6, {"soda_can"}, boxes));
  ProposalMisses m;
  rerunProposals(log_path, ch, o, &seq, 5, &m);
  EXPECT_EQ(m.suppressed, static_cast<int>(boxes.size()));
  EXPECT_EQ(m.covered, 0);
}

TEST(ProposalBoxes, WhatTheEvaluatorDumpsTheTrainerReadsBack) {
  ProposalRecording run;
  run.boxes[0] = {{10, 20, 30, 40}, {1.5, 2.25, 3, 4}};
  run.boxes[7] = {};  // a frame without boxes
  run.boxes[12] = {{600.5, 400, 39.5, 80}};
  const std::string path = test::tempDir("proposal_boxes_round_trip") + "/sub/scene.csv";
  writeProposalBoxes(run, path);
  const auto read = recognizer::readProposalBoxes(path);
  ASSERT_EQ(read.size(), 2u);
  EXPECT_EQ(read.at(0),
            (std::vector<cv::Rect2d>{cv::Rect2d(10, 20, 30, 40), cv::Rect2d(1.5, 2.25, 3, 4)}));
  EXPECT_EQ(read.at(12), (std::vector<cv::Rect2d>{cv::Rect2d(600.5, 400, 39.5, 80)}));
}
