// Proposals without the bus: density clustering at each scale, the map filters (support plane),
// occlusion culling in the projection, stable candidate ids as the map grows, and degenerate
// input (empty map, one point, NaN points, LOST or non-finite poses, malformed clouds).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <thread>

#include "common/config.h"
#include "procs/proposals/candidate_map.h"
#include "procs/proposals/projector.h"
#include "procs/proposals/proposal_engine.h"
#include "procs/proposals/synthetic_map.h"
#include "tests/support/test_support.h"

using namespace slamaware;
using namespace slamaware::proposals;
using namespace slamaware::synthmap;

namespace {

ProposalOptions metricOptions() {
  ProposalOptions o;
  o.relative_lengths = false;  // the tests place things in map units
  o.recluster_interval_s = 0;  // every map change clustered at the next pose
  return o;
}

// One tracked pose at T: whether the engine re-clustered first, and how many boxes it gave.
std::pair<bool, int> trackedPose(ProposalEngine& engine, int seq, const SE3& T) {
  std::string why;
  bool reclustered = false;
  const proposals_t m =
      engine.onPose(poseMessage(seq, pose_t::STATE_TRACKING, T), &why, &reclustered);
  return {reclustered, m.num_boxes};
}

// Gives `engine` the camera and a map's first points: they are clustered at once, at the first
// pose (seq 0, at T), into `boxes` boxes.
void startWith(ProposalEngine& engine, const std::vector<MapPoint>& first, const SE3& T,
               int boxes) {
  std::string why;
  ASSERT_TRUE(engine.onCameraInfo(vgaInfo(), &why)) << why;
  ASSERT_TRUE(engine.onMap(cloudMessage(1, first), &why)) << why;
  const auto [ran, n] = trackedPose(engine, 0, T);
  EXPECT_TRUE(ran) << "the first points are clustered at once";
  EXPECT_EQ(n, boxes);
}

// Which of the objects (split at x = split) a candidate's points (above the table) come from.
std::set<int> sidesOf(const Candidate& c, float split) {
  std::set<int> sides;
  for (const auto& p : c.points)
    if (p.z() > 0.01f) sides.insert(p.x() < split ? 0 : 1);
  return sides;
}

// The map seen by a camera 1 m above the table looking down, then re-clustered.
bool reclusterFromAbove(CandidateMap& map) {
  map.addView(map.mapId(), lookingDown(1.0));
  return map.recluster();
}

// A dark cap's brim lying flat around a crown of radius 0.04 at the origin, 4 mm above the table
// (in its band), out to 0.1; `right_half`: only where x > 0.
std::vector<MapPoint> capBrim(bool right_half) {
  std::vector<MapPoint> brim;
  for (float x = -0.1f; x <= 0.1f; x += 0.004f)
    for (float y = -0.1f; y <= 0.1f; y += 0.004f) {
      const float r = std::hypot(x, y);
      if ((x > 0 || !right_half) && r > 0.042f && r < 0.1f)
        brim.push_back({Eigen::Vector3f(x, y, 0.004f), 40, 40, 40});
    }
  return brim;
}

}  // namespace

// At each density scale alone, two objects whose gap is larger than the scale's radius are two
// clusters, and no cluster holds points of both.
TEST(ProposalClustering, SeparatesTwoObjectsAtEveryScale) {
  const ProposalOptions base = metricOptions();
  for (int s = 0; s < base.scales; ++s) {
    ProposalOptions o = base;
    o.scales = 1;
    o.radius = base.radius * std::pow(2.0, s);
    o.max_extent = 1.0;
    const float r = static_cast<float>(o.radius);
    const float gap = 1.5f * r;  // larger than the radius
    const float rad = 0.04f, step = static_cast<float>(base.radius / 2);
    const float left = -rad - gap / 2, right = rad + gap / 2;  // centres: surfaces `gap` apart
    const auto points =
        join(cylinder(left, 0, rad, 0.1f, step), cylinder(right, 0, rad, 0.1f, step));
    const std::vector<Candidate> found = clusterPoints(points, o);
    ASSERT_GE(found.size(), 2u) << "scale " << s;
    std::set<int> seen;
    for (const auto& c : found) {
      const auto sides = sidesOf(c, 0.0f);
      EXPECT_EQ(sides.size(), 1u) << "scale " << s << ": a cluster merges across a gap of " << gap;
      seen.insert(sides.begin(), sides.end());
    }
    EXPECT_EQ(seen, (std::set<int>{0, 1})) << "scale " << s;
  }
}

// The same objects touching (gap below the finest radius) are one cluster at the coarsest scale:
// the separation above is the gap's doing, not a clustering that never merges.
TEST(ProposalClustering, MergesObjectsCloserThanTheRadius) {
  ProposalOptions o = metricOptions();
  o.scales = 1;
  o.radius = 0.064;
  o.max_extent = 1.0;
  const float rad = 0.04f, gap = 0.01f;
  const auto points = join(cylinder(-rad - gap / 2, 0, rad, 0.1f, 0.004f),
                           cylinder(rad + gap / 2, 0, rad, 0.1f, 0.004f));
  const std::vector<Candidate> found = clusterPoints(points, o);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(sidesOf(found[0], 0.0f).size(), 2u);
}

// Touching objects of different colours: position alone cannot split them at either scale; the
// second clustering, on position and colour (at the coarser scale), adds each of them alone (the
// merged pair stays too).
TEST(ProposalClustering, TouchingObjectsOfDifferentColoursAreAlsoCandidatesAlone) {
  const float rad = 0.04f, gap = 0.01f;
  const auto points = join(cylinder(-rad - gap / 2, 0, rad, 0.1f, 0.004f, 60),
                           cylinder(rad + gap / 2, 0, rad, 0.1f, 0.004f, 200));
  for (const double colour : {0.0, 40.0}) {
    ProposalOptions o = metricOptions();
    o.scales = 2;
    o.radius = 0.032;
    o.max_extent = 1.0;
    o.colour_distance = colour;
    std::multiset<size_t> sides;
    for (const auto& c : clusterPoints(points, o)) sides.insert(sidesOf(c, 0.0f).size());
    if (colour > 0)
      EXPECT_EQ(sides, (std::multiset<size_t>{1, 1, 2})) << "each object alone, and the pair";
    else
      EXPECT_EQ(sides, (std::multiset<size_t>{2})) << "position alone merges them";
  }
}

