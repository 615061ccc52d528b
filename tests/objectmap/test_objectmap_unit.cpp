// The object map's algorithm without the bus: the fusion equation on hand-made views, candidate
// voxels from boxes over a synthetic cloud, merge and split of candidates with stable ids,
// segments per SLAM map, OctoMap ray casting, the whole engine on a synthetic scene, and the
// shipped config.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include "common/config.h"
#include "procs/objectmap/candidate_voxels.h"
#include "procs/objectmap/frame_labels.h"
#include "procs/objectmap/fusion.h"
#include "procs/objectmap/object_map.h"
#include "procs/objectmap/object_table.h"
#include "procs/objectmap/occupancy_map.h"
#include "tests/objectmap/synthetic_world.h"
#include "tests/support/test_support.h"

using namespace slamaware;
using namespace slamaware::objectmap;

namespace {

std::vector<float> logs(std::initializer_list<double> p) {
  std::vector<float> out;
  for (double x : p) out.push_back(static_cast<float>(std::log(x)));
  return out;
}

std::vector<uint8_t> encode(const object_map_t& m) {
  std::vector<uint8_t> buf(static_cast<size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

// Feeds frames [first, last) of a world (clouds first) to an engine.
void feed(ObjectMapEngine& e, const test::SyntheticWorld& w, int32_t map_id, int first, int last,
          int32_t seq_offset = 0) {
  std::string why;
  ASSERT_TRUE(e.onCameraInfo(w.cameraInfo(), &why)) << why;
  const auto clouds = w.keyframeClouds(map_id);
  for (int f = first; f < last; ++f) {
    for (auto c : clouds)
      if (c.seq == f) {
        c.seq += seq_offset;
        c.utime = w.utime(c.seq);
        ASSERT_TRUE(e.onMap(c, &why)) << why;
      }
    ASSERT_TRUE(e.onPose(w.poseMessage(f, map_id, seq_offset), &why)) << why;
    ASSERT_TRUE(e.onProposals(w.proposals(f, map_id, seq_offset), &why)) << why;
    ASSERT_TRUE(e.onDetections(w.detections(f, map_id, seq_offset), &why)) << why;
  }
}

// Voxels [from, to) of a line along x.
std::vector<VoxelKey> lineOfVoxels(int from, int to) {
  std::vector<VoxelKey> k;
  for (int i = from; i < to; ++i) k.push_back(packVoxelKey(40000 + i, 40000, 40000));
  return k;
}

// A voxel belongs to a candidate voted in 2 views and half of them.
VotingOptions twoVotesAndHalfTheViews() {
  VotingOptions vo;
  vo.min_votes = 2;
  vo.min_vote_share = 0.5;
  return vo;
}

// Candidates merge when they share half the smaller's voxels and it is at least half the larger.
GroupingOptions halfOverlapAndHalfSize() {
  GroupingOptions half;
  half.merge_overlap = 0.5;
  half.merge_size_ratio = 0.5;
  return half;
}

const object_t* findLabel(const object_map_t& m, const std::string& label) {
  for (const auto& o : m.objects)
    if (o.label == label) return &o;
  return nullptr;
}

}  // namespace

// ---- Fusion -----------------------------------------------------------------------------------

// Three views whose single-view argmaxes disagree (two say A weakly, one says B strongly): the
// summed log-probabilities pick what the product of probabilities picks (B), not the majority.
TEST(Fusion, SummedLogProbabilitiesPickTheArgmaxOfTheProduct) {
  const std::vector<std::vector<double>> p = {
      {0.40, 0.35, 0.25}, {0.40, 0.35, 0.25}, {0.05, 0.90, 0.05}};
  std::vector<std::vector<float>> views;
  for (const auto& v : p) views.push_back(logs({v[0], v[1], v[2]}));
  std::vector<const std::vector<float>*> ptrs;
  for (const auto& v : views) ptrs.push_back(&v);
  const std::vector<double> sum = sumLogProbabilities(ptrs, 3);

  // Independently: the product over views, normalised (the paper's ML over N views, uniform prior).
  std::vector<double> product(3, 1.0);
  for (const auto& v : p)
    for (int c = 0; c < 3; ++c) product[c] *= v[c];
  const double z = product[0] + product[1] + product[2];
  int best = 0;
  for (int c = 1; c < 3; ++c)
    if (product[c] > product[best]) best = c;
  EXPECT_EQ(best, 1);
  EXPECT_EQ(argmaxClass(sum), best);
  for (const auto& v : p)
    EXPECT_EQ(std::max_element(v.begin(), v.end()) - v.begin(), &v == &p[2] ? 1 : 0);
  const std::vector<double> post = posteriorFromLogEvidence(sum);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(sum[c], std::log(product[c]), 1e-6);
    EXPECT_NEAR(post[c], product[c] / z, 1e-6);
  }
}

// A single confidently wrong view (p = 0.98 for the wrong class, 0.01 for the right one: the
// recognizer's probability floor) is outvoted by five moderately right ones.
TEST(Fusion, AConfidentlyWrongViewIsOutvoted) {
  std::vector<std::vector<float>> views(5, logs({0.6, 0.2, 0.2}));
  views.push_back(logs({0.01, 0.98, 0.01}));
  std::vector<const std::vector<float>*> ptrs;
  for (const auto& v : views) ptrs.push_back(&v);
  EXPECT_EQ(argmaxClass(sumLogProbabilities(ptrs, 3)), 0);
  // Without the five, the wrong view alone wins: the evidence is what changed the answer.
  EXPECT_EQ(argmaxClass(sumLogProbabilities({ptrs.back()}, 3)), 1);
}

// Objectness weights (classes: mug, cap, background): three views of the whole object say mug
// (p(background) small); six views in which the object is cut by the border say, weakly, cap and
// mostly background. The plain sum follows the many poor views; the weighted sum the good ones, and
// each view's weight is 1 - p(background).
TEST(Fusion, ObjectnessWeightsLetViewsOfTheWholeObjectDecide) {
  std::vector<std::vector<float>> views(3, logs({0.8, 0.1, 0.1}));
  for (int i = 0; i < 6; ++i) views.push_back(logs({0.02, 0.18, 0.8}));
  std::vector<const std::vector<float>*> ptrs;
  for (const auto& v : views) ptrs.push_back(&v);
  EXPECT_EQ(argmaxClass(sumLogProbabilities(ptrs, 3)), 2)
      << "plain: the poor views win (background)";
  EXPECT_EQ(argmaxClass(sumLogProbabilities(ptrs, 3, true)), 0)
      << "weighted: the whole-object views win";
  const auto one = sumLogProbabilities({ptrs.back()}, 3, true);
  EXPECT_NEAR(one[1], 0.2 * std::log(0.18), 1e-6);
  // Views that all say background keep background.
  std::vector<float> bg = logs({0.01, 0.01, 0.98});
  EXPECT_EQ(argmaxClass(sumLogProbabilities({&bg, &bg, &bg}, 3, true)), 2);
}

// posterior_views_exponent: forty views that all say (0.5, 0.3, 0.2) give a posterior of 1 for the
// first class when taken as independent (e = 0), the views' own posterior when averaged (e = 1),
// and something between for e = 0.5; the label is the same for every e. With objectness weights,
// W is the sum of the weights and e = 1 gives the weighted geometric mean, normalised.
TEST(Fusion, TheViewsExponentTempersTheConfidenceNotTheLabel) {
  std::vector<std::vector<float>> views(40, logs({0.5, 0.3, 0.2}));
  std::vector<const std::vector<float>*> ptrs;
  for (const auto& v : views) ptrs.push_back(&v);
  double w = 0;
  const std::vector<double> sum = sumLogProbabilities(ptrs, 3, false, &w);
  EXPECT_DOUBLE_EQ(w, 40);
  const auto independent = posteriorFromLogEvidence(sum, w, 0);
  const auto average = posteriorFromLogEvidence(sum, w, 1);
  const auto between = posteriorFromLogEvidence(sum, w, 0.5);
  EXPECT_GT(independent[0], 1 - 1e-6);
  EXPECT_NEAR(average[0], 0.5, 1e-5);
  EXPECT_NEAR(average[1], 0.3, 1e-5);
  EXPECT_NEAR(average[2], 0.2, 1e-5);
  EXPECT_GT(between[0], average[0]);
  EXPECT_LT(between[0], independent[0]);
  for (const auto* p : {&independent, &average, &between}) EXPECT_EQ(argmaxClass(*p), 0);
  // A single view (W <= 1) is not sharpened.
  const auto one = posteriorFromLogEvidence(sumLogProbabilities({ptrs[0]}, 3), 1, 1);
  EXPECT_NEAR(one[0], 0.5, 1e-5);

  // Weighted: two views, p(background) 0.2 and 0.6 -> weights 0.8 and 0.4, W = 1.2.
  std::vector<float> a = logs({0.7, 0.1, 0.2}), b = logs({0.1, 0.3, 0.6});
  const std::vector<double> ws = sumLogProbabilities({&a, &b}, 3, true, &w);
  EXPECT_NEAR(w, 1.2, 1e-6);
  const auto mean = posteriorFromLogEvidence(ws, w, 1);
  std::vector<double> geo(3);
  double z = 0;
  for (int c = 0; c < 3; ++c)
    z += geo[c] = std::exp((0.8 * a[c] + 0.4 * b[c]) / 1.2);  // (pa^0.8 pb^0.4)^(1/1.2)
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean[c], geo[c] / z, 1e-6);
  EXPECT_EQ(argmaxClass(mean), argmaxClass(ws));
}

