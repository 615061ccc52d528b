// The proposals' map filters without the bus: density clustering against bridging noise, the
// priors the views give (up, look-at), the support chosen among the planes of a room, free-space
// carving, the multi-keyframe agreement, and candidates kept per SLAM map.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <random>

#include "procs/proposals/candidate_map.h"
#include "procs/proposals/density_clustering.h"
#include "procs/proposals/free_space.h"
#include "procs/proposals/proposal_engine.h"
#include "procs/proposals/scene_structure.h"
#include "procs/proposals/synthetic_map.h"

using namespace slamaware;
using namespace slamaware::proposals;
using namespace slamaware::synthmap;

namespace {

ProposalOptions metricOptions() {
  ProposalOptions o;
  o.relative_lengths = false;  // the tests place things in map units (metres)
  return o;
}

View viewOf(const SE3& T_world_camera) {
  const Eigen::Matrix3f R = T_world_camera.linear().cast<float>();
  return {T_world_camera.translation().cast<float>(), R.col(2), R.col(0), -R.col(1)};
}

// Cameras on a circle of `radius` at `height`, every `step_deg` over `arc_deg`, looking at
// `target`.
std::vector<SE3> circle(double radius, double height, double arc_deg, double step_deg,
                        const Eigen::Vector3d& target) {
  std::vector<SE3> out;
  for (double a = 0; a <= arc_deg + 1e-9; a += step_deg) {
    const double r = a * M_PI / 180;
    out.push_back(
        lookAt(Eigen::Vector3d(radius * std::cos(r), radius * std::sin(r), height), target));
  }
  return out;
}

// A regular grid of points on the rectangle [x0, x1] x [y0, y1] at height z.
std::vector<MapPoint> horizontalPatch(float x0, float x1, float y0, float y1, float z, float step) {
  std::vector<MapPoint> out;
  for (float x = x0; x <= x1; x += step)
    for (float y = y0; y <= y1; y += step) out.push_back({Eigen::Vector3f(x, y, z), 100, 100, 100});
  return out;
}

}  // namespace

// DBSCAN: a sparse line of stray depths between two objects (each point closer than the radius to
// the next) does not join them, because none of its points has enough neighbours to be a core
// point; single linkage (one neighbour is enough) joins them through it.
TEST(DensityClustering, StrayPointsBetweenObjectsDoNotBridgeThem) {
  std::vector<Eigen::Vector3f> points;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-0.02f, 0.02f);
  for (float cx : {-0.1f, 0.1f})
    for (int i = 0; i < 400; ++i) points.emplace_back(cx + u(rng), u(rng), u(rng));
  for (float x = -0.1f; x <= 0.1f; x += 0.006f)
    points.emplace_back(x, 0, 0);  // the bridge, into both
  // Whether some cluster holds points of both objects.
  auto joined = [&](const std::vector<int>& label, int count) {
    std::vector<std::array<bool, 2>> sides(static_cast<size_t>(count), {false, false});
    for (size_t i = 0; i < 800; ++i)
      if (label[i] >= 0) sides[static_cast<size_t>(label[i])][i / 400] = true;
    for (const auto& s : sides)
      if (s[0] && s[1]) return true;
    return false;
  };
  DensityClusterOptions o;
  o.radius = 0.008f;
  o.min_neighbours = 4;
  int count = 0;
  std::vector<int> label = densityClusters(points, {}, o, &count);
  EXPECT_FALSE(joined(label, count)) << "the stray points joined the two objects";
  int clustered = 0;
  for (size_t i = 0; i < 800; ++i) clustered += label[i] >= 0;
  EXPECT_GT(clustered, 760) << "the objects themselves are not clustered";
  o.min_neighbours = 1;
  label = densityClusters(points, {}, o, &count);
  EXPECT_TRUE(joined(label, count)) << "single linkage should chain through the bridge";
}