// Two objects whose gap lies between the radii of two scales: the coarser scale joins them, and
// that cluster has two parts (the finer scale's clusters, each half of it); each object alone has
// one. With split_share over 0.5 no cluster can have two parts.
TEST(ProposalClustering, TouchingObjectsJoinedAtACoarserScaleAreTwoParts) {
  const float rad = 0.04f, gap = 0.012f;  // between the radii 0.008 and 0.016
  const auto points = join(cylinder(-rad - gap / 2, 0, rad, 0.1f, 0.004f),
                           cylinder(rad + gap / 2, 0, rad, 0.1f, 0.004f));
  for (const double share : {0.35, 0.6}) {
    ProposalOptions o = metricOptions();
    o.scales = 2;
    o.split_share = share;
    int pairs = 0, singles = 0;
    for (const auto& c : clusterPoints(points, o)) {
      if (sidesOf(c, 0.0f).size() == 2) {
        ++pairs;
        EXPECT_EQ(c.parts, share < 0.5 ? 2 : 0) << "split_share " << share;
      } else {
        ++singles;
        EXPECT_LE(c.parts, 1);
      }
    }
    EXPECT_EQ(pairs, 1);
    EXPECT_EQ(singles, 2);
  }
}

// The whole map path: a table with two objects on it, 12 cm apart; the table is removed as the
// support plane and each object is a candidate spanning its own extent (down to the table),
// standing on the support; the coarsest scale (16 x 0.008) joins the two, and that candidate is
// marked as two parts (ranked after objects alone); without the table the same objects do not
// stand on one.
TEST(ProposalClustering, ObjectsOnATableAreCandidates) {
  ProposalOptions o = metricOptions();
  CandidateMap map(o);
  const auto points = join(table(0.8f, 0.004f), join(cylinder(-0.1f, 0, 0.04f, 0.12f, 0.004f),
                                                     cylinder(0.1f, 0, 0.04f, 0.08f, 0.004f)));
  map.update(1, true, 0, std::vector<int32_t>(points.size(), 0), points);
  ASSERT_TRUE(reclusterFromAbove(map));
  EXPECT_TRUE(map.stats().support);
  EXPECT_EQ(map.stats().planes, 1);
  int tall = 0, short_ = 0, pairs = 0;
  for (const auto& c : map.candidates()) {
    if (sidesOf(c, 0.0f).size() == 2) {
      ++pairs;
      EXPECT_GE(c.parts, 2) << "a candidate spanning both objects is two parts";
    }
    EXPECT_LT(c.max.z(), 0.13f);
    EXPECT_TRUE(c.on_support) << "its box is trimmed as one on a support";
    if (c.min.x() > -0.15f && c.max.x() < -0.05f && c.max.z() > 0.11f && c.min.z() < 0.005f) ++tall;
    if (c.min.x() > 0.05f && c.max.x() < 0.15f && c.max.z() > 0.07f && c.max.z() < 0.09f &&
        c.min.z() < 0.005f)
      ++short_;
  }
  EXPECT_GE(tall, 1);
  EXPECT_GE(short_, 1);
  EXPECT_LE(pairs, 1);
  // The same objects without the table: no support, and candidates that do not stand on one.
  CandidateMap bare(o);
  const auto objects =
      join(cylinder(-0.1f, 0, 0.04f, 0.12f, 0.004f), cylinder(0.1f, 0, 0.04f, 0.08f, 0.004f));
  bare.update(1, true, 0, std::vector<int32_t>(objects.size(), 0), objects);
  ASSERT_TRUE(reclusterFromAbove(bare));
  EXPECT_FALSE(bare.stats().support);
  ASSERT_FALSE(bare.candidates().empty());
  for (const auto& c : bare.candidates()) EXPECT_FALSE(c.on_support);
}

// A young map is sparse (SLAM's first keyframes: its triangulated features, a few converged
// seeds): two objects of about 50 points each, fewer than min_points. While the map holds fewer
// than young_map_points points, each is a candidate of its own (a coarse scale may also join the
// two: then as two parts); a map past that size is not young and keeps min_points.
TEST(ProposalClustering, AYoungMapsSparseObjectsAreCandidates) {
  const auto a = cylinder(-0.1f, 0, 0.04f, 0.12f, 0.025f),
             b = cylinder(0.12f, 0, 0.04f, 0.1f, 0.025f);
  ASSERT_LT(a.size(), 60u);
  ASSERT_GT(a.size(), 30u);
  const auto points = join(table(0.8f, 0.02f), join(a, b));
  for (const int young_map_points : {0, static_cast<int>(points.size()) + 1}) {
    ProposalOptions o = metricOptions();
    ASSERT_EQ(o.min_points, 60);
    o.young_map_points = young_map_points;
    o.young_min_points = 15;
    CandidateMap map(o);
    map.update(1, true, 0, std::vector<int32_t>(points.size(), 0), points);
    ASSERT_TRUE(reclusterFromAbove(map));
    const bool young = young_map_points > 0;
    EXPECT_EQ(map.stats().young, young);
    EXPECT_TRUE(map.stats().support);
    std::set<int> sides;
    for (const auto& c : map.candidates()) {
      const std::set<int> s = sidesOf(c, 0.01f);
      if (s.size() == 2) {
        EXPECT_GE(c.parts, 2) << "a candidate spanning both objects is two parts";
        continue;
      }
      sides.insert(s.begin(), s.end());
    }
    EXPECT_EQ(sides.size(), young ? 2u : 0u) << "young_map_points " << young_map_points;
  }
}

// A young map's object is often in pieces with no converged seed between them yet (a plain bowl's
// two rims): here two pieces 8 cm apart, more than the fourth radius (8 x 0.008). A young map is
// clustered at young_radius_scale times the radii: with four scales, at 1.5 (12 cm) one candidate
// spans both pieces, at 1 none does; the finer scales still give each piece alone.
TEST(ProposalClustering, AYoungMapsPiecesOfOneObjectAreOneCandidate) {
  const auto a = cylinder(-0.06f, 0, 0.02f, 0.1f, 0.02f),
             b = cylinder(0.06f, 0, 0.02f, 0.1f, 0.02f);
  ASSERT_GE(a.size(), 15u);
  ASSERT_LT(a.size(), 60u);
  const auto points = join(table(0.8f, 0.02f), join(a, b));
  for (const double scale : {1.0, 1.5}) {
    ProposalOptions o = metricOptions();
    o.scales = 4;
    ASSERT_DOUBLE_EQ(o.radius, 0.008);
    o.young_map_points = static_cast<int>(points.size()) + 1;
    o.young_radius_scale = scale;
    CandidateMap map(o);
    map.update(1, true, 0, std::vector<int32_t>(points.size(), 0), points);
    ASSERT_TRUE(reclusterFromAbove(map));
    EXPECT_TRUE(map.stats().young);
    int whole = 0;
    std::set<int> alone;
    for (const auto& c : map.candidates()) {
      const std::set<int> s = sidesOf(c, 0.0f);
      if (s.size() == 2) ++whole;
      if (s.size() == 1) alone.insert(*s.begin());
    }
    EXPECT_EQ(whole, scale > 1 ? 1 : 0) << "young_radius_scale " << scale;
    EXPECT_EQ(alone.size(), 2u) << "young_radius_scale " << scale;
  }
}

