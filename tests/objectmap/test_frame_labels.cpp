// What the object map publishes per frame (frame_labels.h, OBJECT_DETECTIONS): a box's score is its
// object's posterior times its own view's p(class | box); one box per object and frame stands for
// it, the others overlapping it are demoted as duplicates and those beside it are parts; a
// candidate in no object keeps its own views' evidence; and the engine publishes them for every
// DETECTIONS.
#include <gtest/gtest.h>

#include <cmath>

#include "procs/objectmap/frame_labels.h"
#include "procs/objectmap/object_map.h"
#include "procs/objectmap/object_table.h"
#include "tests/objectmap/synthetic_world.h"

using namespace slamaware;
using namespace slamaware::objectmap;

namespace {

// Classes: cap, mug, background; a view sure of an object by 1 - p_background, split evenly.
std::vector<float> view(double p_background) {
  const double o = (1 - p_background) / 2;
  return {static_cast<float>(std::log(o)), static_cast<float>(std::log(o)),
          static_cast<float>(std::log(p_background))};
}

std::vector<VoxelKey> voxels(int from, int to) {
  std::vector<VoxelKey> k;
  for (int i = from; i < to; ++i) k.push_back(packVoxelKey(40000 + i, 40000, 40000));
  return k;
}

FrameBox box(int32_t candidate, double x, double w, const std::vector<float>& log_p) {
  FrameBox b;
  b.x = x, b.y = 100, b.w = w, b.h = 50;
  b.candidate = candidate;
  b.log_p = log_p;
  return b;
}

}  // namespace

// Candidates 3 and 5 are one object (the same voxels), candidate 9 another; candidate 11 has no
// voxels and is an object of its own. Every box of an object carries its object's posterior; its
// own view says how well this box frames an object of each class: a box on a part of the object,
// which its view takes for background, ranks below the box on the whole object, and a distractor's
// box below both.
TEST(FrameLabels, TheWeightIsTheBoxsOwnView) {
  VotingOptions vo;
  ObjectTable t(0.01);
  for (int v = 0; v < 3; ++v)
    t.addVotes(3, voxels(0, 20), vo), t.addVotes(5, voxels(0, 20), vo),
        t.addVotes(9, voxels(50, 70), vo);
  const double bg3[] = {0.2, 0.9, 0.9}, bg9[] = {0.1, 0.95, 0.95, 0.95};
  for (int f = 0; f < 3; ++f) t.addView(3, View{100 * f, f, 2500, view(bg3[f])});
  t.addView(5, View{0, 0, 2500, view(0.2)});
  t.addView(5, View{200, 2, 2500, view(0.4)});
  for (int f = 0; f < 4; ++f) t.addView(9, View{100 * f, f, 2500, view(bg9[f])});
  t.addView(11, View{200, 2, 2500, view(0.5)});
  int32_t next = 1;
  t.update([](VoxelKey) { return true; }, vo, GroupingOptions{}, 3, [&] { return next++; });
  ASSERT_EQ(t.objectOfCandidate(3), t.objectOfCandidate(5));
  ASSERT_NE(t.objectOfCandidate(3), t.objectOfCandidate(9));

  const std::vector<FrameBox> frame2{box(3, 0, 50, view(0.9)), box(5, 100, 50, view(0.4)),
                                     box(9, 200, 50, view(0.95)), box(11, 300, 50, view(0.5))};
  const auto labels = labelFrameBoxes(frame2, t, 3, FusionOptions{});
  ASSERT_EQ(labels.size(), 4u);
  const double own[] = {0.05, 0.3, 0.025, 0.25};  // each box's p(mug | box)
  for (size_t i = 0; i < labels.size(); ++i) {
    EXPECT_NEAR(labels[i].log_weight[0], std::log(own[i]), 1e-6) << "box " << i;
    EXPECT_NEAR(labels[i].log_weight[1], std::log(own[i]), 1e-6) << "box " << i;
    EXPECT_EQ(labels[i].log_weight[2], 0.0) << "the background has no weight";
  }
  EXPECT_EQ(labels[0].object, labels[1].object);
  EXPECT_EQ(labels[0].log_posterior, labels[1].log_posterior) << "one object, one posterior";
  for (const auto& l : labels) {
    // The score: the posterior times the weight for each object class, the background the rest.
    EXPECT_NEAR(l.log_score[1], l.log_posterior[1] + l.log_weight[1], 1e-9);
    EXPECT_NEAR(std::exp(l.log_score[0]) + std::exp(l.log_score[1]) + std::exp(l.log_score[2]), 1.0,
                1e-9);
    EXPECT_NE(l.role, BoxRole::kDuplicate);
  }
  EXPECT_LT(labels[0].log_score[1], labels[1].log_score[1])
      << "the part's box ranks below the whole object's box of the same object";
  EXPECT_LT(labels[2].log_score[1], labels[0].log_score[1])
      << "the distractor, whose views mostly call it background, ranks below both";
}

