// Depth filter: the Gaussian x Beta update converges to the true inverse depth and tells
// outlier-dominated seeds apart; one epipolar search finds most seeds of a textured plane and
// never a match beyond the frame; the whole filter (seeding, epipolar search, updates) recovers
// the depth of a textured plane seen from a moving camera.
#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <random>

#include "procs/slam/depth/depth_filter.h"
#include "procs/slam/depth/epipolar_search.h"
#include "procs/slam/depth/seed.h"
#include "tests/slam/synthetic_scene.h"

using namespace slamaware;
using namespace slamaware::slam;

namespace {

// A texture with detail at several scales (a plane painted with it has gradients everywhere).
cv::Mat makeTexture(int size, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat acc(size, size, CV_32F, cv::Scalar(0));
  for (int scale : {4, 16, 64}) {
    cv::Mat small(size / scale, size / scale, CV_32F);
    rng.fill(small, cv::RNG::UNIFORM, 0, 255);
    cv::Mat big;
    cv::resize(small, big, acc.size(), 0, 0, cv::INTER_CUBIC);
    acc += big / 3;
  }
  cv::Mat out;
  acc.convertTo(out, CV_8U);
  return out;
}

// The view of the plane Z_world = plane_z (texture on it, 1 texel = texel_m metres, centred) by a
// camera with pose T_world_camera.
cv::Mat renderPlane(const cv::Mat& texture, double texel_m, double plane_z,
                    const SE3& T_world_camera, const test::PinholeCamera& cam) {
  cv::Mat map_x(cam.height, cam.width, CV_32F), map_y(cam.height, cam.width, CV_32F);
  const Eigen::Vector3d c = T_world_camera.translation();
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector3d d = T_world_camera.linear() *
                                Eigen::Vector3d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1);
      const double s = (plane_z - c.z()) / d.z();
      const Eigen::Vector3d X = c + s * d;
      map_x.at<float>(v, u) = static_cast<float>(X.x() / texel_m + texture.cols / 2.0);
      map_y.at<float>(v, u) = static_cast<float>(X.y() / texel_m + texture.rows / 2.0);
    }
  }
  cv::Mat out;
  cv::remap(texture, out, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REFLECT);
  return out;
}

constexpr double kPlaneZ = 2.0, kTexel = 0.0015;  // the plane of the tests, metres

// A new keyframe of map 1 with the image `grey` taken at T_world_camera.
DepthKeyframeInput makeKeyframe(int64_t id, const cv::Mat& grey, const SE3& T_world_camera) {
  DepthKeyframeInput kf;
  kf.id = id;
  kf.map_id = 1;
  kf.grey = grey;
  cv::cvtColor(grey, kf.bgr, cv::COLOR_GRAY2BGR);
  kf.T_world_camera = T_world_camera;
  kf.min_depth = 1.0;  // what the sparse map would say, roughly
  kf.mean_depth = 2.6;
  return kf;
}

}  // namespace

TEST(DepthSeedUpdate, ConvergesToTheTrueInverseDepthDespiteOutliers) {
  // Prior: depth between 0.5 and "infinity", mean 2; truth 1.25 (inverse depth 0.8).
  DepthSeed seed = makeSeed(0, 0, Eigen::Vector3f::UnitZ(), 2.0f, 0.5f);
  const float truth = 0.8f, tau = 0.02f;
  std::mt19937_64 rng(5);
  std::normal_distribution<float> inlier(truth, tau);
  std::uniform_real_distribution<float> outlier(0.f, seed.z_range), u01(0, 1);
  for (int i = 0; i < 60; ++i)
    updateSeed(&seed, u01(rng) < 0.3f ? outlier(rng) : inlier(rng), tau * tau);
  EXPECT_NEAR(seed.mu, truth, 3 * tau / std::sqrt(40.f));
  EXPECT_LT(std::sqrt(seed.sigma2), 0.01f);
  // The Beta posterior has learnt the inlier ratio (0.7) roughly.
  EXPECT_GT(seed.inlierRatio(), 0.5f);
  EXPECT_LT(seed.inlierRatio(), 0.9f);
}