TEST(Fusion, ThousandsOfViewsDoNotUnderflowAndTiesGoToTheLowerClass) {
  std::vector<std::vector<float>> views(5000, logs({0.3, 0.3, 0.4}));
  std::vector<const std::vector<float>*> ptrs;
  for (const auto& v : views) ptrs.push_back(&v);
  const auto post = posteriorFromLogEvidence(sumLogProbabilities(ptrs, 3));
  EXPECT_NEAR(post[0] + post[1] + post[2], 1.0, 1e-12);
  EXPECT_NEAR(post[2], 1.0, 1e-9);
  EXPECT_EQ(argmaxClass({1.0, 2.0, 2.0}), 1);
  EXPECT_EQ(argmaxClass({}), -1);
}

// ---- Occupancy ----------------------------------------------------------------------------------

TEST(Occupancy, RayCastingMarksPointsOccupiedAndTheRaysInFrontFree) {
  OccupancyOptions o;
  o.resolution = 0.02;
  o.free_band = 0.2;
  OccupancyMap map(o, o.resolution);
  std::vector<Eigen::Vector3f> wall;
  for (int i = -10; i <= 10; ++i)
    for (int j = -10; j <= 10; ++j) wall.emplace_back(0.01f * i, 0.01f * j, 1.0f);
  const Eigen::Vector3f origin(0, 0, 0);
  const InsertStats s = map.setKeyframe(1, wall, &origin);
  EXPECT_EQ(s.points, wall.size());
  EXPECT_GT(s.free_updates, 0u);
  for (const auto& p : wall) EXPECT_EQ(map.cell(p.cast<double>()), OccupancyMap::Cell::kOccupied);
  // Along the central ray: free within the band in front of the wall, unknown before it.
  EXPECT_EQ(map.cell(Eigen::Vector3d(0.001, 0.001, 0.9)), OccupancyMap::Cell::kFree);
  EXPECT_EQ(map.cell(Eigen::Vector3d(0.001, 0.001, 0.5)), OccupancyMap::Cell::kUnknown);
  EXPECT_EQ(map.cell(Eigen::Vector3d(0.001, 0.001, 1.2)),
            OccupancyMap::Cell::kUnknown);  // behind: unseen

  // Whole rays (free_band <= 0): free from the keyframe up to the points.
  o.free_band = 0;
  OccupancyMap whole(o, o.resolution);
  whole.setKeyframe(1, wall, &origin);
  EXPECT_EQ(whole.cell(Eigen::Vector3d(0.001, 0.001, 0.5)), OccupancyMap::Cell::kFree);
  EXPECT_EQ(whole.cell(Eigen::Vector3d(0.001, 0.001, 0.1)), OccupancyMap::Cell::kFree);

  // The occupied list is sorted, its keys are OctoMap's and the centres follow voxel_key.h.
  const auto& occ = whole.occupied();
  ASSERT_FALSE(occ.empty());
  for (size_t i = 1; i < occ.size(); ++i) EXPECT_LT(occ[i - 1].key, occ[i].key);
  for (const auto& v : occ) {
    EXPECT_TRUE(v.centre.cast<double>().isApprox(voxelCentre(v.key, 0.02), 1e-6));
    VoxelKey k;
    ASSERT_TRUE(voxelKeyOf(v.centre.cast<double>(), 0.02, &k));
    EXPECT_EQ(k, v.key);
    EXPECT_TRUE(whole.isOccupied(v.key));
  }
  // A second keyframe seeing the same wall: hits from two keyframes keep a voxel occupied.
  whole.setKeyframe(2, wall, &origin);
  EXPECT_EQ(whole.cell(Eigen::Vector3d(0.0, 0.0, 1.0)), OccupancyMap::Cell::kOccupied);
}

// The occupied list is kept up to date from the voxels each batch touches: after every batch it
// is what a rebuild from the tree's leaves (a map read back from its bytes) finds, also when rays
// from other keyframes free voxels that were occupied.
TEST(Occupancy, TheOccupiedListFollowsEveryUpdateAsARebuildWouldFindIt) {
  OccupancyOptions o;
  o.resolution = 0.02;
  o.free_band = 0;  // whole rays: later views carve through earlier points
  OccupancyMap map(o, o.resolution);
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(-0.3f, 0.3f);
  size_t freed = 0;
  std::vector<VoxelKey> before;
  for (int batch = 0; batch < 12; ++batch) {
    // A noisy surface at depth ~1 seen from a camera that moves sideways.
    std::vector<Eigen::Vector3f> points;
    for (int i = 0; i < 400; ++i) points.emplace_back(u(rng), u(rng), 1.0f + 0.3f * u(rng));
    const Eigen::Vector3f origin(0.2f * static_cast<float>(batch % 5) - 0.4f, 0, 0);
    map.setKeyframe(batch, points, &origin);
    if (batch == 5) map.occupied();  // read in between: later batches update the list in place
    const OccupancyMap rebuilt =
        OccupancyMap::deserialize(map.serialize([](VoxelKey) { return Rgb{}; }), o, "rebuilt");
    std::vector<VoxelKey> now, expected;
    for (const auto& v : map.occupied()) now.push_back(v.key);
    for (const auto& v : rebuilt.occupied()) expected.push_back(v.key);
    ASSERT_EQ(now, expected) << "after batch " << batch;
    for (size_t i = 0; i < now.size(); ++i)
      ASSERT_TRUE(map.occupied()[i].centre.isApprox(rebuilt.occupied()[i].centre)) << i;
    for (VoxelKey k : before) freed += !std::binary_search(now.begin(), now.end(), k);
    before = now;
  }
  EXPECT_GT(freed, 0u) << "no voxel was ever freed: the test would not see a stale list";
  for (int32_t kf : map.keyframes()) map.removeKeyframe(kf);
  EXPECT_TRUE(map.occupied().empty());
  EXPECT_EQ(map.numVoxels(), 0u);
  EXPECT_TRUE(OccupancyMap::deserialize(map.serialize([](VoxelKey) { return Rgb{}; }), o, "emptied")
                  .occupied()
                  .empty());
}

// A keyframe's evidence can be replaced and taken back exactly: after keyframes moved, were
// removed and got more points, in any order, the map is the one a build from scratch of each
// keyframe's current points gives, to the byte of its .ot file.
TEST(Occupancy, KeyframesReplacedOrTakenBackLeaveWhatABuildFromScratchGives) {
  OccupancyOptions o;
  o.resolution = 0.02;
  o.free_band = 0;  // whole rays: keyframes carve through each other's points
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-0.3f, 0.3f);
  auto surface = [&](int n) {
    std::vector<Eigen::Vector3f> points;
    for (int i = 0; i < n; ++i) points.emplace_back(u(rng), u(rng), 1.0f + 0.3f * u(rng));
    return points;
  };
  std::vector<std::vector<Eigen::Vector3f>> points;
  std::vector<Eigen::Vector3f> origins;
  for (int kf = 0; kf < 6; ++kf) {
    points.push_back(surface(400));
    origins.emplace_back(0.2f * static_cast<float>(kf % 5) - 0.4f, 0, 0);
  }
  OccupancyMap map(o, o.resolution);
  for (int kf = 0; kf < 6; ++kf) map.setKeyframe(kf, points[kf], &origins[kf]);
  const std::vector<OccupiedVoxel> first = map.occupied();

  // The same points and origin again: nothing to do.
  const InsertStats same = map.setKeyframe(1, points[1], &origins[1]);
  EXPECT_EQ(same.unchanged, points[1].size());
  EXPECT_EQ(same.occupied_updates + same.free_updates, 0u);
  // Keyframe 2 moved (bundle adjustment), 4 left SLAM's map, 5 got more points.
  for (auto& p : points[2]) p += Eigen::Vector3f(0.03f, -0.01f, 0.02f);
  origins[2] += Eigen::Vector3f(0.03f, -0.01f, 0.02f);
  const InsertStats moved = map.setKeyframe(2, points[2], &origins[2]);
  EXPECT_GT(moved.occupied_updates, 0u);
  map.removeKeyframe(4);
  const std::vector<Eigen::Vector3f> more = surface(200);
  map.addToKeyframe(5, more, &origins[5]);
  points[5].insert(points[5].end(), more.begin(), more.end());
  EXPECT_EQ(map.keyframes(), (std::vector<int32_t>{0, 1, 2, 3, 5}));

  OccupancyMap scratch(o, o.resolution);
  for (int kf : {5, 3, 2, 1, 0}) scratch.setKeyframe(kf, points[kf], &origins[kf]);
  std::vector<VoxelKey> now, expected;
  for (const auto& v : map.occupied()) now.push_back(v.key);
  for (const auto& v : scratch.occupied()) expected.push_back(v.key);
  EXPECT_EQ(now, expected);
  EXPECT_NE(map.occupied().size(), first.size());  // the changes did change the map
  EXPECT_EQ(map.numVoxels(), scratch.numVoxels());
  const auto grey = [](VoxelKey) { return Rgb{100, 100, 100}; };
  EXPECT_EQ(map.serialize(grey), scratch.serialize(grey));

  // Frozen (the evidence kept in the tree only), the map reads the same; a keyframe given then
  // adds to what it holds.
  const Eigen::Vector3d probe = voxelCentre(expected[expected.size() / 2], o.resolution);
  map.freeze();
  EXPECT_TRUE(map.keyframes().empty());
  EXPECT_EQ(map.occupied().size(), expected.size());
  EXPECT_EQ(map.cell(probe), OccupancyMap::Cell::kOccupied);
  EXPECT_EQ(map.serialize(grey), scratch.serialize(grey));
  map.setKeyframe(9, points[0], &origins[0]);
  scratch.setKeyframe(9, points[0], &origins[0]);
  std::vector<VoxelKey> thawed, twice;
  for (const auto& v : map.occupied()) thawed.push_back(v.key);
  for (const auto& v : scratch.occupied()) twice.push_back(v.key);
  EXPECT_EQ(thawed, twice);
}