// A cap: a dark crown and its brim, which lies flat in the support's band (as low as the table's
// depth noise) and is removed with it. The brim is the crown's colour, which the table hardly
// has: it is taken back by the crown's candidates. The table, and a flat towel of another colour
// touching the brim, are not.
TEST(ProposalClustering, AnObjectsPartInTheSupportsBandIsTheObjects) {
  const std::vector<MapPoint> brim = capBrim(true);
  std::vector<MapPoint> towel;
  for (float x = 0.106f; x <= 0.2f; x += 0.004f)
    for (float y = -0.05f; y <= 0.05f; y += 0.004f)
      towel.push_back({Eigen::Vector3f(x, y, 0.004f), 120, 60, 60});
  const auto points =
      join(join(table(0.8f, 0.004f), cylinder(0, 0, 0.04f, 0.1f, 0.004f, 40)), join(brim, towel));
  for (const double grow : {0.0, 0.06}) {
    ProposalOptions o = metricOptions();
    o.band_grow = grow;
    CandidateMap map(o);
    map.update(1, true, 0, std::vector<int32_t>(points.size(), 0), points);
    ASSERT_TRUE(reclusterFromAbove(map));
    ASSERT_TRUE(map.stats().support);
    float reach = 0;  // how far in +x the crown's candidates reach
    for (const auto& c : map.candidates()) {
      for (const auto& p : c.points)
        EXPECT_LT(p.x(), 0.104f) << "the towel was taken (band_grow " << grow << ")";
      EXPECT_LT((c.max - c.min).head<2>().maxCoeff(), 0.21f)
          << "the table was taken (band_grow " << grow << ")";
      reach = std::max(reach, c.max.x());
    }
    if (grow > 0) {
      EXPECT_GT(reach, 0.09f) << "the brim was not taken";
      EXPECT_GT(map.stats().band_taken, static_cast<int64_t>(brim.size() / 2));
    } else {
      EXPECT_LT(reach, 0.05f);
      EXPECT_EQ(map.stats().band_taken, 0);
    }
  }
}

// A wide brim near the camera is a large share of the support's band: compared with the whole
// band, its colour looked like the support's and it stayed out (band_reference_elsewhere false).
// Compared with the band outside the candidate's surroundings (the table), it is the cap's.
TEST(ProposalClustering, ABrimThatIsMuchOfTheBandIsStillTheObjects) {
  const std::vector<MapPoint> brim = capBrim(false);
  const auto tabletop = table(0.8f, 0.012f);
  ASSERT_GT(brim.size(), tabletop.size() / 4) << "the brim is over a fifth of the band";
  const auto points = join(join(tabletop, cylinder(0, 0, 0.04f, 0.1f, 0.004f, 40)), brim);
  for (const bool elsewhere : {false, true}) {
    ProposalOptions o = metricOptions();
    o.band_reference_elsewhere = elsewhere;
    CandidateMap map(o);
    map.update(1, true, 0, std::vector<int32_t>(points.size(), 0), points);
    ASSERT_TRUE(reclusterFromAbove(map));
    ASSERT_TRUE(map.stats().support);
    float reach = 0;  // how far from the crown's axis the candidates reach
    for (const auto& c : map.candidates()) {
      EXPECT_LT((c.max - c.min).head<2>().maxCoeff(), 0.21f)
          << "the table was taken (elsewhere " << elsewhere << ")";
      reach = std::max({reach, c.max.x(), -c.min.x()});
    }
    if (elsewhere) {
      EXPECT_GT(reach, 0.09f) << "the brim was not taken";
      EXPECT_GT(map.stats().band_taken, static_cast<int64_t>(brim.size() / 2));
    } else {
      EXPECT_LT(reach, 0.05f) << "the whole band as reference: the brim's colour is the support's";
    }
  }
}

// The multi-keyframe check against its definition, counted point by point: a point is kept when
// its voxel and the 26 around it hold points of at least min_keyframes keyframes. Points on both
// sides of the origin (negative voxel indices), keyframes that agree and keyframes alone.
TEST(ProposalFilters, MultiViewCheckKeepsWhatEnoughKeyframesAgreeOn) {
  const double voxel = 0.01;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> where(-0.05f, 0.05f), jitter(-0.012f, 0.012f);
  std::map<int32_t, std::vector<MapPoint>> by_keyframe;
  std::set<uint32_t> hashes;
  for (int32_t kf = 3; kf < 15; ++kf) {
    hashes.insert(static_cast<uint32_t>(kf) * 2654435761u >> 25);
    // Each keyframe sees a few shared spots, and a few of its own far from everything else.
    for (int spot = 0; spot < 6; ++spot) {
      if ((kf + spot) % 3 == 0) continue;
      const Eigen::Vector3f centre(0.1f * float(spot - 3), 0.02f * float(spot % 2), -0.01f);
      for (int i = 0; i < 15; ++i)
        by_keyframe[kf].push_back(
            MapPoint{centre + Eigen::Vector3f(jitter(rng), jitter(rng), jitter(rng))});
    }
    for (int i = 0; i < 10; ++i)
      by_keyframe[kf].push_back(MapPoint{Eigen::Vector3f(float(kf), where(rng), where(rng))});
  }
  ASSERT_EQ(hashes.size(), 12u) << "the test needs keyframes of distinct hashes";
  std::vector<std::pair<int32_t, Eigen::Vector3f>> all;
  for (const auto& [kf, pts] : by_keyframe)
    for (const auto& m : pts) all.emplace_back(kf, m.p);
  const auto index = [&](const Eigen::Vector3f& p) {
    return Eigen::Vector3i(int(std::floor(p.x() / voxel)), int(std::floor(p.y() / voxel)),
                           int(std::floor(p.z() / voxel)));
  };
  for (const int min_keyframes : {2, 4, 7}) {
    std::vector<Eigen::Vector3f> expected;
    for (const auto& [kf, p] : all) {
      std::set<int32_t> agree;
      for (const auto& [other, q] : all)
        if ((index(q) - index(p)).cwiseAbs().maxCoeff() <= 1) agree.insert(other);
      if (static_cast<int>(agree.size()) >= min_keyframes) expected.push_back(p);
    }
    const std::vector<MapPoint> kept = keepMultiView(by_keyframe, voxel, min_keyframes);
    ASSERT_EQ(kept.size(), expected.size()) << "min_keyframes " << min_keyframes;
    for (size_t i = 0; i < kept.size(); ++i) EXPECT_EQ(kept[i].p, expected[i]) << i;
    EXPECT_GT(kept.size(), 0u);
    EXPECT_LT(kept.size(), all.size());
  }
  EXPECT_EQ(keepMultiView(by_keyframe, voxel, 1).size(), all.size()) << "1: off";
}