TEST(DepthSeedUpdate, ASeedFedOnlyOutliersIsRecognised) {
  DepthSeed seed = makeSeed(0, 0, Eigen::Vector3f::UnitZ(), 2.0f, 0.5f);
  std::mt19937_64 rng(6);
  std::uniform_real_distribution<float> outlier(0.f, seed.z_range);
  for (int i = 0; i < 100; ++i) updateSeed(&seed, outlier(rng), 0.02f * 0.02f);
  // Dropped by the filter (inlier ratio under its threshold), and never converged.
  EXPECT_LT(seed.inlierRatio(), DepthFilterOptions().min_inlier_ratio);
  EXPECT_GT(std::sqrt(seed.sigma2), seed.z_range / DepthFilterOptions().convergence_ratio);
}

TEST(DepthSeedUpdate, DepthUncertaintyGrowsWithDistanceAndShrinksWithBaseline) {
  const Eigen::Vector3d f = Eigen::Vector3d(0.1, 0, 1).normalized();
  const double angle = 2 * std::atan(0.5 / 500.0);
  const double near = depthUncertainty(Eigen::Vector3d(0.1, 0, 0), f, 1.0, angle);
  const double far = depthUncertainty(Eigen::Vector3d(0.1, 0, 0), f, 3.0, angle);
  const double wide = depthUncertainty(Eigen::Vector3d(0.3, 0, 0), f, 3.0, angle);
  EXPECT_GT(near, 0);
  EXPECT_GT(far, near);
  EXPECT_LT(wide, far);
  // Stereo rule of thumb: sigma_z ~ z^2 / (f b) x the angle's error in pixels (here one).
  EXPECT_NEAR(far, 9.0 / (500 * 0.1), 0.3 * 9.0 / (500 * 0.1));
}

// One search per seed of a grid over the plane, the frame 0.1 m to the side (25 px of disparity).
// A single search is often wrong (the filter's outlier model is there for that), but most seeds
// whose match is in the frame are found there; and no match, right or wrong, rests on a sample
// beyond the frame's edge, also for seeds whose true match is beyond it.
TEST(EpipolarSearch, FindsMostSeedsAtThePlanesDistanceAndNoMatchBeyondTheFrame) {
  const test::PinholeCamera cam;
  const cv::Mat texture = makeTexture(2048, 5);
  const cv::Mat host = renderPlane(texture, kTexel, kPlaneZ, SE3::Identity(), cam);
  SE3 T = SE3::Identity();
  T.translation() = Eigen::Vector3d(0.1, 0, 0);
  const cv::Mat frame = renderPlane(texture, kTexel, kPlaneZ, T, cam);
  EpipolarSearchParams p;
  p.fx = static_cast<float>(cam.fx), p.fy = static_cast<float>(cam.fy);
  p.cx = static_cast<float>(cam.cx), p.cy = static_cast<float>(cam.cy);
  const Eigen::Matrix3f R = Eigen::Matrix3f::Identity();
  const Eigen::Vector3f t(-0.1f, 0, 0);  // host camera -> frame camera
  const double disparity = cam.fx * 0.1 / kPlaneZ;
  int inside = 0, found = 0, right = 0, beyond = 0, off_frame = 0;
  for (int v = 20; v < cam.height - 20; v += 23)
    for (int u = 3; u < cam.width - 3; u += 5) {
      const Eigen::Vector3f f =
          Eigen::Vector3f((u - p.cx) / p.fx, (v - p.cy) / p.fy, 1.f).normalized();
      const DepthSeed seed = makeSeed(static_cast<float>(u), static_cast<float>(v), f, 2.6f, 1.f);
      const EpipolarMatch m = searchEpipolar(host, frame, R, t, seed, p);
      // Two samples each side, one pixel apart; sub-pixel refinement moves half a pixel at most.
      if (m.result == EpipolarMatch::kFound && (m.px.x() < 1.5f || m.px.x() > cam.width - 2.5f))
        ++off_frame;
      const double u_frame = u - disparity;  // where the seed is in the frame
      if (u_frame < 3) {
        ++beyond;
        continue;
      }
      ++inside;
      if (m.result != EpipolarMatch::kFound) continue;
      ++found;
      const double truth = kPlaneZ / f.z();
      right += std::abs(m.distance - truth) < 0.02 * truth && std::abs(m.px.x() - u_frame) < 0.5 &&
               std::abs(m.px.y() - v) < 0.5;
    }
  ASSERT_GT(beyond, 50);
  EXPECT_EQ(off_frame, 0) << "matches resting on samples beyond the frame";
  EXPECT_GT(found, 0.8 * inside) << found << " of " << inside << " found";
  EXPECT_GT(right, 0.85 * found) << right << " of " << found << " found at the plane";
}