// The grid version against DBSCAN by its definition, every pair of points compared: the same
// core points, the same clusters numbered by their lowest point, border points in the cluster of
// their nearest core point; with and without colour, on blobs, a sparse haze between them and
// points exactly on cell boundaries.
TEST(DensityClustering, EqualsDbscanByDefinition) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1, 1), c(0, 255);
  std::vector<Eigen::Vector3f> points, colours;
  for (int blob = 0; blob < 6; ++blob) {
    const Eigen::Vector3f centre(0.08f * blob, 0.03f * (blob % 2), 0);
    const Eigen::Vector3f colour(c(rng), c(rng), c(rng));
    for (int i = 0; i < 250; ++i) {
      points.push_back(centre + 0.025f * Eigen::Vector3f(u(rng), u(rng), u(rng)));
      colours.push_back(colour + Eigen::Vector3f::Constant(20 * u(rng)));
    }
  }
  for (int i = 0; i < 300; ++i) {
    points.emplace_back(0.25f + 0.3f * u(rng), 0.1f * u(rng), 0.05f * u(rng));
    colours.emplace_back(c(rng), c(rng), c(rng));
  }
  for (int i = 0; i < 40; ++i) {  // on multiples of the radius
    points.emplace_back(0.008f * (i % 7), 0.008f * (i % 3), 0);
    colours.emplace_back(100, 100, 100);
  }
  for (const float colour_distance : {0.f, 40.f}) {
    DensityClusterOptions o;
    o.radius = 0.008f;
    o.min_neighbours = 4;
    o.colour_distance = colour_distance;
    int count = 0;
    const std::vector<int> label = densityClusters(points, colours, o, &count);

    const size_t n = points.size();
    const float r2 = o.radius * o.radius, c2 = colour_distance * colour_distance;
    std::vector<char> core(n);
    for (size_t i = 0; i < n; ++i) {
      int near = 0;
      for (size_t j = 0; j < n; ++j) near += (points[j] - points[i]).squaredNorm() <= r2;
      core[i] = near >= o.min_neighbours;
    }
    std::vector<int> expected(n, -1);
    int expected_count = 0;
    for (size_t seed = 0; seed < n; ++seed) {  // flood fill over linked core points
      if (!core[seed] || expected[seed] >= 0) continue;
      std::vector<size_t> stack{seed};
      expected[seed] = expected_count;
      while (!stack.empty()) {
        const size_t i = stack.back();
        stack.pop_back();
        for (size_t j = 0; j < n; ++j)
          if (core[j] && expected[j] < 0 && (points[j] - points[i]).squaredNorm() <= r2 &&
              (colour_distance <= 0 || (colours[j] - colours[i]).squaredNorm() < c2)) {
            expected[j] = expected_count;
            stack.push_back(j);
          }
      }
      ++expected_count;
    }
    for (size_t i = 0; i < n; ++i) {
      if (core[i]) continue;
      float best = std::numeric_limits<float>::infinity();
      for (size_t j = 0; j < n; ++j) {
        const float d = (points[j] - points[i]).squaredNorm();
        if (core[j] && d <= r2 && (d < best || (d == best && expected[j] < expected[i]))) {
          best = d;
          expected[i] = expected[j];
        }
      }
    }
    EXPECT_EQ(count, expected_count) << "colour distance " << colour_distance;
    EXPECT_EQ(label, expected) << "colour distance " << colour_distance;
    EXPECT_GT(expected_count, 3) << "the cloud should hold several clusters";
  }
}

// With little roll, the cameras' x axes are horizontal: up is perpendicular to all of them even
// when every camera looks steeply down (where the image's own up is nearly horizontal), and the
// optical axes of cameras circling a point meet at it.
TEST(ViewPriors, UpAndLookAtFromCamerasCirclingATable) {
  const Eigen::Vector3d table_centre(0.1, -0.05, 0.74);
  std::vector<View> views;
  for (const SE3& T : circle(0.6, 1.6, 150, 10, table_centre))
    views.push_back(viewOf(T));  // ~55 deg down
  const ViewPriors p = viewPriors(views);
  ASSERT_TRUE(p.up_known);
  EXPECT_GT(p.up.dot(Eigen::Vector3f::UnitZ()), std::cos(1.0 * M_PI / 180));
  ASSERT_TRUE(p.has_look_at);
  EXPECT_LT((p.look_at - table_centre.cast<float>()).norm(), 0.01f);
  // One camera alone: up unknown, no look-at.
  const ViewPriors one = viewPriors({views.front()});
  EXPECT_FALSE(one.up_known);
  EXPECT_FALSE(one.has_look_at);
}