// Of two candidates on one line of sight, the far one is culled; moved aside, both are kept.
TEST(ProposalProjection, FarCandidateBehindANearOneIsCulled) {
  const ProposalOptions o = metricOptions();
  auto candidate = [](int id, float x, float z) {
    Candidate c;
    c.id = id;
    for (float u = -0.05f; u <= 0.05f; u += 0.005f)
      for (float v = -0.05f; v <= 0.05f; v += 0.005f) c.points.emplace_back(x + u, v, z);
    c.min = c.points.front();
    c.max = c.points.back();
    return c;
  };
  // Camera at the origin looking along world z.
  const SE3 T = SE3::Identity();
  ProjectionStats st;
  auto boxes = projectCandidates({candidate(1, 0, 1.0f), candidate(2, 0, 2.0f)}, vga(), T, o, &st);
  ASSERT_EQ(boxes.size(), 1u);
  EXPECT_EQ(boxes[0].candidate_id, 1);
  EXPECT_EQ(st.occluded, 1);
  EXPECT_NEAR(boxes[0].median_depth, 1.0, 1e-3);
  boxes = projectCandidates({candidate(1, 0, 1.0f), candidate(2, 0.4f, 2.0f)}, vga(), T, o, &st);
  EXPECT_EQ(boxes.size(), 2u);
  EXPECT_EQ(st.occluded, 0);
}

TEST(ProposalProjection, SmallBoxesAreDroppedAndOverlapsSuppressed) {
  ProposalOptions o = metricOptions();
  o.nms_iou = 0.5;  // the stage's own suppression (off by default: the recognizer's, by confidence)
  auto square = [](int id, float x, float half, int scale) {
    Candidate c;
    c.id = id;
    c.scale = scale;
    for (float u = -half; u <= half; u += half / 10)
      for (float v = -half; v <= half; v += half / 10) c.points.emplace_back(x + u, v, 1.0f);
    return c;
  };
  // 0.01 at 1 m with f = 500: 10 px, under 20 px.
  auto boxes = projectCandidates({square(1, 0, 0.01f, 0)}, vga(), SE3::Identity(), o);
  EXPECT_TRUE(boxes.empty());
  // Two near-identical boxes: one survives, the finer scale.
  boxes = projectCandidates({square(2, 0, 0.1f, 1), square(3, 0.005f, 0.1f, 0)}, vga(),
                            SE3::Identity(), o);
  ASSERT_EQ(boxes.size(), 1u);
  EXPECT_EQ(boxes[0].candidate_id, 3);
  EXPECT_NEAR(boxes[0].w, 100, 3);
}

// A box of a candidate on a support spans its points without the outer box_trim_pct % on each
// side (a thin smear off an object does not widen it); box_trim_gap grows it back over the trimmed
// points that run on densely to the object's outline, and not over the smear. A candidate with no
// support under it is trimmed by box_trim_pct_unsupported instead.
TEST(ProposalProjection, TrimmedBoxesGrowBackToTheOutlineButNotOverASmear) {
  ProposalOptions o = metricOptions();
  o.box_trim_pct_unsupported = 0;
  Candidate c;
  c.id = 1;
  c.on_support = true;
  // A 0.2 m square at 1 m (100 px with f = 500, centred on the principal point)...
  for (float u = -0.1f; u <= 0.1001f; u += 0.005f)
    for (float v = -0.1f; v <= 0.1001f; v += 0.005f) c.points.emplace_back(u, v, 1.0f);
  // ...with a smear running 0.3 m off its right side.
  for (int i = 1; i <= 30; ++i)
    c.points.emplace_back(0.1f + 0.01f * static_cast<float>(i), 0.0f, 1.0f);
  const CameraModel cam = vga();
  const double left = cam.cx() - 50, right = cam.cx() + 50;
  auto box = [&](double trim, double gap) {
    o.box_trim_pct = trim;
    o.box_trim_gap = gap;
    const auto boxes = projectCandidates({c}, cam, SE3::Identity(), o);
    EXPECT_EQ(boxes.size(), 1u);
    return boxes.empty() ? ProposalBox() : boxes[0];
  };
  const ProposalBox all = box(0, 0), trimmed = box(3, 0), grown = box(3, 10);
  EXPECT_GT(all.x + all.w, right + 100);        // the smear
  EXPECT_GT(trimmed.x, left + 1);               // the square's own left edge trimmed away
  EXPECT_LT(trimmed.x + trimmed.w, right + 2);  // the smear too
  EXPECT_NEAR(grown.x, left, 1.5);              // its edges back, the smear still out
  EXPECT_NEAR(grown.x + grown.w, right, 1.5);
  EXPECT_NEAR(grown.y, cam.cy() - 50, 1.5);
  EXPECT_NEAR(grown.y + grown.h, cam.cy() + 50, 1.5);
  c.on_support = false;
  const ProposalBox unsupported = box(3, 0);
  EXPECT_EQ(unsupported.x, all.x);  // untrimmed, the smear too
  EXPECT_EQ(unsupported.w, all.w);
  o.box_trim_pct_unsupported = 3;
  EXPECT_EQ(box(3, 0).w, trimmed.w);
}

// Two touching objects, found alike at more scales than the larger of them alone, and boxed
// almost as that one: the pair would suppress it. A cluster of two parts ranks after single
// objects, so the larger object keeps its box and the pair is suppressed.
TEST(ProposalProjection, APairOfTouchingObjectsRanksAfterAnObjectAlone) {
  ProposalOptions o = metricOptions();
  o.nms_iou = 0.5;  // the stage's own suppression (off by default: the recognizer's, by confidence)
  auto square = [](int id, float x, float half, int stability, int parts) {
    Candidate c;
    c.id = id;
    c.stability = stability;
    c.parts = parts;
    for (float u = -half; u <= half; u += half / 10)
      for (float v = -half; v <= half; v += half / 10) c.points.emplace_back(x + u, v, 1.0f);
    return c;
  };
  for (const int pair_parts : {1, 2}) {
    const auto boxes =
        projectCandidates({square(1, 0, 0.1f, 3, pair_parts), square(2, -0.02f, 0.085f, 1, 1)},
                          vga(), SE3::Identity(), o);
    ASSERT_EQ(boxes.size(), 1u) << "the two boxes overlap by IoU > 0.5";
    EXPECT_EQ(boxes[0].candidate_id, pair_parts == 2 ? 2 : 1)
        << "pair of " << pair_parts << " parts";
  }
}