TEST(Occupancy, PointsBeyondMaxRangeOrNotFiniteAreDropped) {
  OccupancyOptions o;
  o.max_range = 2.0;
  OccupancyMap map(o, o.resolution);
  const Eigen::Vector3f origin(0, 0, 0);
  const InsertStats s = map.setKeyframe(1, {{0, 0, 1}, {0, 0, 3}, {NAN, 0, 1}}, &origin);
  EXPECT_EQ(s.points, 1u);
  EXPECT_EQ(s.dropped, 2u);
  EXPECT_EQ(map.occupied().size(), 1u);
}

// A segment whose SLAM map has no points yet (SLAM started a map and lost it before its first
// cloud): saving it must not crash (OctoMap's ColorOcTree cannot update an empty tree), and the
// bytes read back as an empty map.
TEST(Occupancy, AnEmptyMapSerializesAndReadsBack) {
  OccupancyOptions o;
  OccupancyMap map(o, o.resolution);
  const std::string bytes = map.serialize([](VoxelKey) { return Rgb{1, 2, 3}; });
  EXPECT_FALSE(bytes.empty());
  const OccupancyMap back = OccupancyMap::deserialize(bytes, o, "empty");
  EXPECT_TRUE(back.occupied().empty());
  // The engine: a pose in a map that never sent a cloud makes an empty segment; a snapshot saves
  // it.
  ObjectMapEngine e(ObjectMapOptions{});
  const test::SyntheticWorld w({}, test::SyntheticWorld::defaultObjects());
  std::string why;
  ASSERT_TRUE(e.onPose(w.poseMessage(0, 3), &why)) << why;
  const MapSnapshot snap = e.snapshot();
  EXPECT_EQ(snap.segment_files.size(), 1u);
}

// ---- Candidate voxels -----------------------------------------------------------------------

// A cube of points 1 unit in front of the camera and a wall 0.5 behind it, seen from an arc of
// views; the box of each view is the cube's projection with a 15 px margin (boxes are never
// tight). Over the views the candidate keeps the cube's voxels and none of the wall's.
TEST(CandidateVoxels, AnObjectInFrontOfAWallKeepsItsVoxelsAndNotTheWall) {
  test::SyntheticWorldOptions wo;
  wo.table = false;
  wo.frames = 30;
  const test::SyntheticObject cube{5, Eigen::Vector3d(0, 0.0, 0), Eigen::Vector3d(0.05, 0.05, 0.05),
                                   0};
  const test::SyntheticWorld world(wo, {cube});
  OccupancyOptions oo;
  OccupancyMap map(oo, oo.resolution);
  for (const auto& c : world.keyframeClouds(1)) {
    std::vector<Eigen::Vector3f> pts;
    for (int i = 0; i < c.num_points; ++i) pts.emplace_back(c.x[i], c.y[i], c.z[i]);
    const Eigen::Vector3f origin(c.kf_x.back(), c.kf_y.back(), c.kf_z.back());
    map.setKeyframe(c.keyframe_id, pts, &origin);
  }
  VotingOptions vo;
  ObjectTable table(map.resolution());
  size_t wall_votes_in_one_view = 0;
  for (int f = 0; f < wo.frames; ++f) {
    const proposals_t p = world.proposals(f, 1);
    ASSERT_EQ(p.num_boxes, 1);
    VoteBox b{p.boxes[0].x - 15, p.boxes[0].y - 15, p.boxes[0].w + 30, p.boxes[0].h + 30,
              p.median_depth[0]};
    const auto keys = voxelsInBoxes(map.occupied(), world.camera(), world.pose(f), {b}, vo)[0];
    for (VoxelKey k : keys) wall_votes_in_one_view += voxelCentre(k, map.resolution()).z() > 0.3;
    table.addVotes(5, keys, vo);
    table.addView(5, View{world.utime(f), f, b.w * b.h, logs({0.9, 0.1})});
  }
  EXPECT_EQ(wall_votes_in_one_view, 0u) << "the depth band keeps the wall out of every view";
  table.update([&](VoxelKey k) { return map.isOccupied(k); }, vo, GroupingOptions{}, 2,
               [] { return 1; });
  const Candidate& c = table.candidates().at(5);
  std::set<VoxelKey> cube_voxels;
  for (const auto& p : world.objectPoints(0)) {
    VoxelKey k;
    if (voxelKeyOf(p, map.resolution(), &k) && map.isOccupied(k)) cube_voxels.insert(k);
  }
  size_t inside = 0;
  for (VoxelKey k : c.voxels) {
    const Eigen::Vector3d p = voxelCentre(k, map.resolution());
    EXPECT_LT((p - cube.centre).cwiseAbs().maxCoeff(), 0.05 + map.resolution())
        << "voxel outside the cube";
    inside += cube_voxels.count(k);
  }
  EXPECT_GE(inside, cube_voxels.size() * 9 / 10)
      << "most of the cube's occupied voxels are the candidate's";
  const Object& o = table.objects().begin()->second;
  EXPECT_LT((o.centroid - cube.centre).norm(), 0.01);
  EXPECT_NEAR(o.extent.x(), 0.1, 0.025);
}

// ---- Merge, split, stable ids ----------------------------------------------------------------

TEST(ObjectTable, MergeKeepsTheUnionOfViewsSplitKeepsEachCandidatesOwnAndIdsStayStable) {
  const VotingOptions vo = twoVotesAndHalfTheViews();
  const GroupingOptions half = halfOverlapAndHalfSize();
  ObjectTable t(0.01);
  // Candidate 1: voxels 0..19, candidate 2: voxels 10..29 (the shared 10..19 are half of each).
  for (int v = 0; v < 3; ++v)
    t.addVotes(1, lineOfVoxels(0, 20), vo), t.addVotes(2, lineOfVoxels(10, 30), vo);
  // A voxel voted once in three views is below the share and min_votes: not the candidate's.
  t.addVotes(1, lineOfVoxels(100, 101), vo);
  t.addView(1, View{100, 1, 50, logs({0.7, 0.2, 0.1})});
  t.addView(1, View{200, 2, 50, logs({0.6, 0.3, 0.1})});  // frame 2: the smaller box
  t.addView(1, View{300, 3, 50, logs({0.5, 0.4, 0.1})});
  t.addView(2, View{200, 2, 80, logs({0.1, 0.8, 0.1})});  // frame 2: the larger box
  t.addView(2, View{400, 4, 80, logs({0.2, 0.7, 0.1})});
  int32_t next = 7;
  auto new_id = [&] { return next++; };
  std::set<VoxelKey> free;
  auto occupied = [&](VoxelKey k) { return !free.count(k); };

  t.update(occupied, vo, half, 3, new_id);
  ASSERT_EQ(t.objects().size(), 1u);
  const Object merged = t.objects().begin()->second;
  EXPECT_EQ(merged.id, 7);
  EXPECT_EQ(merged.candidates, (std::vector<int32_t>{1, 2}));
  EXPECT_EQ(merged.num_views, 4) << "frame 2 counts once";
  EXPECT_EQ(merged.num_voxels, 30);
  EXPECT_EQ(t.candidates().at(1).voxels.size(), 20u);
  const double want_c1 =
      std::log(0.2) + std::log(0.8) + std::log(0.4) + std::log(0.7);  // frame 2 from the larger box
  EXPECT_NEAR(merged.log_evidence[1], want_c1, 1e-5);
  EXPECT_EQ(merged.label, 1);
  EXPECT_EQ(merged.first_seen_utime, 100);
  EXPECT_EQ(merged.last_seen_utime, 400);

  // The shared voxels turn free (a full SLAM map moved them): the candidates split. The part with
  // the lower candidate keeps the id, the other gets a new one, each with its own views only.
  for (VoxelKey k : lineOfVoxels(10, 20)) free.insert(k);
  t.update(occupied, vo, half, 3, new_id);
  ASSERT_EQ(t.objects().size(), 2u);
  const Object& a = t.objects().at(7);
  EXPECT_EQ(a.candidates, (std::vector<int32_t>{1}));
  EXPECT_EQ(a.num_views, 3);
  EXPECT_NEAR(a.log_evidence[0], std::log(0.7) + std::log(0.6) + std::log(0.5), 1e-5);
  ASSERT_TRUE(t.objects().count(8));
  const Object& b = t.objects().at(8);
  EXPECT_EQ(b.candidates, (std::vector<int32_t>{2}));
  EXPECT_EQ(b.num_views, 2);
  EXPECT_NEAR(b.log_evidence[1], std::log(0.8) + std::log(0.7), 1e-5);

  // Nothing changes: nothing is renumbered.
  t.update(occupied, vo, half, 3, new_id);
  EXPECT_TRUE(t.objects().count(7) && t.objects().count(8));
  EXPECT_EQ(next, 9);

  // They merge again: the lower previous id survives with the union of the evidence.
  free.clear();
  t.update(occupied, vo, half, 3, new_id);
  ASSERT_EQ(t.objects().size(), 1u);
  EXPECT_EQ(t.objects().begin()->first, 7);
  EXPECT_EQ(t.objects().begin()->second.num_views, 4);
  EXPECT_NEAR(t.objects().begin()->second.log_evidence[1], want_c1, 1e-5);
}