// One detection per object and frame: the box its own view finds most object-like stands for the
// object; a box framing it as that one does, or a part of it inside that box (a sliver of IoU 0.2),
// is a duplicate ranked below every detection; a box on another part beside it keeps its score.
TEST(FrameLabels, DuplicatesOfAnObjectInAFrameAreDemotedByTheirShareInsideItsBox) {
  VotingOptions vo;
  ObjectTable t(0.01);
  for (int32_t c : {1, 2, 3, 4})
    for (int v = 0; v < 3; ++v) t.addVotes(c, voxels(0, 20), vo);
  for (int v = 0; v < 3; ++v) t.addVotes(7, voxels(50, 70), vo);
  const std::vector<float> shifted = view(0.6), whole = view(0.1), beside = view(0.7),
                           side = view(0.3);
  t.addView(1, View{0, 0, 2500, shifted});
  t.addView(2, View{0, 0, 2500, whole});
  t.addView(3, View{0, 0, 1000, beside});
  t.addView(4, View{0, 0, 500, side});
  t.addView(7, View{0, 0, 2500, view(0.9)});
  int32_t next = 1;
  t.update([](VoxelKey) { return true; }, vo, GroupingOptions{}, 3, [&] { return next++; });
  ASSERT_EQ(t.objectOfCandidate(1), t.objectOfCandidate(4));
  auto at = [](int32_t c, double x, double w, const std::vector<float>& p) {
    return box(c, x, w, p);
  };
  const std::vector<FrameBox> frame{at(1, 105, 50, shifted), at(2, 100, 50, whole),
                                    at(3, 150, 20, beside), at(7, 100, 50, view(0.9)),
                                    at(4, 110, 10, side)};
  const auto l = labelFrameBoxes(frame, t, 3, FusionOptions{});
  EXPECT_EQ(l[1].role, BoxRole::kPrimary) << "the most object-like box of the object";
  EXPECT_EQ(l[3].role, BoxRole::kPrimary) << "another object's box";
  EXPECT_EQ(l[0].role, BoxRole::kDuplicate);
  EXPECT_EQ(l[4].role, BoxRole::kDuplicate)
      << "wholly inside the primary box: a duplicate, whatever its IoU (0.2)";
  EXPECT_EQ(l[2].role, BoxRole::kPart) << "beside the primary box";
  const double share = 45.0 * 50 / 2500;  // 90 % of the shifted box lies inside the whole one
  const auto undemoted = labelFrameBoxes({frame[0]}, t, 3, FusionOptions{});
  EXPECT_NEAR(l[0].log_weight[1], undemoted[0].log_weight[1] - share * share / kDuplicateSigma,
              1e-9);
  EXPECT_NEAR(
      l[4].log_weight[1],
      labelFrameBoxes({frame[4]}, t, 3, FusionOptions{})[0].log_weight[1] - 1 / kDuplicateSigma,
      1e-9);
  EXPECT_EQ(l[2].log_weight, labelFrameBoxes({frame[2]}, t, 3, FusionOptions{})[0].log_weight);
  EXPECT_EQ(l[0].label, l[1].label) << "a duplicate keeps its object's label";
  EXPECT_LT(l[4].log_score[1], l[1].log_score[1] - 5);
  EXPECT_LT(l[0].log_score[1], l[2].log_score[1]);
}

// A box of a candidate the table does not hold (its box was refused) is labelled by its own view.
TEST(FrameLabels, ACandidateInNoObjectIsLabelledByItsOwnViews) {
  ObjectTable t(0.01);
  const std::vector<float> own{std::log(0.2f), std::log(0.7f), std::log(0.1f)};
  const auto l = labelFrameBoxes({box(42, 0, 50, own)}, t, 3, FusionOptions{});
  ASSERT_EQ(l.size(), 1u);
  EXPECT_EQ(l[0].role, BoxRole::kNoObject);
  EXPECT_EQ(l[0].object, -1);
  EXPECT_NEAR(l[0].log_posterior[1], std::log(0.7), 1e-6);
  EXPECT_EQ(l[0].label, 1);
  EXPECT_NEAR(l[0].log_weight[1], std::log(0.7), 1e-6);
}

// The engine answers every DETECTIONS with its boxes, in order, each with its object.
TEST(FrameLabels, TheEngineLabelsEveryBoxOfEveryFrame) {
  const test::SyntheticWorld w({}, test::SyntheticWorld::defaultObjects());
  ObjectMapEngine e(ObjectMapOptions{});
  std::string why;
  ASSERT_TRUE(e.onCameraInfo(w.cameraInfo(), &why));
  const auto clouds = w.keyframeClouds(1);
  for (int f = 0; f < 20; ++f) {
    for (const auto& c : clouds) {
      if (c.seq == f) {
        ASSERT_TRUE(e.onMap(c, &why)) << why;
      }
    }
    ASSERT_TRUE(e.onPose(w.poseMessage(f, 1), &why));
    ASSERT_TRUE(e.onProposals(w.proposals(f, 1), &why));
    const detections_t d = w.detections(f, 1);
    ASSERT_TRUE(e.onDetections(d, &why)) << why;
    const object_detections_t m = e.frameDetections(d);
    EXPECT_EQ(m.seq, d.seq);
    EXPECT_EQ(m.utime, d.utime);
    ASSERT_EQ(m.num_boxes, d.num_boxes);
    ASSERT_EQ(m.candidate_ids, d.candidate_ids);
    for (int i = 0; i < m.num_boxes; ++i) {
      ASSERT_EQ(m.log_score[static_cast<size_t>(i)].size(), m.class_names.size());
      const Object* o = e.objectOfCandidate(1, d.candidate_ids[static_cast<size_t>(i)]);
      EXPECT_EQ(m.object_ids[static_cast<size_t>(i)], o ? o->id : -1);
      if (o) {
        EXPECT_EQ(m.labels[static_cast<size_t>(i)], e.classes()[static_cast<size_t>(o->label)]);
      }
    }
  }
  // A malformed message still gets its answer (the map refused it).
  detections_t bad = w.detections(20, 1);
  bad.log_prob.pop_back();
  EXPECT_FALSE(e.onDetections(bad, &why));
  EXPECT_EQ(e.frameDetections(bad).seq, 20);
}