TEST(DepthFilter, RecoversThePlaneDepthFromAMovingCamera) {
  const test::PinholeCamera cam;
  const cv::Mat texture = makeTexture(2048, 3);
  const double plane_z = kPlaneZ;
  DepthFilterOptions options;
  options.max_keyframes = 100;  // keep the one keyframe's seeds alive through the sequence
  DepthFilter filter(options, cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy);

  DepthFrameInput first;
  first.map_id = 1;
  first.located = true;
  const DepthKeyframeInput kf =
      makeKeyframe(7, renderPlane(texture, kTexel, plane_z, SE3::Identity(), cam), SE3::Identity());
  first.grey = kf.grey;
  first.new_keyframes.push_back(kf);
  filter.process(first);
  const int64_t seeds = filter.stats().active_seeds;
  ASSERT_GT(seeds, 3000);

  for (int k = 1; k <= 16; ++k) {
    // Sideways and a little forward, with a slight turn.
    SE3 T = SE3::Identity();
    T.translation() = Eigen::Vector3d(0.02 * k, 0.005 * k, 0.01 * k);
    T.linear() = expSO3(Eigen::Vector3d(0.002 * k, -0.004 * k, 0.001 * k));
    DepthFrameInput f;
    f.map_id = 1;
    f.located = true;
    f.grey = renderPlane(texture, kTexel, plane_z, T, cam);
    f.T_world_camera = T;
    f.keyframe_poses = {{7, SE3::Identity()}};
    filter.process(f);
  }
  const SemiDenseKeyframe result = filter.keyframe(7);
  EXPECT_GT(result.points.size(), 0.5 * seeds)
      << "converged " << result.points.size() << " of " << seeds;
  std::vector<double> rel;
  for (const auto& p : result.points) rel.push_back(std::abs(p.p_camera.z() - plane_z) / plane_z);
  std::sort(rel.begin(), rel.end());
  EXPECT_LT(rel[rel.size() / 2], 0.01);       // median relative error under 1%
  EXPECT_LT(rel[rel.size() * 9 / 10], 0.02);  // 90% under 2%
  for (const auto& p : result.points) EXPECT_GT(p.depth_std, 0);
}

namespace {

// Frame k of a camera sliding sideways over the plane by `step` m per frame. When
// with_keyframe is set, the frame is also a new keyframe (id 7 + k), as at low frame rates.
DepthFrameInput slidingFrame(const cv::Mat& texture, const test::PinholeCamera& cam, int k,
                             double step, bool with_keyframe) {
  SE3 T = SE3::Identity();
  T.translation() = Eigen::Vector3d(step * k, 0, 0);
  DepthFrameInput f;
  f.map_id = 1;
  f.located = true;
  f.grey = renderPlane(texture, kTexel, kPlaneZ, T, cam);
  f.T_world_camera = T;
  if (with_keyframe) f.new_keyframes.push_back(makeKeyframe(7 + k, f.grey, T));
  return f;
}

// Feeds frames 0, 1, ... (frame 0 seeds keyframe 7) until keyframe 7 is finished; returns the
// number of the frame that finished it (-1: never, within 20 frames).
int frameThatFinishesTheFirstKeyframe(DepthFilter& filter, const cv::Mat& texture,
                                      const test::PinholeCamera& cam, double step) {
  for (int k = 0; k < 20; ++k) {
    const std::vector<int64_t> done = filter.process(slidingFrame(texture, cam, k, step, true));
    if (std::find(done.begin(), done.end(), 7) != done.end()) return k;
  }
  return -1;
}

}  // namespace