// A user's label is held by the candidates of the object it was given to: a split leaves it on
// both parts, a merge with an unlabelled object keeps it, and an unknown id is refused.
TEST(ObjectTable, AUserLabelStaysWithTheCandidatesThroughSplitsAndMerges) {
  const VotingOptions vo = twoVotesAndHalfTheViews();
  const GroupingOptions half = halfOverlapAndHalfSize();
  ObjectTable t(0.01);
  for (int v = 0; v < 3; ++v)
    t.addVotes(1, lineOfVoxels(0, 20), vo), t.addVotes(2, lineOfVoxels(10, 30), vo);
  t.addView(1, View{100, 1, 50, logs({0.7, 0.2, 0.1})});
  t.addView(2, View{200, 2, 80, logs({0.1, 0.8, 0.1})});
  int32_t next = 7;
  auto new_id = [&] { return next++; };
  std::set<VoxelKey> free;
  auto occupied = [&](VoxelKey k) { return !free.count(k); };
  t.update(occupied, vo, half, 3, new_id);
  ASSERT_EQ(t.objects().size(), 1u);
  EXPECT_FALSE(t.setUserLabel(99, "temple"));
  ASSERT_TRUE(t.setUserLabel(7, "temple"));
  EXPECT_EQ(t.objects().at(7).user_label, "temple");

  for (VoxelKey k : lineOfVoxels(10, 20)) free.insert(k);  // split
  t.update(occupied, vo, half, 3, new_id);
  ASSERT_EQ(t.objects().size(), 2u);
  EXPECT_EQ(t.objects().at(7).user_label, "temple");
  EXPECT_EQ(t.objects().at(8).user_label, "temple");
  ASSERT_TRUE(t.setUserLabel(8, ""));  // taken back from one part
  t.update(occupied, vo, half, 3, new_id);
  EXPECT_EQ(t.objects().at(8).user_label, "");
  free.clear();  // merged again: the labelled candidate carries it into the whole
  t.update(occupied, vo, half, 3, new_id);
  ASSERT_EQ(t.objects().size(), 1u);
  EXPECT_EQ(t.objects().begin()->second.user_label, "temple");
}

// One object, two candidates: the object alone and the object with its neighbour (the can and the
// mug beside it). In a frame that boxed both, the view that counts is the one that takes its box
// for an object most surely, not the larger box; on a tie, the larger.
TEST(ObjectTable, AFrameBoxedByTwoCandidatesCountsTheMostObjectLikeBox) {
  VotingOptions vo;
  ObjectTable t(0.01);
  for (int v = 0; v < 3; ++v)
    t.addVotes(1, lineOfVoxels(0, 20), vo), t.addVotes(2, lineOfVoxels(0, 20), vo);
  // Classes: can, mug, background.
  t.addView(1, View{100, 1, 50, logs({0.8, 0.1, 0.1})});   // the can alone
  t.addView(2, View{100, 1, 120, logs({0.3, 0.3, 0.4})});  // the can and the mug: larger, less sure
  t.addView(1, View{200, 2, 50, logs({0.6, 0.2, 0.2})});
  t.addView(2, View{200, 2, 60, logs({0.5, 0.3, 0.2})});  // the same p(background): the larger
  int32_t next = 1;
  t.update([](VoxelKey) { return true; }, vo, GroupingOptions{}, 3, [&] { return next++; });
  ASSERT_EQ(t.objects().size(), 1u);
  const Object& o = t.objects().begin()->second;
  EXPECT_EQ(o.candidates, (std::vector<int32_t>{1, 2}));
  EXPECT_EQ(o.num_views, 2);
  EXPECT_NEAR(o.log_evidence[0], std::log(0.8) + std::log(0.5), 1e-5);
  EXPECT_NEAR(o.log_evidence[2], std::log(0.1) + std::log(0.2), 1e-5);
  EXPECT_EQ(o.label, 0);
}

// A coarse candidate (a cluster of the table top, or one seen in few views that kept much of its
// boxes' background) contains the voxels of two small objects: each small one overlaps it fully,
// but a part is not merged into the whole it lies in, so three objects stay three.
TEST(ObjectTable, APartIsNotMergedIntoTheWholeItLiesIn) {
  VotingOptions vo;
  ObjectTable t(0.01);
  for (int v = 0; v < 3; ++v) {
    t.addVotes(1, lineOfVoxels(0, 200), vo);    // the whole
    t.addVotes(2, lineOfVoxels(10, 40), vo);    // a mug on it
    t.addVotes(3, lineOfVoxels(100, 130), vo);  // a bowl on it
    t.addVotes(4, lineOfVoxels(12, 42), vo);    // the mug again, under a new id (re-clustered)
  }
  // Classes: mug, bowl, background. The whole is called background.
  t.addView(1, View{100, 1, 10, logs({0.1, 0.1, 0.8})});
  for (int32_t c : {2, 4}) t.addView(c, View{100, 1, 10, logs({0.7, 0.2, 0.1})});
  t.addView(3, View{100, 1, 10, logs({0.2, 0.7, 0.1})});
  int32_t next = 1;
  t.update([](VoxelKey) { return true; }, vo, GroupingOptions{}, 3, [&] { return next++; });
  ASSERT_EQ(t.objects().size(), 3u);
  std::set<std::vector<int32_t>> groups;
  for (const auto& [id, o] : t.objects()) groups.insert(o.candidates);
  EXPECT_EQ(groups, (std::set<std::vector<int32_t>>{{1}, {2, 4}, {3}}));
}

// With the label it is: a mug's handle called mug lies in the mug called mug (one object, the
// union of their evidence); a bowl-called part of the same mug, and the same geometry called
// background, stay apart. A candidate called mug without voxels yet joins the mug when its boxes
// put it inside the mug, not when they put it elsewhere. same_label_overlap 0 turns this off.
TEST(ObjectTable, APartCalledLikeTheWholeItLiesInIsMergedIntoIt) {
  VotingOptions vo;
  auto build = [&](ObjectTable& t) {
    for (int v = 0; v < 3; ++v) {
      t.addVotes(1, lineOfVoxels(0, 100), vo);   // the mug
      t.addVotes(2, lineOfVoxels(80, 100), vo);  // its handle, called mug
      t.addVotes(3, lineOfVoxels(0, 20), vo);    // its bottom, called bowl
      t.addVotes(4, lineOfVoxels(40, 60), vo);   // a part called background
    }
    t.addView(1, View{100, 1, 50, logs({0.8, 0.1, 0.1})});
    t.addView(1, View{200, 2, 50, logs({0.7, 0.2, 0.1})});
    t.addView(2, View{300, 3, 10, logs({0.6, 0.1, 0.3})});
    t.addView(3, View{300, 3, 10, logs({0.2, 0.6, 0.2})});
    t.addView(4, View{400, 4, 10, logs({0.3, 0.1, 0.6})});
    // Voxel keys 40000 + i along x at 0.01: x from 72.32 to 73.32, y = z = 72.325.
    t.addView(5, View{500, 5, 10, logs({0.6, 0.2, 0.2})});
    t.addBoxPosition(5, Eigen::Vector3d(72.8, 72.325, 72.325), 0.3);
    t.addView(6, View{500, 5, 10, logs({0.6, 0.2, 0.2})});
    t.addBoxPosition(6, Eigen::Vector3d(75.0, 72.325, 72.325), 0.3);
  };
  int32_t next = 1;
  ObjectTable t(0.01);
  build(t);
  t.update([](VoxelKey) { return true; }, vo, GroupingOptions{}, 3, [&] { return next++; });
  std::map<std::vector<int32_t>, const Object*> by_group;
  for (const auto& [id, o] : t.objects()) by_group[o.candidates] = &o;
  ASSERT_EQ(by_group.size(), 4u);
  ASSERT_TRUE(by_group.count({1, 2, 5}));
  EXPECT_TRUE(by_group.count({3}) && by_group.count({4}) && by_group.count({6}));
  const Object& mug = *by_group.at({1, 2, 5});
  EXPECT_EQ(mug.label, 0);
  EXPECT_EQ(mug.num_views, 4);
  EXPECT_NEAR(mug.log_evidence[0], std::log(0.8) + std::log(0.7) + std::log(0.6) + std::log(0.6),
              1e-5);
  EXPECT_EQ(mug.num_voxels, 100);

  GroupingOptions off;
  off.same_label_overlap = 0;
  ObjectTable apart(0.01);
  build(apart);
  apart.update([](VoxelKey) { return true; }, vo, off, 3, [&] { return next++; });
  EXPECT_EQ(apart.objects().size(), 6u);
}

TEST(ObjectTable, RarelyVotedVoxelsAreForgotten) {
  VotingOptions vo;
  vo.forget_share = 0.1;
  ObjectTable t(0.01);
  const VoxelKey once = packVoxelKey(1, 2, 3), always = packVoxelKey(4, 5, 6);
  t.addVotes(1, {once, always}, vo);
  for (int i = 0; i < 19; ++i) t.addVotes(1, {always}, vo);
  using Votes = std::vector<std::pair<VoxelKey, int32_t>>;
  EXPECT_EQ(t.candidates().at(1).votes, (Votes{{always, 20}})) << "1 vote in 20 views < 10%";
  t.addVotes(1, {once, always, always}, vo);
  t.addVotes(1, {always, once}, vo);
  EXPECT_EQ(t.candidates().at(1).votes, (Votes{{once, 2}, {always, 22}}))
      << "sorted by voxel; a key given twice in one view counts once";
}