// Ids survive incremental updates: an object seen from more keyframes keeps its id, a new one
// gets a new id, and a dropped map id starts over.
TEST(ProposalIds, StableAcrossIncrementalUpdatesOfAGrowingMap) {
  const ProposalOptions o = metricOptions();
  CandidateMap map(o);
  const auto tab = table(0.8f, 0.004f);
  const auto a = cylinder(-0.15f, 0, 0.04f, 0.1f, 0.004f);
  const auto b = cylinder(0.15f, 0.1f, 0.03f, 0.08f, 0.004f);
  // Keyframe 0: the table and the lower half of object a.
  std::vector<MapPoint> a_low, a_high;
  for (const auto& p : a) (p.p.z() < 0.05f ? a_low : a_high).push_back(p);
  map.update(1, false, 0, {}, join(tab, a_low));
  ASSERT_TRUE(reclusterFromAbove(map));
  // The candidates that are a whole object (centred on it, as wide as it).
  auto idNear = [&](float x) {
    std::set<int32_t> ids;
    for (const auto& c : map.candidates())
      if (std::abs(0.5f * (c.min.x() + c.max.x()) - x) < 0.02f && c.max.x() - c.min.x() > 0.05f)
        ids.insert(c.id);
    return ids;
  };
  auto shared = [](const std::set<int32_t>& a, const std::set<int32_t>& b) {
    for (int32_t id : a)
      if (b.count(id)) return true;
    return false;
  };
  const auto a_ids = idNear(-0.15f);
  ASSERT_FALSE(a_ids.empty());
  EXPECT_FALSE(map.recluster()) << "re-clustered without a change";
  // Keyframe 1 adds the upper half of a; keyframe 2 adds object b.
  map.update(1, false, 1, {}, a_high);
  ASSERT_TRUE(reclusterFromAbove(map));
  const auto a_ids2 = idNear(-0.15f);
  ASSERT_FALSE(a_ids2.empty());
  EXPECT_TRUE(shared(a_ids, a_ids2)) << "object a lost its id when its top was added";
  map.update(1, false, 2, {}, b);
  ASSERT_TRUE(reclusterFromAbove(map));
  EXPECT_TRUE(shared(idNear(-0.15f), a_ids2)) << "object a lost its id when b appeared";
  const auto b_ids = idNear(0.15f);
  ASSERT_FALSE(b_ids.empty());
  for (int32_t id : b_ids) EXPECT_FALSE(a_ids2.count(id));
  // Keyframe 2 re-published (its depths refined): ids stay.
  map.update(1, false, 2, {}, b);
  ASSERT_TRUE(reclusterFromAbove(map));
  EXPECT_EQ(idNear(0.15f), b_ids);
  // A new map id starts over: nothing of the old map is proposed.
  map.update(2, false, 0, {}, tab);
  ASSERT_TRUE(reclusterFromAbove(map));
  EXPECT_TRUE(map.candidates().empty());
}