// A room: a large floor (more points than anything), a wall, and a table with an object on it,
// seen by cameras circling the table. The support is the table (what the views look at), not the
// floor; the wall and the table top are removed; the object stays, and is over the support.
TEST(SceneStructure, TheSupportIsThePlaneTheViewsLookAt) {
  const ProposalOptions o = metricOptions();
  const auto floor = horizontalPatch(-1.5f, 1.5f, -1.5f, 1.5f, 0, 0.01f);  // 90k points
  std::vector<MapPoint> wall;
  for (float y = -1.5f; y <= 1.5f; y += 0.01f)
    for (float z = 0; z <= 1.5f; z += 0.01f)
      wall.push_back({Eigen::Vector3f(2.1f, y, z), 90, 90, 90});
  const auto table = horizontalPatch(-0.6f, 0.6f, -0.4f, 0.4f, 0.74f, 0.01f);  // 9.7k points
  auto object = cylinder(0.1f, 0.05f, 0.04f, 0.12f, 0.004f);
  for (auto& m : object) m.p.z() += 0.74f;
  const auto points = join(join(floor, wall), join(table, object));
  std::vector<View> views;
  for (const SE3& T : circle(1.0, 1.3, 300, 10, Eigen::Vector3d(0, 0, 0.74)))
    views.push_back(viewOf(T));
  const StructureResult r = removeStructure(points, views, viewPriors(views), o);
  const Support& support = r.support;
  const std::vector<MapPoint>& rest = r.kept;
  ASSERT_TRUE(r.has_support);
  EXPECT_GT(support.plane.n.dot(Eigen::Vector3f::UnitZ()), 0.999f);
  EXPECT_NEAR(-support.plane.d, 0.74f, 0.005f) << "the support is not the table top";
  EXPECT_TRUE(support.over(Eigen::Vector3f(0.1f, 0.05f, 0.8f), 0.0f));
  EXPECT_FALSE(support.over(Eigen::Vector3f(1.5f, 1.5f, 0.8f), 0.05f))
      << "the support region spills over the floor";
  size_t on_wall = 0, on_table = 0, of_object = 0;
  for (const auto& m : rest) {
    on_wall += m.p.x() > 2.05f;
    on_table += std::abs(m.p.z() - 0.74f) < 0.002f &&
                (m.p.head<2>() - Eigen::Vector2f(0.1f, 0.05f)).norm() > 0.05f;
    of_object += m.p.z() > 0.75f && (m.p.head<2>() - Eigen::Vector2f(0.1f, 0.05f)).norm() < 0.05f;
  }
  EXPECT_LT(on_wall, wall.size() / 20);
  EXPECT_LT(on_table, table.size() / 100);
  EXPECT_GT(of_object, object.size() * 8 / 10);
}

// A young map: a plain table holds about one point per structure cell (scattered, as a depth filter
// converges them), and the few views so far have moved too little for up or a look-at point. The
// table is still the support (the plane the optical axes hit), removed around the object standing
// on it; with cells that must hold three points each, as the default once was, it is no structure.
TEST(SceneStructure, ASparseTableOfAYoungMapIsTheSupport) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> ux(-0.6f, 0.6f), uy(-0.4f, 0.4f), noise(-0.002f, 0.002f);
  std::vector<MapPoint> table;
  const ProposalOptions o = metricOptions();
  const int points =
      static_cast<int>(1.2 * 0.8 / (o.structure_cell * o.structure_cell));  // one per cell
  for (int i = 0; i < points; ++i)
    table.push_back({Eigen::Vector3f(ux(rng), uy(rng), 0.74f + noise(rng)), 90, 90, 90});
  auto object = cylinder(0.1f, 0.05f, 0.04f, 0.12f, 0.004f);
  for (auto& m : object) m.p.z() += 0.74f;
  const auto all = join(table, object);
  std::vector<View> views;
  for (const SE3& T : circle(1.0, 1.3, 4, 1, Eigen::Vector3d(0, 0, 0.74)))
    views.push_back(viewOf(T));
  const ViewPriors priors = viewPriors(views);
  ASSERT_FALSE(priors.up_known);
  ASSERT_FALSE(priors.has_look_at);

  auto run = [&](const ProposalOptions& options, bool* has_support) {
    const StructureResult r = removeStructure(all, views, priors, options);
    const Support& support = r.support;
    const std::vector<MapPoint>& rest = r.kept;
    *has_support = r.has_support;
    if (*has_support) {
      EXPECT_NEAR(-support.plane.d / support.plane.n.z(), 0.74f, 0.005f)
          << "the support is not the table top";
    }
    size_t on_table = 0, of_object = 0;
    for (const auto& m : rest) {
      on_table += std::abs(m.p.z() - 0.74f) < 0.003f &&
                  (m.p.head<2>() - Eigen::Vector2f(0.1f, 0.05f)).norm() > 0.05f;
      of_object += m.p.z() > 0.75f;
    }
    EXPECT_GT(of_object, object.size() * 8 / 10);
    return on_table;
  };
  bool has_support = false;
  EXPECT_LT(run(o, &has_support), table.size() / 20);
  EXPECT_TRUE(has_support);
  ProposalOptions dense = o;
  dense.structure_min_points = 3;
  EXPECT_GT(run(dense, &has_support), table.size() / 2);
  EXPECT_FALSE(has_support);
}