// A long session: two candidates of one object seen in every frame for 300 s at 30 Hz, a full-rate
// period of 10 s. The views older than it are merged into the same time bins for both candidates
// (a frame still counts once per object), each standing for the frames of its bin, so the evidence
// is what all the frames give (to float rounding) while the views kept stay bounded: the last 10 s
// plus 16 bins per doubling of age. Candidates seen in a few frames long ago are forgotten; one
// holding a user's label is not.
TEST(ObjectTable, OldViewsAreMergedIntoTheSameBinsAndKeepTheirEvidence) {
  VotingOptions vo;
  ObjectTable t(0.01, 10.0), every(0.01, 0);
  for (int v = 0; v < 3; ++v)
    for (ObjectTable* x : {&t, &every})
      x->addVotes(1, lineOfVoxels(0, 20), vo), x->addVotes(2, lineOfVoxels(0, 20), vo);
  const int frames = 9000;
  auto utime = [](int f) { return 1000000 + int64_t{f} * 33333; };
  // 40 tentative clusters seen in 3 frames each during the first 4 s; cluster 140 labelled.
  for (int c = 100; c < 140 + 1; ++c)
    for (int f = (c - 100) * 3; f < (c - 100) * 3 + 3; ++f)
      t.addView(c, View{utime(f), f, 10, logs({0.3, 0.3, 0.4})});
  // Two objects seen only in the first 10 s, each in its own voxels: 150 in 3 frames, 151 in 300.
  for (int v = 0; v < 3; ++v)
    t.addVotes(150, lineOfVoxels(300, 310), vo), t.addVotes(151, lineOfVoxels(400, 410), vo);
  for (int f = 0; f < 300; ++f) {
    if (f < 3) t.addView(150, View{utime(f), f, 40, logs({0.8, 0.1, 0.1})});
    t.addView(151, View{utime(f), f, 40, logs({0.8, 0.1, 0.1})});
  }
  int32_t next = 1;
  auto update = [&](ObjectTable& x) {
    x.update([](VoxelKey) { return true; }, vo, GroupingOptions{}, 3, [&] { return next++; });
  };
  update(t);
  ASSERT_TRUE(t.setUserLabel(t.objectOfCandidate(140)->id, "temple"));
  for (int f = 0; f < frames; ++f) {
    // Views that vary over the session: mostly class 0, now and then class 1.
    const double p0 = 0.5 + 0.3 * std::sin(f * 0.01);
    for (ObjectTable* x : {&t, &every}) {
      x->addView(1, View{utime(f), f, 50, logs({p0, 0.9 - p0, 0.1})});
      x->addView(2, View{utime(f), f, 80, logs({p0, 0.85 - p0, 0.15})});
    }
    if (f % 100 == 99) update(t);
  }
  update(t);
  update(every);
  const Candidate& c1 = t.candidates().at(1);
  const Candidate& c2 = t.candidates().at(2);
  std::vector<ViewKey> k1, k2;
  int64_t stood_for = 0;
  for (const auto& [k, v] : c1.views) k1.push_back(k), stood_for += v.frames;
  for (const auto& [k, v] : c2.views) k2.push_back(k);
  EXPECT_EQ(k1, k2) << "the same bins for every candidate";
  // 300 at full rate, then 5 doublings of age (10 to 300 s) of at most 16 bins (one more where a
  // level's boundary splits one); without merging 9000, with the sampling it replaced about 1,000.
  EXPECT_LE(c1.views.size(), 300u + 5 * 17);
  EXPECT_GT(c1.views.size(), 300u + 4 * 16);
  EXPECT_EQ(stood_for, frames) << "every frame in exactly one view";
  // The newest 10 s are all there, one frame each.
  EXPECT_EQ(c1.views.rbegin()->second.frames, 1);
  EXPECT_EQ(std::prev(c1.views.end(), 300)->second.frames, 1);
  EXPECT_NE(std::prev(c1.views.end(), 300)->second.seq, kMergedViewSeq);
  EXPECT_EQ(c1.views.begin()->second.seq, kMergedViewSeq);

  const Object& o = *t.objectOfCandidate(1);
  const Object& all = *every.objectOfCandidate(1);
  EXPECT_EQ(o.candidates, (std::vector<int32_t>{1, 2}));
  EXPECT_EQ(o.num_views, frames) << "a frame counts once per object";
  EXPECT_EQ(all.num_views, frames);
  EXPECT_EQ(o.label, all.label);
  EXPECT_NEAR(o.evidence_weight, all.evidence_weight, 1e-5 * all.evidence_weight);
  for (size_t c = 0; c < 3; ++c)
    EXPECT_NEAR(o.log_evidence[c], all.log_evidence[c], 1e-5 * std::abs(all.log_evidence[c]))
        << "class " << c;
  EXPECT_NEAR(o.posterior[0], all.posterior[0], 1e-4);
  // Another 300 s: the views do not grow with the session (one doubling of age: 16 bins more).
  for (int f = frames; f < 2 * frames; ++f) {
    t.addView(1, View{utime(f), f, 50, logs({0.6, 0.3, 0.1})});
    if (f % 100 == 99) update(t);
  }
  update(t);
  EXPECT_LE(t.candidates().at(1).views.size(), k1.size() + 17);

  int tentative_left = 0;
  for (int c = 100; c < 140; ++c) tentative_left += t.candidates().count(c) > 0;
  EXPECT_EQ(tentative_left, 0) << "called background and out of view for 300 s";
  ASSERT_TRUE(t.candidates().count(140)) << "a user's label is never forgotten";
  EXPECT_EQ(t.candidates().at(140).views.size(), 3u);
  EXPECT_FALSE(t.candidates().count(150)) << "3 frames 290 s ago: fewer than the 2^5 of its age";
  ASSERT_TRUE(t.candidates().count(151)) << "300 frames: kept";
  EXPECT_LE(t.candidates().at(151).views.size(), 2u) << "10 s at 290 s old: bins of 10 s";
  EXPECT_EQ(t.objectOfCandidate(151)->num_views, 300);
  EXPECT_EQ(t.objectOfCandidate(151)->label, 0);
}

// An object whose parts the proposals gave new ids as their clusters came and went: candidates 1-3
// (each seen in the first second, voted by 3, 6 and 4 views) and 4 (in view until 9.9 s), grouped
// as one object. Once 1-3 have not been seen for the full-rate period, they are folded into one
// candidate (the lowest id); the object keeps its id, its evidence, its frames and its voxels.
// Candidate 5, alone in another object, has nothing to fold into.
TEST(ObjectTable, StaleCandidatesOfAnObjectAreFoldedIntoOneThatKeepsItsEvidenceAndVoxels) {
  const VotingOptions vo = twoVotesAndHalfTheViews();
  const GroupingOptions half = halfOverlapAndHalfSize();
  ObjectTable t(0.01, 10.0);
  auto utime = [](int f) { return int64_t{f} * 100000; };  // 10 Hz
  for (int v = 0; v < 3; ++v) t.addVotes(1, lineOfVoxels(0, 20), vo);
  t.addVotes(1, lineOfVoxels(100, 101), vo);  // once in 4: below the share
  for (int v = 0; v < 6; ++v)
    t.addVotes(2, lineOfVoxels(10, v < 2 ? 35 : 30), vo);  // 30-34: 2 in 6
  for (int v = 0; v < 4; ++v) t.addVotes(3, lineOfVoxels(20, 40), vo);
  for (int v = 0; v < 3; ++v) t.addVotes(4, lineOfVoxels(5, 35), vo);
  for (int v = 0; v < 3; ++v) t.addVotes(5, lineOfVoxels(500, 510), vo);
  // Frames boxed by two or three of them, more and less object-like.
  t.addView(1, View{utime(0), 0, 50, logs({0.6, 0.3, 0.1})});
  t.addView(1, View{utime(1), 1, 50, logs({0.5, 0.3, 0.2})});
  t.addView(1, View{utime(2), 2, 50, logs({0.7, 0.2, 0.1})});
  t.addView(2, View{utime(1), 1, 70, logs({0.2, 0.7, 0.1})});
  t.addView(2, View{utime(2), 2, 70, logs({0.7, 0.2, 0.1})});  // as object-like: the larger
  t.addView(2, View{utime(3), 3, 70, logs({0.4, 0.4, 0.2})});
  t.addView(3, View{utime(2), 2, 90, logs({0.3, 0.6, 0.1})});
  t.addView(3, View{utime(4), 4, 90, logs({0.8, 0.1, 0.1})});
  t.addView(5, View{utime(5), 5, 20, logs({0.2, 0.7, 0.1})});
  t.addBoxPosition(1, Eigen::Vector3d(0.1, 0, 1), 0.1);
  t.addBoxPosition(2, Eigen::Vector3d(0.2, 0, 1), 0.3);  // the larger box, seen later
  t.addBoxPosition(3, Eigen::Vector3d(0.3, 0, 1), 0.2);
  for (int f = 0; f < 100; ++f) t.addView(4, View{utime(f), f, 60, logs({0.6, 0.3, 0.1})});
  int32_t next = 1;
  auto update = [&] {
    t.update([](VoxelKey) { return true; }, vo, half, 3, [&] { return next++; });
  };
  update();  // all seen within 10 s of the newest view (9.9 s): nothing thinned or folded
  ASSERT_EQ(t.objects().size(), 2u);
  const Object before = *t.objectOfCandidate(1);
  ASSERT_EQ(before.candidates, (std::vector<int32_t>{1, 2, 3, 4}));
  auto voxelsOf = [&](const std::vector<int32_t>& members) {  // the union of their voxels
    std::set<VoxelKey> all;
    for (int32_t c : members)
      all.insert(t.candidates().at(c).voxels.begin(), t.candidates().at(c).voxels.end());
    return std::vector<VoxelKey>(all.begin(), all.end());
  };
  const std::vector<VoxelKey> voxels_before = voxelsOf(before.candidates);
  size_t votes_before = 0;
  for (int32_t c : {1, 2, 3}) votes_before += t.candidates().at(c).votes.size();

  t.foldStaleCandidates(utime(115), vo);  // 11.5 s: candidates 1-3 and 5 unseen for 10 s
  EXPECT_TRUE(t.candidates().count(1));
  EXPECT_FALSE(t.candidates().count(2));
  EXPECT_FALSE(t.candidates().count(3));
  EXPECT_TRUE(t.candidates().count(4)) << "in view: not folded";
  EXPECT_TRUE(t.candidates().count(5)) << "alone in its object";
  const Candidate& folded = t.candidates().at(1);
  EXPECT_EQ(folded.voting_views, 6);
  EXPECT_EQ(folded.views.size(), 5u) << "frames 0-4";
  EXPECT_EQ(folded.box_positions, 3);
  EXPECT_DOUBLE_EQ(folded.box_size, 0.3) << "the largest box of the parts, as the object has it";
  EXPECT_LT(folded.votes.size(), votes_before) << "below-threshold votes are not carried over";
  EXPECT_FALSE(std::binary_search(folded.votes.begin(), folded.votes.end(),
                                  std::make_pair(lineOfVoxels(100, 101)[0], 0),
                                  [](const auto& a, const auto& b) { return a.first < b.first; }));
  update();
  const Object& after = *t.objectOfCandidate(1);
  EXPECT_EQ(after.id, before.id);
  EXPECT_EQ(after.candidates, (std::vector<int32_t>{1, 4}));
  EXPECT_EQ(after.num_views, before.num_views);
  EXPECT_EQ(after.label, before.label);
  ASSERT_EQ(after.log_evidence.size(), before.log_evidence.size());
  for (size_t c = 0; c < 3; ++c) EXPECT_NEAR(after.log_evidence[c], before.log_evidence[c], 1e-9);
  EXPECT_EQ(after.num_voxels, before.num_voxels);
  EXPECT_EQ(voxelsOf(after.candidates), voxels_before);
  EXPECT_TRUE(after.centroid.isApprox(before.centroid));
}