// keep_lost_s: a candidate that a re-clustering does not find again, and whose place no new
// cluster holds (its points were left out of that clustering), stays a candidate with its id for
// keep_lost_s of frame time, ranked after the candidates found; one whose voxels a new cluster
// holds (merged into it) is dropped at once, and so is every lost one with keep_lost_s 0. A dropped
// candidate's cluster that comes back at the same scale takes its id back; at another scale, or
// mostly elsewhere, it is a new candidate.
TEST(ProposalIds, ALostCandidateIsKeptForKeepLostSeconds) {
  auto candidate = [](const std::vector<MapPoint>& pts) {
    Candidate c;
    for (const auto& p : pts) c.points.push_back(p.p);
    c.min = c.max = c.points.front();
    for (const auto& q : c.points) {
      c.min = c.min.cwiseMin(q);
      c.max = c.max.cwiseMax(q);
    }
    return c;
  };
  const auto a = cylinder(-0.15f, 0, 0.04f, 0.1f, 0.004f),
             b = cylinder(0.15f, 0, 0.04f, 0.1f, 0.004f);
  auto clustering = [&](std::vector<Candidate> found) {
    Clustering c;
    c.map_id = 1;
    c.found = std::move(found);
    c.key_voxel = 0.01;
    return c;
  };
  auto ids = [](const CandidateMap& m) {
    std::map<int32_t, int64_t> out;  // id -> lost_since
    for (const auto& c : m.candidates()) out[c.id] = c.lost_since;
    return out;
  };
  ProposalOptions o = metricOptions();
  o.keep_lost_s = 1.0;
  CandidateMap map(o);
  map.update(1, false, 0, {}, join(a, b));
  Candidate stable_b = candidate(b);
  stable_b.stability = 2;  // found at two scales: it would rank first
  ASSERT_TRUE(map.adopt(clustering({candidate(a), stable_b}), 0));
  const auto first = ids(map);
  ASSERT_EQ(first.size(), 2u);
  const int32_t id_a = first.begin()->first, id_b = std::next(first.begin())->first;
  // b left out of the next clusterings: kept, lost since the first of them, until 1 s later.
  ASSERT_TRUE(map.adopt(clustering({candidate(a)}), 500000));
  EXPECT_EQ(ids(map), (std::map<int32_t, int64_t>{{id_a, -1}, {id_b, 500000}}));
  ASSERT_TRUE(map.adopt(clustering({candidate(a)}), 1500000));
  EXPECT_EQ(ids(map), (std::map<int32_t, int64_t>{{id_a, -1}, {id_b, 500000}}))
      << "lost 1 s ago: still kept";
  // Ranked after the candidate found, though found at more scales.
  const auto boxes =
      projectCandidates(map.candidates(), vga(), lookAt({0, -0.5, 0.3}, {0, 0, 0.05}), o);
  ASSERT_EQ(boxes.size(), 2u);
  EXPECT_EQ(boxes[0].candidate_id, id_a);
  EXPECT_EQ(boxes[1].candidate_id, id_b);
  EXPECT_TRUE(boxes[1].lost);
  ASSERT_TRUE(map.adopt(clustering({candidate(a)}), 1500001));
  EXPECT_EQ(ids(map), (std::map<int32_t, int64_t>{{id_a, -1}}))
      << "lost more than 1 s ago: dropped";
  // Found again: it takes its id back.
  ASSERT_TRUE(map.adopt(clustering({candidate(a), candidate(b)}), 1600000));
  EXPECT_EQ(ids(map), (std::map<int32_t, int64_t>{{id_a, -1}, {id_b, -1}}));
  // a merged into a cluster with b: the new cluster holds a's voxels, a is not kept beside it.
  ASSERT_TRUE(map.adopt(clustering({candidate(join(a, b))}), 1700000));
  ASSERT_EQ(map.candidates().size(), 1u);
  EXPECT_EQ(map.candidates()[0].lost_since, -1);
  // keep_lost_s 0: a candidate not found again is dropped at once.
  CandidateMap plain(metricOptions());
  plain.update(1, false, 0, {}, join(a, b));
  ASSERT_TRUE(plain.adopt(clustering({candidate(a), candidate(b)}), 0));
  const auto plain_ids = ids(plain);
  ASSERT_TRUE(plain.adopt(clustering({candidate(a)}), 500000));
  EXPECT_EQ(plain.candidates().size(), 1u);
  // Clusterings later, b's cluster comes back (a little grown) beside a new one: b takes its id
  // back, the new one gets a new id.
  ASSERT_TRUE(plain.adopt(clustering({candidate(a)}), 600000));
  const auto c = cylinder(0.45f, 0, 0.04f, 0.1f, 0.004f);
  const auto b_grown = join(b, cylinder(0.15f, 0, 0.045f, 0.1f, 0.004f));
  ASSERT_TRUE(plain.adopt(clustering({candidate(c), candidate(a), candidate(b_grown)}), 900000));
  const auto back = ids(plain);
  ASSERT_EQ(back.size(), 3u);
  for (const auto& [id, since] : plain_ids) EXPECT_TRUE(back.count(id)) << "id " << id;
  EXPECT_GT(back.rbegin()->first, plain_ids.rbegin()->first) << "the new cluster's id is new";
  // A cluster in b's place but mostly elsewhere is another candidate: a new id.
  CandidateMap other(metricOptions());
  other.update(1, false, 0, {}, join(a, b));
  ASSERT_TRUE(other.adopt(clustering({candidate(a), candidate(b)}), 0));
  ASSERT_TRUE(other.adopt(clustering({candidate(a)}), 500000));
  auto wide = b;  // b and three more like it in a row: a quarter of its voxels are b's
  for (float y : {0.12f, 0.24f, 0.36f}) wide = join(wide, cylinder(0.15f, y, 0.04f, 0.1f, 0.004f));
  ASSERT_TRUE(other.adopt(clustering({candidate(a), candidate(wide)}), 600000));
  EXPECT_EQ(ids(other).rbegin()->first, 3) << "a third id";
  // b's region coming back as a cluster of another scale (a part or a pair at another radius
  // overlaps it as much) is another candidate: a new id.
  CandidateMap scales(metricOptions());
  scales.update(1, false, 0, {}, join(a, b));
  ASSERT_TRUE(scales.adopt(clustering({candidate(a), candidate(b)}), 0));
  ASSERT_TRUE(scales.adopt(clustering({candidate(a)}), 500000));
  Candidate b_coarser = candidate(b);
  b_coarser.scale = 1;
  ASSERT_TRUE(scales.adopt(clustering({candidate(a), b_coarser}), 600000));
  EXPECT_EQ(ids(scales).rbegin()->first, 3) << "a third id";
}

// A map of objects on a table seen from above gives boxes; degenerate input gives none and no
// crash.
TEST(ProposalEngineInput, DegenerateInputGivesNoBoxes) {
  ProposalEngine engine(metricOptions());
  std::string why;
  ASSERT_TRUE(engine.onCameraInfo(vgaInfo(), &why)) << why;
  const SE3 T = lookingDown(1.0);
  // Empty map.
  ASSERT_TRUE(engine.onMap(cloudMessage(1, {}), &why));
  EXPECT_EQ(engine.onPose(poseMessage(0, pose_t::STATE_TRACKING, T), &why).num_boxes, 0);
  // One point.
  ASSERT_TRUE(engine.onMap(cloudMessage(1, {{Eigen::Vector3f(0, 0, 0.05f), 1, 2, 3}}), &why));
  EXPECT_EQ(engine.onPose(poseMessage(1, pose_t::STATE_TRACKING, T), &why).num_boxes, 0);
  // Only NaN points.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<MapPoint> nans(500, MapPoint{Eigen::Vector3f(nan, 0, nan), 0, 0, 0});
  ASSERT_TRUE(engine.onMap(cloudMessage(1, nans), &why));
  EXPECT_EQ(engine.onPose(poseMessage(2, pose_t::STATE_TRACKING, T), &why).num_boxes, 0);
  // A real scene with NaN points mixed in: boxes, all finite.
  auto scene = join(table(0.8f, 0.004f), join(cylinder(-0.1f, 0, 0.04f, 0.12f, 0.004f), nans));
  ASSERT_TRUE(engine.onMap(cloudMessage(1, scene), &why));
  proposals_t m = engine.onPose(poseMessage(3, pose_t::STATE_TRACKING, T), &why);
  ASSERT_GE(m.num_boxes, 1);
  EXPECT_EQ(m.seq, 3);
  for (const auto& b : m.boxes)
    EXPECT_TRUE(std::isfinite(b.x) && std::isfinite(b.w) && b.w >= 20 && b.h >= 20);
  // The same map, but SLAM is lost, initialising, or on another map: no boxes.
  EXPECT_EQ(engine.onPose(poseMessage(4, pose_t::STATE_LOST, T), &why).num_boxes, 0);
  EXPECT_EQ(engine.onPose(poseMessage(5, pose_t::STATE_INITIALIZING, T), &why).num_boxes, 0);
  EXPECT_EQ(engine.onPose(poseMessage(6, pose_t::STATE_TRACKING, T, 7), &why).num_boxes, 0);
  // A pose that is not finite: no boxes, and the reason names the message.
  pose_t bad = poseMessage(7, pose_t::STATE_TRACKING, T);
  bad.position[0] = std::numeric_limits<double>::quiet_NaN();
  why.clear();
  EXPECT_EQ(engine.onPose(bad, &why).num_boxes, 0);
  EXPECT_NE(why.find("SLAM_POSE seq 7"), std::string::npos) << why;
  // A cloud whose arrays disagree with num_points is refused; the map is kept.
  point_cloud_t broken = cloudMessage(1, scene);
  broken.num_points += 10;
  EXPECT_FALSE(engine.onMap(broken, &why));
  EXPECT_NE(why.find("SLAM_MAP"), std::string::npos) << why;
  EXPECT_GE(engine.onPose(poseMessage(8, pose_t::STATE_TRACKING, T), &why).num_boxes, 1);
  // No camera yet: no boxes.
  ProposalEngine blind(metricOptions());
  ASSERT_TRUE(blind.onMap(cloudMessage(1, scene), &why));
  EXPECT_EQ(blind.onPose(poseMessage(0, pose_t::STATE_TRACKING, T), &why).num_boxes, 0);
  // A camera that cannot be used is refused.
  camera_info_t zero = vgaInfo();
  zero.fx = 0;
  EXPECT_FALSE(blind.onCameraInfo(zero, &why));
}