// At a low frame rate every frame is a keyframe: seeds that lived for max_keyframes newer
// keyframes only would be searched in as few frames; min_frames keeps them for that many
// searches, and more of them converge.
TEST(DepthFilter, SeedsAreSearchedInMinFramesEvenWhenEveryFrameIsAKeyframe) {
  const test::PinholeCamera cam;
  const cv::Mat texture = makeTexture(2048, 5);
  DepthFilterOptions options;
  options.max_keyframes = 3;
  options.min_frames = 3;               // as max_keyframes: the keyframe count alone decides
  options.young_convergence_ratio = 0;  // converged seeds only
  DepthFilter by_keyframes(options, cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy);
  EXPECT_EQ(frameThatFinishesTheFirstKeyframe(by_keyframes, texture, cam, 0.05), 3);
  options.min_frames = 6;
  DepthFilter by_frames(options, cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy);
  EXPECT_EQ(frameThatFinishesTheFirstKeyframe(by_frames, texture, cam, 0.05), 6);
  EXPECT_GE(by_frames.keyframe(7).points.size(), by_keyframes.keyframe(7).points.size());
  EXPECT_GT(by_frames.keyframe(7).points.size(), 1000u);
}

// Frames too close to the keyframe are not searched and do not count; the keyframe still
// finishes once max_keyframes + min_frames newer keyframes exist.
TEST(DepthFilter, SeedsWithoutUsableFramesStillEndAfterMaxKeyframesPlusMinFrames) {
  const test::PinholeCamera cam;
  const cv::Mat texture = makeTexture(2048, 5);
  DepthFilterOptions options;
  options.max_keyframes = 3;
  options.min_frames = 4;
  options.min_baseline_ratio = 1.0;  // no frame has this baseline: nothing is searched
  DepthFilter filter(options, cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy);
  EXPECT_EQ(frameThatFinishesTheFirstKeyframe(filter, texture, cam, 0.05), 7);
  EXPECT_EQ(filter.keyframe(7).points.size(), 0u);
}

// A keyframe that local mapping culls takes its seeds and points with it: one culled while its
// seeds converge stops being searched, one culled after it finished leaves the stored map; the
// others are untouched. (Driving the same path again makes keyframes that are culled again; kept,
// their points would grow the map with every pass.)
TEST(DepthFilter, ACulledKeyframesSeedsAndPointsGo) {
  const test::PinholeCamera cam;
  const cv::Mat texture = makeTexture(2048, 5);
  DepthFilterOptions options;
  options.max_keyframes = 3;
  options.min_frames = 6;
  options.young_convergence_ratio = 0;
  DepthFilter filter(options, cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy);
  ASSERT_EQ(frameThatFinishesTheFirstKeyframe(filter, texture, cam, 0.05), 6);
  // Keyframe 7 finished; 8..13 (seeded by frames 1..6) live.
  ASSERT_GT(filter.keyframe(7).points.size(), 1000u);
  std::vector<int64_t> live_before;
  for (const auto& kf : filter.liveKeyframes(1)) live_before.push_back(kf.id);
  ASSERT_EQ(live_before, (std::vector<int64_t>{8, 9, 10, 11, 12, 13}));
  const int64_t seeds_before = filter.stats().active_seeds;

  DepthFrameInput f = slidingFrame(texture, cam, 7, 0.05, false);
  f.culled_keyframes = {7, 9};
  const std::vector<int64_t> finished = filter.process(f);
  EXPECT_TRUE(std::find(finished.begin(), finished.end(), 9) == finished.end())
      << "a culled keyframe is not finished (nothing is published for it)";
  EXPECT_EQ(filter.keyframe(7).id, -1);
  EXPECT_EQ(filter.keyframe(9).id, -1);
  std::vector<int64_t> stored, live;
  for (const auto& kf : filter.mapKeyframes(1)) stored.push_back(kf.id);
  for (const auto& kf : filter.liveKeyframes(1)) live.push_back(kf.id);
  EXPECT_EQ(stored, (std::vector<int64_t>{8, 10, 11, 12, 13}));
  EXPECT_EQ(live, stored);
  EXPECT_LT(filter.stats().active_seeds, seeds_before);
  // The count of stored points lost the culled ones' points.
  int64_t stored_points = 0;
  for (const auto& kf : filter.mapKeyframes(1))
    stored_points += static_cast<int64_t>(kf.points.size());
  EXPECT_EQ(filter.stats().points, stored_points);
}