TEST(ObjectTable, BackgroundOutOfViewIsForgottenObjectsAndUserLabelsStay) {
  VotingOptions vo;
  ObjectTable t(0.01, 10.0), every(0.01, 0);
  auto utime = [](int f) { return 1000000 + int64_t{f} * 33333; };
  int32_t next = 1;
  auto update = [&](ObjectTable& x) {
    x.update([](VoxelKey) { return true; }, vo, GroupingOptions{}, 3, [&] { return next++; });
  };
  // 1: a mug seen for 1 s; 2: background seen for 1 s; 3: background always in view; 4:
  // background seen for 1 s that a user labelled.
  for (ObjectTable* x : {&t, &every}) {
    for (int f = 0; f < 30; ++f) {
      x->addView(1, View{utime(f), f, 50, logs({0.7, 0.2, 0.1})});
      x->addView(2, View{utime(f), f, 50, logs({0.1, 0.2, 0.7})});
      x->addView(4, View{utime(f), f, 50, logs({0.1, 0.2, 0.7})});
    }
    update(*x);
    ASSERT_TRUE(x->setUserLabel(x->objectOfCandidate(4)->id, "stool"));
    for (int f = 0; f < 900; ++f) {
      x->addView(3, View{utime(f), f, 50, logs({0.1, 0.2, 0.7})});
      if (f % 100 == 99) update(*x);
    }
    update(*x);
  }
  EXPECT_TRUE(t.candidates().count(1)) << "an object is remembered out of view";
  EXPECT_FALSE(t.candidates().count(2)) << "background is forgotten 10 s after its last view";
  EXPECT_TRUE(t.candidates().count(3)) << "background in view stays";
  EXPECT_TRUE(t.candidates().count(4)) << "a user's label is never forgotten";
  EXPECT_EQ(t.objects().size(), 3u);
  EXPECT_EQ(every.candidates().size(), 4u) << "without thinning nothing is forgotten";
}

// ---- The engine -----------------------------------------------------------------------------

TEST(ObjectMapEngine, FusesASyntheticSceneIntoLabelledObjectsAtTheirPlaces) {
  ObjectMapOptions o;
  ObjectMapEngine e(o);
  const test::SyntheticWorld w({}, test::SyntheticWorld::defaultObjects());
  feed(e, w, 1, 0, 40);
  const object_map_t m = e.objectMap();
  EXPECT_EQ(m.seq, 39);
  EXPECT_EQ(m.map_id, 1);
  EXPECT_EQ(m.class_names, test::SyntheticWorld::classNames());
  ASSERT_EQ(m.num_objects, 3);
  for (const auto& truth : w.objects()) {
    const std::string label = test::SyntheticWorld::classNames()[static_cast<size_t>(truth.cls)];
    const object_t* ob = findLabel(m, label);
    ASSERT_TRUE(ob) << "no " << label;
    EXPECT_EQ(ob->map_id, 1);
    EXPECT_EQ(ob->num_views, 40);
    EXPECT_GT(ob->num_voxels, 50);
    const Eigen::Vector3d c(ob->centroid[0], ob->centroid[1], ob->centroid[2]);
    EXPECT_LT((c - truth.centre).norm(), 0.015) << label << " at " << c.transpose();
    for (int a = 0; a < 3; ++a) {
      EXPECT_GT(ob->extent[a], 2 * truth.half_size[a] - 0.02) << label << " axis " << a;
      EXPECT_LT(ob->extent[a], 2 * truth.half_size[a] + 0.06) << label << " axis " << a;
    }
    const float* top = &*std::max_element(ob->posterior.begin(), ob->posterior.end());
    EXPECT_EQ(top - ob->posterior.data(), truth.cls);
    EXPECT_EQ(ob->first_seen_utime, w.utime(0));
    EXPECT_EQ(ob->last_seen_utime, w.utime(39));
  }
  // The same input gives the same bytes (lockstep replays rely on it).
  ObjectMapEngine again(o);
  feed(again, w, 1, 0, 40);
  EXPECT_EQ(encode(again.objectMap()), encode(m));
}

// Merged views go into the saved table with the frames they stand for and come back with them.
TEST(ObjectMapEngine, MergedViewsAreSavedWithTheFramesTheyStandFor) {
  ObjectMapOptions o;
  o.views_full_rate_s = 0.3;  // 40 frames at 30 Hz: views up to 4 periods old
  ObjectMapEngine e(o);
  const test::SyntheticWorld w({}, test::SyntheticWorld::defaultObjects());
  feed(e, w, 1, 0, 40);
  const object_map_t m = e.objectMap();
  ASSERT_EQ(m.num_objects, 3);
  int merged = 0;
  for (const auto& [id, c] : e.segments().at(1)->table.candidates())
    for (const auto& [k, v] : c.views) merged += v.seq == kMergedViewSeq && v.frames > 1;
  EXPECT_GT(merged, 0);
  // 9 views at full rate, 31 older frames in merged views: each frame counted once.
  for (const auto& ob : m.objects) EXPECT_EQ(ob.num_views, 40);
  ObjectMapEngine back(o);
  back.restore(e.snapshot());
  EXPECT_EQ(encode(back.objectMap()), encode(m));
  EXPECT_EQ(back.snapshot().content, e.snapshot().content);
}

// The evaluator's accessor: a candidate id (of a SLAM map) leads to the object holding it now.
TEST(ObjectMapEngine, ACandidateLeadsToTheObjectThatHoldsIt) {
  ObjectMapEngine e(ObjectMapOptions{});
  const test::SyntheticWorld w({}, test::SyntheticWorld::defaultObjects());
  feed(e, w, 1, 0, 40);
  for (const auto& truth : w.objects()) {
    const Object* o = e.objectOfCandidate(1, truth.candidate);
    ASSERT_TRUE(o) << "candidate " << truth.candidate;
    EXPECT_TRUE(std::count(o->candidates.begin(), o->candidates.end(), truth.candidate));
    EXPECT_EQ(o->label, truth.cls);
    EXPECT_EQ(o->num_views, 40);
    const auto& objects = e.segments().at(1)->table.objects();
    ASSERT_TRUE(objects.count(o->id));
    EXPECT_EQ(&objects.at(o->id), o);
  }
  EXPECT_EQ(e.objectOfCandidate(1, 999), nullptr) << "unknown candidate";
  EXPECT_EQ(e.objectOfCandidate(2, w.objects()[0].candidate), nullptr) << "unknown map";
  // A view added after the last regrouping is seen: the accessor regroups first.
  std::string why;
  detections_t d = w.detections(39, 1);
  ASSERT_GT(d.num_boxes, 0);
  d.candidate_ids[0] = 77;
  ASSERT_TRUE(e.onDetections(d, &why)) << why;
  const Object* added = e.objectOfCandidate(1, 77);
  ASSERT_TRUE(added);
  EXPECT_EQ(added->candidates, (std::vector<int32_t>{77}));
  EXPECT_EQ(added->num_views, 1);
}