// The frame a map is initialised from was INITIALIZING when its pose came, so it got no boxes;
// once the map is late_keyframe_delay_s older than the keyframe of that frame, the candidates are
// projected into it with the keyframe's pose (the latest, bundle adjustment moves it): the
// boxes a tracked pose there gives. Only once, only for a keyframe whose frame had no boxes, and
// not for a culled one.
TEST(ProposalEngineInput, TheReferenceKeyframeGetsItsProposalsLate) {
  ProposalOptions o = metricOptions();
  o.late_keyframe_delay_s = 0.005;  // 5 poses (1 ms apart)
  const SE3 T0 =
      makeSE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.05, 0, 0)) * lookingDown(1.0);
  const SE3 T = lookingDown(1.0);
  const auto scene = join(join(table(0.8f, 0.004f), cylinder(-0.1f, 0, 0.04f, 0.12f, 0.004f)),
                          cylinder(0.15f, 0.05f, 0.04f, 0.12f, 0.004f));
  const auto keyframe = [](int seq, const SE3& pose, bool culled = false) {
    keyframe_t k{};
    k.seq = seq;
    k.utime = 1000 * seq;
    k.id = seq;
    k.map_id = 1;
    se3ToArrays(pose, k.position, k.orientation);
    k.culled = culled;
    return k;
  };
  ProposalEngine engine(o);
  std::string why;
  ASSERT_TRUE(engine.onCameraInfo(vgaInfo(), &why)) << why;
  EXPECT_EQ(engine.onPose(poseMessage(0, pose_t::STATE_INITIALIZING, T), &why).num_boxes, 0);
  EXPECT_EQ(engine.onPose(poseMessage(1, pose_t::STATE_INITIALIZING, T), &why).num_boxes, 0);
  EXPECT_EQ(engine.onPose(poseMessage(2, pose_t::STATE_INITIALIZING, T), &why).num_boxes, 0);
  // Initialised at seq 3 from seq 0: keyframes 0 (first at T, then moved to T0) and 3.
  ASSERT_TRUE(engine.onMap(cloudMessage(1, scene), &why)) << why;
  engine.onKeyframe(keyframe(0, T));
  engine.onKeyframe(keyframe(1, T, /*culled=*/true));  // a keyframe of seq 1, culled at once
  ASSERT_EQ(engine.onPose(poseMessage(3, pose_t::STATE_TRACKING, T), &why).num_boxes, 2);
  engine.onKeyframe(keyframe(0, T0));
  engine.onKeyframe(keyframe(3, T));  // its frame has boxes: nothing late
  EXPECT_EQ(engine.onPose(poseMessage(4, pose_t::STATE_TRACKING, T), &why).num_boxes, 2);
  EXPECT_TRUE(engine.takeLateProposals().empty()) << "4 ms after seq 0: not yet";
  EXPECT_EQ(engine.onPose(poseMessage(5, pose_t::STATE_TRACKING, T), &why).num_boxes, 2);
  const std::vector<proposals_t> late = engine.takeLateProposals();
  ASSERT_EQ(late.size(), 1u) << "seq 0 only: seq 1's keyframe was culled, seq 3 had its boxes";
  EXPECT_EQ(late[0].seq, 0);
  EXPECT_EQ(late[0].utime, 0);
  EXPECT_EQ(late[0].map_id, 1);
  // The boxes a tracked pose at the keyframe's latest pose gives.
  const proposals_t there = engine.onPose(poseMessage(6, pose_t::STATE_TRACKING, T0), &why);
  ASSERT_EQ(late[0].num_boxes, 2);
  ASSERT_EQ(there.num_boxes, 2);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(late[0].candidate_ids[i], there.candidate_ids[i]);
    EXPECT_FLOAT_EQ(late[0].boxes[i].x, there.boxes[i].x);
    EXPECT_FLOAT_EQ(late[0].boxes[i].w, there.boxes[i].w);
  }
  const proposals_t at_T = engine.onPose(poseMessage(7, pose_t::STATE_TRACKING, T), &why);
  EXPECT_NE(late[0].boxes[0].x, at_T.boxes[0].x)
      << "the keyframe's moved pose is used, not its first one";
  EXPECT_TRUE(engine.takeLateProposals().empty()) << "once only";
  // Bundle adjustment moves the keyframe again: it has had its proposals.
  engine.onKeyframe(keyframe(0, T));
  for (int seq = 8; seq < 30; ++seq) {
    engine.onPose(poseMessage(seq, pose_t::STATE_TRACKING, T), &why);
    EXPECT_TRUE(engine.takeLateProposals().empty()) << "seq " << seq << ": once only";
  }

  // Off (< 0): never.
  o.late_keyframe_delay_s = -1;
  ProposalEngine off(o);
  ASSERT_TRUE(off.onCameraInfo(vgaInfo(), &why)) << why;
  off.onPose(poseMessage(0, pose_t::STATE_INITIALIZING, T), &why);
  ASSERT_TRUE(off.onMap(cloudMessage(1, scene), &why)) << why;
  off.onKeyframe(keyframe(0, T0));
  for (int seq = 1; seq < 30; ++seq) {
    off.onPose(poseMessage(seq, pose_t::STATE_TRACKING, T), &why);
    EXPECT_TRUE(off.takeLateProposals().empty());
  }
}