// A young map's keyframe takes its map points (triangulated features) as its first points, at
// once: at low frame rates its seeds need several frames to converge, and the map would show
// nothing until then. Once the map's seeds have converged to young_map_points, new keyframes
// start empty again and finished ones keep their converged seeds alone; another map is young
// again; features behind the camera or outside the image are refused.
TEST(DepthFilter, AYoungMapsKeyframesStartFromTheirMapPoints) {
  const test::PinholeCamera cam;
  const cv::Mat texture = makeTexture(2048, 5);
  DepthFilterOptions options;
  options.young_map_points = 1000;
  DepthFilter filter(options, cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy);

  // Map points on the plane seen by keyframe 7 (at the origin), plus two bad ones.
  DepthFrameInput first = slidingFrame(texture, cam, 0, 0.05, true);
  DepthKeyframeInput& kf = first.new_keyframes.front();
  for (int i = 0; i < 40; ++i) {
    const Eigen::Vector2i px(20 + 15 * i, 30 + 10 * i);
    const Eigen::Vector3f p(float((px.x() - cam.cx) / cam.fx * kPlaneZ),
                            float((px.y() - cam.cy) / cam.fy * kPlaneZ), float(kPlaneZ));
    kf.sparse.push_back({px, p});
  }
  kf.sparse.push_back({Eigen::Vector2i(100, 100), Eigen::Vector3f(0, 0, -1)});     // behind
  kf.sparse.push_back({Eigen::Vector2i(cam.width, 5), Eigen::Vector3f(0, 0, 2)});  // outside
  filter.process(first);
  const SemiDenseKeyframe seeded = filter.keyframe(7);
  ASSERT_EQ(seeded.points.size(), 40u);
  EXPECT_EQ(seeded.from_features, 40u);
  const uint8_t grey = kf.grey.at<uint8_t>(30, 20);
  EXPECT_EQ(seeded.points[0].rgb[0], grey);
  EXPECT_NEAR(seeded.points[0].p_camera.z(), kPlaneZ, 1e-6);
  EXPECT_NEAR(seeded.points[0].depth_std,
              options.sparse_depth_std * seeded.points[0].p_camera.norm(), 1e-6);
  const auto live = filter.liveKeyframes(1);
  ASSERT_EQ(live.size(), 1u);
  EXPECT_EQ(live[0].from_features, 40u);

  // The seeds converge (thousands of points on the plane): the map is no longer young.
  for (int k = 1; k <= 8; ++k) filter.process(slidingFrame(texture, cam, k, 0.05, false));
  const size_t with_features = filter.keyframe(7).points.size();
  ASSERT_GE(with_features, 1040u);
  EXPECT_EQ(filter.keyframe(7).from_features, 40u);
  DepthFrameInput later = slidingFrame(texture, cam, 9, 0.05, true);
  later.new_keyframes.front().sparse = kf.sparse;
  filter.process(later);
  EXPECT_EQ(filter.keyframe(16).points.size(), 0u);
  EXPECT_EQ(filter.keyframe(16).from_features, 0u);

  // A new map is young.
  DepthFrameInput other = slidingFrame(texture, cam, 10, 0.05, true);
  other.map_id = 2;
  other.new_keyframes.front().map_id = 2;
  other.new_keyframes.front().sparse = kf.sparse;
  const size_t before = filter.keyframe(7).points.size(),
               provisional = filter.keyframe(7).provisional;
  filter.process(other);
  EXPECT_EQ(filter.keyframe(17).points.size(), 40u);
  // Map 1's keyframes are finished by the new map: keyframe 7 keeps only its converged seeds
  // (its map points and provisional seeds were stand-ins), keyframe 16 (no converged seed, no
  // map points) nothing.
  EXPECT_TRUE(filter.keyframe(7).finished);
  EXPECT_EQ(filter.keyframe(7).from_features, 0u);
  EXPECT_EQ(filter.keyframe(7).provisional, 0u);
  EXPECT_EQ(filter.keyframe(7).points.size(), before - 40 - provisional);

  // Off.
  options.young_map_points = 0;
  DepthFilter off(options, cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy);
  DepthFrameInput again = slidingFrame(texture, cam, 0, 0.05, true);
  again.new_keyframes.front().sparse = kf.sparse;
  off.process(again);
  EXPECT_EQ(off.keyframe(7).points.size(), 0u);
}