// Real time defers the regrouping (the node regroups at most every regroup_period_s): the frames
// only collect evidence and votes until regroup(), which then gives the objects that regrouping
// after every frame gives (the same candidates, labels, views and voxels; ids may differ).
TEST(ObjectMapEngine, ADeferredRegroupingGivesTheObjectsOfRegroupingEveryFrame) {
  const test::SyntheticWorld w({}, test::SyntheticWorld::defaultObjects());
  ObjectMapEngine every(ObjectMapOptions{});
  feed(every, w, 1, 0, 40);
  EXPECT_FALSE(every.regroupPending());

  ObjectMapEngine deferred(ObjectMapOptions{});
  deferred.deferRegrouping(true);
  feed(deferred, w, 1, 0, 20);
  EXPECT_TRUE(deferred.regroupPending());
  EXPECT_EQ(deferred.numObjects(), 0u) << "nothing regrouped yet";
  const int64_t before = deferred.regroupings();
  deferred.regroup();
  EXPECT_FALSE(deferred.regroupPending());
  EXPECT_EQ(deferred.regroupings(), before + 1);
  EXPECT_EQ(deferred.objectMap().num_objects, 3);
  feed(deferred, w, 1, 20, 40);
  EXPECT_EQ(deferred.objectMap().objects.at(0).num_views, 20)
      << "views since the regrouping not shown yet";
  deferred.regroup();

  const auto summary = [](const ObjectMapEngine& e) {
    std::vector<std::tuple<std::vector<int32_t>, int, int32_t, int32_t>> s;
    for (const auto& [id, o] : e.segments().at(1)->table.objects())
      s.emplace_back(o.candidates, o.label, o.num_views, o.num_voxels);
    std::sort(s.begin(), s.end());
    return s;
  };
  EXPECT_EQ(summary(deferred), summary(every));
  ASSERT_EQ(summary(every).size(), 3u);
  EXPECT_EQ(std::get<2>(summary(every)[0]), 40);
}

TEST(ObjectMapEngine, ANewMapIdStartsANewSegmentAndTheOldOneIsUnchanged) {
  ObjectMapEngine e(ObjectMapOptions{});
  const test::SyntheticWorld w1({}, test::SyntheticWorld::defaultObjects());
  feed(e, w1, 1, 0, 20);
  const object_map_t before = e.objectMap();
  ASSERT_EQ(before.num_objects, 3);

  // SLAM re-initialises: map 2, another frame of reference, the same candidate ids reused.
  auto moved = test::SyntheticWorld::defaultObjects();
  for (auto& o : moved) o.centre += Eigen::Vector3d(0.1, 0, 0.1);
  const test::SyntheticWorld w2({}, moved);
  feed(e, w2, 2, 0, 20, 20);
  const object_map_t after = e.objectMap();
  EXPECT_EQ(after.map_id, 2);
  EXPECT_EQ(e.segments().size(), 2u);
  ASSERT_EQ(after.num_objects, 6);
  std::vector<object_t> seg1;
  for (const auto& o : after.objects)
    if (o.map_id == 1) seg1.push_back(o);
  ASSERT_EQ(seg1.size(), before.objects.size());
  for (size_t i = 0; i < seg1.size(); ++i) {
    object_map_t a{}, b{};  // compare the encoded objects
    a.objects = {seg1[i]};
    b.objects = {before.objects[i]};
    a.num_objects = b.num_objects = 1;
    EXPECT_EQ(encode(a), encode(b)) << "object " << seg1[i].id << " of segment 1 changed";
  }

  // The camera restarts (seq goes back): SLAM's map 1 of the new session is a new segment.
  feed(e, w2, 1, 0, 5);
  EXPECT_EQ(e.sessions(), 2);
  EXPECT_EQ(e.segments().size(), 3u);
  EXPECT_EQ(e.currentSegment(), 3);
  const object_map_t restarted = e.objectMap();
  int in_seg1 = 0;
  for (const auto& o : restarted.objects) in_seg1 += o.map_id == 1;
  EXPECT_EQ(in_seg1, 3);

  // Queries by map id.
  object_query_t q{};
  q.kind = object_query_t::KIND_ALL;
  q.map_id = 2;
  const auto r2 = e.answer(q);
  EXPECT_EQ(r2.error, "");
  EXPECT_EQ(r2.num_objects, 3);
  q.map_id = 42;
  EXPECT_NE(e.answer(q).error.find("no map segment 42"), std::string::npos);
}

TEST(ObjectMapEngine, QueriesByLabelAndRegionAndBadQueriesGetAnError) {
  ObjectMapEngine e(ObjectMapOptions{});
  const test::SyntheticWorld w({}, test::SyntheticWorld::defaultObjects());
  feed(e, w, 1, 0, 30);
  object_query_t q{};
  q.request_id = 77;
  q.map_id = -1;
  q.kind = object_query_t::KIND_BY_LABEL;
  q.label = "coffee_mug";
  auto r = e.answer(q);
  EXPECT_EQ(r.request_id, 77);
  EXPECT_EQ(r.error, "");
  ASSERT_EQ(r.num_objects, 1);
  EXPECT_EQ(r.objects[0].label, "coffee_mug");
  // A region around the soda can only.
  q.kind = object_query_t::KIND_BY_REGION;
  const Eigen::Vector3d can = w.objects()[2].centre;
  for (int i = 0; i < 3; ++i) q.region_min[i] = can[i] - 0.02, q.region_max[i] = can[i] + 0.02;
  r = e.answer(q);
  ASSERT_EQ(r.num_objects, 1);
  EXPECT_EQ(r.objects[0].label, "soda_can");
  // Everything.
  for (int i = 0; i < 3; ++i) q.region_min[i] = -10, q.region_max[i] = 10;
  EXPECT_EQ(e.answer(q).num_objects, 3);
  q.region_min[0] = 11;
  EXPECT_NE(e.answer(q).error.find("bad region"), std::string::npos);
  q.kind = object_query_t::KIND_BY_LABEL;
  q.label = "giraffe";
  r = e.answer(q);
  EXPECT_NE(r.error.find("unknown label 'giraffe'"), std::string::npos) << r.error;
  EXPECT_EQ(r.num_objects, 0);
  q.kind = 9;
  EXPECT_NE(e.answer(q).error.find("unknown query kind 9"), std::string::npos);
}

TEST(ObjectMapEngine, MalformedInputIsRefusedWithAReason) {
  ObjectMapEngine e(ObjectMapOptions{});
  const test::SyntheticWorld w({}, test::SyntheticWorld::defaultObjects());
  std::string why;
  camera_info_t bad_camera = w.cameraInfo();
  bad_camera.width = 0;
  EXPECT_FALSE(e.onCameraInfo(bad_camera, &why));
  point_cloud_t cloud = w.keyframeClouds(1)[0];
  cloud.num_points += 1;
  EXPECT_FALSE(e.onMap(cloud, &why));
  EXPECT_NE(why.find("num_points"), std::string::npos);
  pose_t pose = w.poseMessage(0, 1);
  pose.position[0] = NAN;
  EXPECT_FALSE(e.onPose(pose, &why));
  detections_t d = w.detections(0, 1);
  d.class_names[1] = d.class_names[0];
  EXPECT_FALSE(e.onDetections(d, &why));
  EXPECT_NE(why.find("repeated class name"), std::string::npos) << why;
  d = w.detections(0, 1);
  d.log_prob[0].pop_back();
  EXPECT_FALSE(e.onDetections(d, &why));
  // A box with NaN probabilities is skipped, the others are fused.
  d = w.detections(0, 1);
  d.log_prob[0][0] = NAN;
  FrameReport r;
  EXPECT_TRUE(e.onDetections(d, &why, &r));
  EXPECT_EQ(r.boxes_rejected, 1);
  EXPECT_EQ(r.boxes, d.num_boxes - 1);
  EXPECT_FALSE(r.localised);  // no pose, no camera: evidence only
  EXPECT_EQ(e.objectMap().num_objects, d.num_boxes - 1);
}