// A growing map is clustered again at most every recluster_interval_s of frame time (poses are
// 1 ms apart here); the first points of a map at once.
TEST(ProposalEngineInput, AGrowingMapIsReclusteredAtMostOncePerInterval) {
  ProposalOptions o = metricOptions();
  o.recluster_interval_s = 0.01;
  ProposalEngine engine(o);
  const SE3 T = lookingDown(1.0);
  const auto one = join(table(0.8f, 0.004f), cylinder(-0.1f, 0, 0.04f, 0.12f, 0.004f));
  // The second object adds less than recluster_growth times the points: the interval decides.
  const auto two = join(one, cylinder(0.15f, 0.05f, 0.04f, 0.12f, 0.004f));
  auto step = [&](int seq) { return trackedPose(engine, seq, T); };
  startWith(engine, one, T, 1);
  std::string why;
  bool ran = false;
  int boxes = 0;
  ASSERT_TRUE(engine.onMap(cloudMessage(1, two), &why));
  for (int seq = 1; seq < 10; ++seq) {
    std::tie(ran, boxes) = step(seq);
    EXPECT_FALSE(ran) << "seq " << seq << ": within 10 ms of the last clustering";
    EXPECT_EQ(boxes, 1) << "seq " << seq << ": the last candidates are projected meanwhile";
  }
  std::tie(ran, boxes) = step(10);
  EXPECT_TRUE(ran);
  EXPECT_EQ(boxes, 2) << "the second object appears once the interval has passed";
  std::tie(ran, boxes) = step(30);
  EXPECT_FALSE(ran) << "no change, no clustering";
}

// A young map grows many times over between two intervals: once it holds recluster_growth times
// the points of its last clustering it is clustered at once; smaller growth waits for the interval.
TEST(ProposalEngineInput, AMapThatGrewByTheGrowthFactorIsReclusteredBeforeTheInterval) {
  const SE3 T = lookingDown(1.0);
  const auto young = join(table(0.8f, 0.008f), cylinder(-0.1f, 0, 0.04f, 0.12f, 0.004f));
  const auto grown = join(join(table(0.8f, 0.004f), cylinder(-0.1f, 0, 0.04f, 0.12f, 0.004f)),
                          cylinder(0.15f, 0.05f, 0.04f, 0.12f, 0.004f));
  const auto more = join(grown, cylinder(-0.15f, -0.15f, 0.04f, 0.12f, 0.004f));
  ASSERT_GT(grown.size(), 2 * young.size());
  ASSERT_LT(more.size(), 1.5 * grown.size());
  for (const double growth : {1.5, 0.0}) {
    ProposalOptions o = metricOptions();
    o.recluster_interval_s = 10;
    o.recluster_growth = growth;
    ProposalEngine engine(o);
    auto step = [&](int seq) { return trackedPose(engine, seq, T); };
    startWith(engine, young, T, 1);
    std::string why;
    bool ran = false;
    int boxes = 0;
    ASSERT_TRUE(engine.onMap(cloudMessage(1, grown), &why));
    std::tie(ran, boxes) = step(1);
    if (growth > 1) {
      EXPECT_TRUE(ran) << "the map more than doubled: clustered without waiting for the interval";
      EXPECT_EQ(boxes, 2);
      ASSERT_TRUE(engine.onMap(cloudMessage(1, more), &why));
      std::tie(ran, boxes) = step(2);
      EXPECT_FALSE(ran) << "grown by less than the factor: waits for the interval";
      EXPECT_EQ(boxes, 2) << "the last candidates are projected meanwhile";
    } else {
      EXPECT_FALSE(ran) << "growth off: only the interval counts";
      EXPECT_EQ(boxes, 1);
    }
  }
}

// Real time: clustering runs on a worker thread; the frames go on meanwhile (with the last
// candidates: none at first) and the finished clustering gives the boxes clustering at once gives.
TEST(ProposalEngineInput, BackgroundClusteringGivesTheSameBoxesWithoutHoldingFrames) {
  ProposalOptions o = metricOptions();
  o.recluster_interval_s = 0;
  ProposalEngine now(o), background(o, /*background_clustering=*/true);
  std::string why;
  const SE3 T = lookingDown(1.0);
  const auto scene = join(table(0.8f, 0.004f), join(cylinder(-0.1f, 0, 0.04f, 0.12f, 0.004f),
                                                    cylinder(0.15f, 0.05f, 0.04f, 0.12f, 0.004f)));
  for (ProposalEngine* e : {&now, &background}) {
    ASSERT_TRUE(e->onCameraInfo(vgaInfo(), &why)) << why;
    ASSERT_TRUE(e->onMap(cloudMessage(1, scene), &why)) << why;
  }
  const proposals_t expected = now.onPose(poseMessage(0, pose_t::STATE_TRACKING, T), &why);
  ASSERT_EQ(expected.num_boxes, 2);
  bool taken = false;
  proposals_t m = background.onPose(poseMessage(0, pose_t::STATE_TRACKING, T), &why, &taken);
  EXPECT_FALSE(taken);
  EXPECT_EQ(m.num_boxes, 0) << "the first frame does not wait for the clustering";
  for (int seq = 1; seq < 2000 && !taken; ++seq) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    m = background.onPose(poseMessage(seq, pose_t::STATE_TRACKING, T), &why, &taken);
  }
  ASSERT_TRUE(taken) << "the clustering never finished";
  ASSERT_EQ(m.num_boxes, expected.num_boxes);
  for (int i = 0; i < m.num_boxes; ++i) {
    EXPECT_EQ(m.candidate_ids[i], expected.candidate_ids[i]);
    EXPECT_FLOAT_EQ(m.boxes[i].x, expected.boxes[i].x);
    EXPECT_FLOAT_EQ(m.boxes[i].w, expected.boxes[i].w);
  }
  // A new map id while nothing runs: its clustering is taken for it, the old map's is not lost.
  ASSERT_TRUE(background.onMap(cloudMessage(2, scene), &why)) << why;
  taken = false;
  for (int seq = 2000; seq < 4000 && !taken; ++seq) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    m = background.onPose(poseMessage(seq, pose_t::STATE_TRACKING, T, 2), &why, &taken);
  }
  ASSERT_TRUE(taken);
  EXPECT_EQ(m.num_boxes, 2);
  EXPECT_EQ(m.map_id, 2);
}

TEST(ShippedConfig, ProposalsYamlEqualsDefaults) {
  ProposalOptions file =
      loadConfig<ProposalOptions>(test::sourcePath("config/proposals.yaml"), "proposals", false);
  ProposalOptions defaults;
  EXPECT_TRUE(optionsEqual(file, defaults)) << describeOptions(optionListOf(file));
  EXPECT_EQ(test::readTextFile(test::sourcePath("config/proposals.yaml")),
            defaultConfigFileText<ProposalOptions>("proposals"))
      << "config/proposals.yaml is generated from the built-in defaults: make configs";
}