// Keyframes in front of a wall see it through the space before it: a point floating there (a
// wrong depth) is carved away, the wall's own points are not.
TEST(FreeSpace, PointsThatKeyframesSawThroughAreRemoved) {
  std::map<int32_t, std::vector<MapPoint>> by_keyframe;
  std::map<int32_t, Eigen::Vector3f> centres;
  std::vector<View> views;
  const auto wall = [] {
    std::vector<MapPoint> w;
    for (float x = -0.5f; x <= 0.5f; x += 0.005f)
      for (float y = -0.4f; y <= 0.4f; y += 0.005f)
        w.push_back({Eigen::Vector3f(x, y, 0), 1, 1, 1});
    return w;
  }();
  for (int k = 0; k < 6; ++k) {
    const Eigen::Vector3d eye(-0.3 + 0.12 * k, 0.05 * (k % 2), 1.0);
    const SE3 T = lookAt(eye, Eigen::Vector3d(0, 0, 0));
    views.push_back(viewOf(T));
    centres[k] = eye.cast<float>();
    by_keyframe[k] = wall;  // every keyframe seeded the wall
  }
  std::vector<MapPoint> test = {
      {Eigen::Vector3f(0.02f, 0.01f, 0.3f), 1, 1, 1},    // floating
      {Eigen::Vector3f(-0.1f, 0.05f, 0.6f), 1, 1, 1},    // floating
      {Eigen::Vector3f(0.01f, 0.02f, 0.0f), 1, 1, 1},    // on the wall
      {Eigen::Vector3f(0.2f, -0.1f, 0.002f), 1, 1, 1}};  // on the wall (noise)
  FreeSpaceOptions o;
  int64_t removed = 0;
  const auto kept = removeSeenThrough(test, by_keyframe, centres, views, o, &removed);
  EXPECT_EQ(removed, 2);
  ASSERT_EQ(kept.size(), 2u);
  for (const auto& m : kept) EXPECT_LT(std::abs(m.p.z()), 0.01f);
}

// A cluster of points that only one keyframe seeded (a wrong depth it alone made) is not an
// object once the map has enough keyframes; the same points seeded by several keyframes are.
TEST(CandidateMapFilters, PointsOnlyOneKeyframeSeededAreNoObject) {
  const ProposalOptions o = metricOptions();
  const auto tab = table(0.8f, 0.004f);
  const auto a = cylinder(-0.15f, 0, 0.04f, 0.1f, 0.004f);
  const auto ghost = cylinder(0.15f, 0.1f, 0.03f, 0.08f, 0.004f);
  CandidateMap map(o);
  for (int k = 0; k < 10; ++k)
    map.update(1, false, k, {}, join(tab, a));  // table and a: every keyframe
  map.update(1, false, 10, {}, ghost);          // only keyframe 10
  map.addView(1, lookingDown(1.0));
  ASSERT_TRUE(map.recluster());
  EXPECT_GT(map.stats().single_view, static_cast<int64_t>(ghost.size() / 2));
  for (const auto& c : map.candidates())
    EXPECT_LT(c.centroid.x(), 0.0f) << "a candidate where only one keyframe saw something";
  EXPECT_FALSE(map.candidates().empty());
}

// SLAM may relocalise into an older map: the candidates of that map are still there.
TEST(ProposalEngineMaps, CandidatesOfAnOlderMapAreKept) {
  ProposalOptions o = metricOptions();
  ProposalEngine engine(o);
  std::string why;
  ASSERT_TRUE(engine.onCameraInfo(vgaInfo(), &why)) << why;
  const auto scene = join(table(0.8f, 0.004f), cylinder(0, 0, 0.05f, 0.12f, 0.004f));
  const SE3 T = lookingDown(1.0);
  ASSERT_TRUE(engine.onMap(cloudMessage(1, scene), &why));
  const proposals_t first = engine.onPose(poseMessage(0, pose_t::STATE_TRACKING, T, 1), &why);
  ASSERT_GE(first.num_boxes, 1);
  ASSERT_TRUE(engine.onMap(cloudMessage(2, scene), &why));  // SLAM starts map 2 ...
  const proposals_t other = engine.onPose(poseMessage(1, pose_t::STATE_TRACKING, T, 2), &why);
  ASSERT_GE(other.num_boxes, 1);
  // ... and relocalises into map 1: its candidates (same ids) are proposed again.
  const proposals_t back = engine.onPose(poseMessage(2, pose_t::STATE_RELOCALIZED, T, 1), &why);
  ASSERT_EQ(back.num_boxes, first.num_boxes);
  EXPECT_EQ(back.candidate_ids, first.candidate_ids);
  for (int32_t id : other.candidate_ids)
    for (int32_t id1 : first.candidate_ids)
      EXPECT_NE(id, id1) << "candidate ids are not unique across maps";
}