// SLAM publishes a keyframe again as its points converge, with the earlier points first: the
// engine inserts only the points it has not inserted yet; a full cloud starts over.
TEST(ObjectMapEngine, ARepublishedKeyframeInsertsOnlyItsNewPoints) {
  ObjectMapEngine e(ObjectMapOptions{});
  const test::SyntheticWorld w({}, test::SyntheticWorld::defaultObjects());
  const point_cloud_t whole = w.keyframeClouds(1)[0];
  ASSERT_FALSE(whole.full);
  ASSERT_GT(whole.num_points, 100);
  const int n = whole.num_points, k = n * 2 / 5;
  auto firstPoints = [k](point_cloud_t c) {
    c.num_points = k;
    for (auto* v : {&c.x, &c.y, &c.z, &c.depth_std}) v->resize(static_cast<size_t>(k));
    for (auto* v : {&c.r, &c.g, &c.b}) v->resize(static_cast<size_t>(k));
    c.keyframe_ids.resize(static_cast<size_t>(k));
    return c;
  };
  const point_cloud_t first = firstPoints(whole);  // the keyframe while its seeds converge
  std::string why;
  CloudReport r;
  ASSERT_TRUE(e.onMap(first, &why, &r)) << why;
  EXPECT_EQ(r.repeated, 0u);
  EXPECT_EQ(r.insert.points + r.insert.dropped, static_cast<size_t>(k));
  ASSERT_TRUE(e.onMap(whole, &why, &r)) << why;
  EXPECT_EQ(r.repeated, static_cast<size_t>(k));
  EXPECT_EQ(r.insert.points + r.insert.dropped, static_cast<size_t>(n - k));
  ASSERT_TRUE(e.onMap(whole, &why, &r)) << why;  // the same again: nothing new
  EXPECT_EQ(r.repeated, static_cast<size_t>(n));
  EXPECT_EQ(r.insert.points, 0u);
  point_cloud_t full = whole;
  full.full = true;
  full.keyframe_id = -1;
  ASSERT_TRUE(e.onMap(full, &why, &r)) << why;  // the keyframe as it is in the map: nothing to do
  EXPECT_EQ(r.repeated, static_cast<size_t>(n));
  EXPECT_EQ(r.insert.points, 0u);
  EXPECT_EQ(r.keyframes_unchanged, 1u);
  ASSERT_TRUE(e.onMap(whole, &why, &r)) << why;  // the full cloud held them all
  EXPECT_EQ(r.repeated, static_cast<size_t>(n));
  ASSERT_TRUE(e.onMap(firstPoints(full), &why, &r)) << why;  // a full cloud of the first points
  EXPECT_EQ(r.keyframes_changed, 1u);                        // replaces the keyframe's
  ASSERT_TRUE(e.onMap(whole, &why, &r)) << why;              // then the rest are new again
  EXPECT_EQ(r.repeated, static_cast<size_t>(k));
  EXPECT_EQ(r.insert.points + r.insert.dropped, static_cast<size_t>(n - k));
}

// A full cloud costs only the keyframes that changed since the clouds before it, and leaves the
// map a fresh engine given only that full cloud builds.
TEST(ObjectMapEngine, AFullCloudReplacesOnlyTheKeyframesThatChanged) {
  const test::SyntheticWorld w({}, test::SyntheticWorld::defaultObjects());
  const std::vector<point_cloud_t> parts = w.keyframeClouds(1);
  ASSERT_GE(parts.size(), 4u);
  ObjectMapEngine e(ObjectMapOptions{});
  std::string why;
  CloudReport r;
  for (const auto& c : parts) ASSERT_TRUE(e.onMap(c, &why, &r)) << why;
  point_cloud_t full = w.fullCloud(1);
  ASSERT_TRUE(e.onMap(full, &why, &r)) << why;
  EXPECT_EQ(r.keyframes_unchanged, parts.size());
  EXPECT_EQ(r.keyframes_changed + r.keyframes_removed + r.insert.points, 0u);
  // Keyframe 1 moved, keyframe 2 was culled.
  point_cloud_t next = full;
  next.x.clear(), next.y.clear(), next.z.clear(), next.depth_std.clear();
  next.r.clear(), next.g.clear(), next.b.clear(), next.keyframe_ids.clear();
  for (size_t i = 0; i < full.x.size(); ++i) {
    const int32_t kf = full.keyframe_ids[i];
    if (kf == 2) continue;
    const float dx = kf == 1 ? 0.02f : 0.0f;
    next.x.push_back(full.x[i] + dx), next.y.push_back(full.y[i]), next.z.push_back(full.z[i]);
    next.depth_std.push_back(full.depth_std[i]), next.keyframe_ids.push_back(kf);
    next.r.push_back(0), next.g.push_back(0), next.b.push_back(0);
  }
  next.num_points = static_cast<int32_t>(next.x.size());
  next.seq += 1;
  ASSERT_TRUE(e.onMap(next, &why, &r)) << why;
  EXPECT_EQ(r.keyframes_changed, 1u);
  EXPECT_EQ(r.keyframes_removed, 1u);
  EXPECT_EQ(r.keyframes_unchanged, parts.size() - 2);

  ObjectMapEngine fresh(ObjectMapOptions{});
  ASSERT_TRUE(fresh.onMap(next, &why, &r)) << why;
  const auto keys = [](const ObjectMapEngine& m) {
    std::vector<VoxelKey> k;
    for (const auto& v : m.segments().at(1)->occupancy.occupied()) k.push_back(v.key);
    return k;
  };
  EXPECT_EQ(keys(e), keys(fresh));
  EXPECT_FALSE(keys(e).empty());
}

TEST(ObjectMapEngine, ANewClassFromAnotherModelIsAddedBeforeBackground) {
  ObjectMapEngine e(ObjectMapOptions{});
  const test::SyntheticWorld w({}, test::SyntheticWorld::defaultObjects());
  std::string why;
  ASSERT_TRUE(e.onDetections(w.detections(0, 1), &why));
  detections_t d = w.detections(1, 1);
  // Another model: a class more, in another order.
  d.class_names = {"soda_can", "giraffe", "coffee_mug", "bowl", "cap", "background"};
  d.num_classes = 6;
  for (auto& row : d.log_prob) row = logs({0.1, 0.1, 0.5, 0.1, 0.1, 0.1});
  ASSERT_TRUE(e.onDetections(d, &why)) << why;
  EXPECT_EQ(e.classes(), (std::vector<std::string>{"bowl", "cap", "coffee_mug", "soda_can",
                                                   "giraffe", "background"}));
  const object_map_t m = e.objectMap();
  for (const auto& o : m.objects) {
    EXPECT_EQ(o.num_classes, 6);
    EXPECT_EQ(o.num_views, 2);
    // Frame 0's model had no giraffe: that view gives it its background's log p (the old model's
    // background held giraffes), frame 1's view log 0.1; so giraffe's evidence is background's.
    EXPECT_FLOAT_EQ(o.log_evidence[4], o.log_evidence[5]) << "object " << o.id;
  }
}

// ---- Config ---------------------------------------------------------------------------------

TEST(ObjectMapConfig, ShippedYamlEqualsDefaults) {
  ObjectMapOptions file =
      loadConfig<ObjectMapOptions>(test::sourcePath("config/objectmap.yaml"), "objectmap", false);
  ObjectMapOptions defaults;
  EXPECT_TRUE(optionsEqual(file, defaults)) << describeOptions(optionListOf(file));
  EXPECT_EQ(test::readTextFile(test::sourcePath("config/objectmap.yaml")),
            defaultConfigFileText<ObjectMapOptions>("objectmap"))
      << "config/objectmap.yaml is generated from the built-in defaults: make configs";
}

namespace {

// A lockstep input of frame `seq` as the order sees it: "map 3", "pose 3", "proposals 3".
std::string describe(const LockstepInputs::Input& in) {
  if (const auto* m = std::get_if<point_cloud_t>(&in)) return "map " + std::to_string(m->seq);
  if (const auto* m = std::get_if<pose_t>(&in)) return "pose " + std::to_string(m->seq);
  return "proposals " + std::to_string(std::get<proposals_t>(in).seq);
}

template <class Msg>
Msg ofFrame(int32_t seq) {
  Msg m{};
  m.seq = seq;
  return m;
}

}  // namespace

// With several frames in the pipeline a later frame's map and pose arrive before an earlier
// frame's detections; each DETECTIONS releases the inputs of its own frame and those before, in
// their order of arrival, and late proposals (frame 0, sent just before frame 5 released them) the
// inputs of frame 5 as well, as one frame at a time would have had them.
TEST(LockstepInputs, InputsAreHandledInTheOrderOfTheFramesWhateverTheirArrival) {
  LockstepInputs order;
  std::vector<std::string> handled;
  const LockstepInputs::Handler h = [&](const LockstepInputs::Input& in) {
    handled.push_back(describe(in));
  };
  order.add(3, ofFrame<point_cloud_t>(3), h);
  order.add(3, ofFrame<pose_t>(3), h);
  order.add(3, ofFrame<proposals_t>(3), h);
  order.add(4, ofFrame<point_cloud_t>(4), h);  // frame 4 ahead of frame 3's detections
  order.add(4, ofFrame<pose_t>(4), h);
  EXPECT_TRUE(handled.empty());
  order.releaseUpTo(3, h);  // DETECTIONS 3
  EXPECT_EQ(handled, (std::vector<std::string>{"map 3", "pose 3", "proposals 3"}));
  handled.clear();
  order.add(4, ofFrame<proposals_t>(4), h);
  order.add(5, ofFrame<point_cloud_t>(5), h);
  order.add(5, ofFrame<pose_t>(5), h);
  order.add(0, ofFrame<proposals_t>(0), h);  // late: released by frame 5, the pose after 4
  order.add(5, ofFrame<proposals_t>(5), h);
  order.add(6, ofFrame<pose_t>(6), h);
  order.releaseUpTo(4, h);  // (the late proposals are kept by seq: any time before is right)
  EXPECT_EQ(handled, (std::vector<std::string>{"map 4", "pose 4", "proposals 4", "proposals 0"}));
  handled.clear();
  order.releaseUpTo(0, h);  // the late DETECTIONS: frame 5's inputs come before it
  EXPECT_EQ(handled, (std::vector<std::string>{"map 5", "pose 5", "proposals 5"}));
  handled.clear();
  order.releaseUpTo(5, h);
  EXPECT_TRUE(handled.empty());
  EXPECT_EQ(order.waiting(), 1u);  // pose 6
  // Without DETECTIONS (the recognizer gone) at most kMaxWaiting inputs wait.
  for (int32_t s = 7; s < 7 + static_cast<int32_t>(LockstepInputs::kMaxWaiting); ++s)
    order.add(s, ofFrame<pose_t>(s), h);
  EXPECT_EQ(handled, std::vector<std::string>{"pose 6"});
  EXPECT_EQ(order.waiting(), LockstepInputs::kMaxWaiting);
}