namespace {

size_t countProvisional(const SemiDenseKeyframe& kf) {
  return static_cast<size_t>(std::count_if(kf.points.begin(), kf.points.end(),
                                           [](const SemiDensePoint& p) { return p.provisional; }));
}

}  // namespace

// A young map's seeds are also published once they are as certain as young_convergence_ratio
// asks: at 30 fps its first keyframe's seeds need about ten frames of baseline to converge, and
// its objects would have no points until then. They are stand-ins, as its map points: filtered
// on, and dropped when the keyframe finishes, leaving the converged seeds alone. A keyframe of a
// map that is no longer young has none.
TEST(DepthFilter, AYoungMapsSeedsStandInProvisionallyUntilItsKeyframeFinishes) {
  const test::PinholeCamera cam;
  const cv::Mat texture = makeTexture(2048, 5);
  DepthFilterOptions options;
  options.young_map_points = 1000;
  options.young_convergence_ratio = 30;
  DepthFilterOptions strict_options = options;
  strict_options.young_convergence_ratio = 0;
  DepthFilter filter(options, cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy);
  DepthFilter strict(strict_options, cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy);
  const auto young = [&](int k) {  // frame k, keyframe 7 with one map point when k = 0
    DepthFrameInput f = slidingFrame(texture, cam, k, 0.01, k == 0);
    if (k == 0)
      f.new_keyframes.front().sparse.push_back(
          {Eigen::Vector2i(int(cam.cx), int(cam.cy)), Eigen::Vector3f(0, 0, float(kPlaneZ))});
    return f;
  };
  // A short baseline (1 cm per frame at 2 m): after six frames the seeds are certain to a few
  // per cent, not yet to the half per cent of convergence_ratio.
  for (int k = 0; k <= 6; ++k) {
    filter.process(young(k));
    strict.process(young(k));
  }
  const SemiDenseKeyframe early = filter.keyframe(7);
  ASSERT_EQ(strict.keyframe(7).provisional, 0u);
  const size_t converged_strict =
      strict.keyframe(7).points.size() - strict.keyframe(7).from_features;
  EXPECT_EQ(early.provisional, countProvisional(early));
  EXPECT_GT(early.provisional, 1000u);
  EXPECT_GT(early.provisional, 4 * converged_strict + 500);
  std::vector<double> rel;
  for (const auto& p : early.points)
    if (p.provisional) rel.push_back(std::abs(p.p_camera.z() - kPlaneZ) / kPlaneZ);
  std::sort(rel.begin(), rel.end());
  EXPECT_LT(rel[rel.size() / 2], 0.03);
  const auto live = filter.liveKeyframes(1);
  ASSERT_EQ(live.size(), 1u);
  EXPECT_EQ(live[0].points, early.points.size());

  // Filtered on: the seeds converge (the map is no longer young), and a new map finishes map 1's
  // keyframe, which drops its stand-ins and keeps exactly its converged seeds.
  for (int k = 7; k <= 40; ++k) {
    filter.process(young(k));
    strict.process(young(k));
  }
  ASSERT_GE(filter.keyframe(7).points.size() - filter.keyframe(7).from_features -
                filter.keyframe(7).provisional,
            1000u);
  DepthFrameInput later = slidingFrame(texture, cam, 41, 0.01, true);
  filter.process(later);
  EXPECT_EQ(filter.keyframe(48).provisional, 0u);  // not young any more: no provisional seeds
  DepthFrameInput other = slidingFrame(texture, cam, 42, 0.01, true);
  other.map_id = 2;
  other.new_keyframes.front().map_id = 2;
  filter.process(other);
  const SemiDenseKeyframe done = filter.keyframe(7);
  ASSERT_TRUE(done.finished);
  EXPECT_TRUE(done.features_dropped);
  EXPECT_EQ(done.provisional, 0u);
  EXPECT_EQ(done.from_features, 0u);
  EXPECT_EQ(countProvisional(done), 0u);
  EXPECT_GE(done.points.size(), 1000u);
}
