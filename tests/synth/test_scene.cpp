// Scenes: byte-identical output for one seed, geometry of the ground truth (projected boxes,
// depth), the visibility rule of boxes.csv, a smooth hand-held path, clear config errors, and a
// contact sheet of a suite scene (build/synth-sheets/scene.png).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "common/config.h"
#include "common/dataset.h"
#include "common/image_codec.h"
#include "tests/support/test_support.h"
#include "tests/synth/synth_test_util.h"
#include "tools/synth/random_scene.h"
#include "tools/synth/scene.h"
#include "tools/synth/writers.h"

using namespace slamaware;
using namespace slamaware::synth;
namespace fs = std::filesystem;

namespace {

// visibility.csv: (frame, instance) -> visible fraction.
std::map<std::pair<int, std::string>, double> readVisibility(const std::string& dir) {
  std::map<std::pair<int, std::string>, double> out;
  std::ifstream in(dir + "/visibility.csv");
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::stringstream s(line);
    std::string f, inst, vis, sil, frac;
    std::getline(s, f, ',');
    std::getline(s, inst, ',');
    std::getline(s, vis, ',');
    std::getline(s, sil, ',');
    std::getline(s, frac, ',');
    out[{std::stoi(f), inst}] = std::stod(frac);
  }
  return out;
}

bool inside(const GroundTruthBox& b, int w, int h) {
  return b.x > 1 && b.y > 1 && b.x + b.w < w - 1 && b.y + b.h < h - 1;
}

// Projected extent [x0, y0, x1, y1] of points (world) seen from T_world_camera.
Eigen::Vector4d projectExtent(const std::vector<Eigen::Vector3d>& pts, const SE3& T_world_camera,
                              const CameraModel& cam) {
  Eigen::Vector4d e(1e9, 1e9, -1e9, -1e9);
  for (const auto& p : pts) {
    const Eigen::Vector2d px = cam.project(T_world_camera.inverse() * p);
    e[0] = std::min(e[0], px.x());
    e[1] = std::min(e[1], px.y());
    e[2] = std::max(e[2], px.x());
    e[3] = std::max(e[3], px.y());
  }
  return e;
}

std::vector<Eigen::Vector3d> boxCorners(const GroundTruthObject& o) {
  std::vector<Eigen::Vector3d> c;
  for (int i = 0; i < 8; ++i)
    c.push_back(o.center + 0.5 * Eigen::Vector3d((i & 1 ? 1 : -1) * o.size.x(),
                                                 (i & 2 ? 1 : -1) * o.size.y(),
                                                 (i & 4 ? 1 : -1) * o.size.z()));
  return c;
}

// A box covers pixel columns [x, x + w - 1]; a projected extent [a, b] covers centres
// ceil(a)..floor(b).
void expectBoxMatches(const GroundTruthBox& b, const Eigen::Vector4d& e, double tol,
                      const std::string& what) {
  EXPECT_NEAR(b.x, e[0], tol) << what;
  EXPECT_NEAR(b.y, e[1], tol) << what;
  EXPECT_NEAR(b.x + b.w - 1, e[2], tol) << what;
  EXPECT_NEAR(b.y + b.h - 1, e[3], tol) << what;
}

SceneOptions cuboidScene() {
  SceneOptions o;
  o.name = "cuboids";
  o.seed = 21;
  o.frames = 24;
  o.room.furniture = 1;
  o.room.pictures = 1;
  o.objects.count = 5;
  o.objects.distractors = 4;
  o.objects.classes = {"cereal_box"};
  o.objects.distractor_categories = {"food_box", "rubber_eraser", "notebook", "binder",
                                     "calculator"};
  o.objects.yaw_deg = 0;  // axis-aligned cuboids: objects.csv is exactly their shape
  o.sensor.shutter_s = 0;
  return o;
}

}  // namespace

TEST(SynthScene, SameSeedSameBytesOtherSeedOtherBytes) {
  const std::string cfg = test::sourcePath("config/scenes/kitchen_wood.yaml");
  const std::string base = test::tempDir("synth_determinism");
  auto run = [&](const std::string& out, int seed) {
    const std::string cmd = test::binPath("slamaware-synth") + " scene --quiet --config " + cfg +
                            " --frames 5 --seed " + std::to_string(seed) + " --out " + out + " > " +
                            out + ".log 2>&1";
    return std::system(cmd.c_str());
  };
  ASSERT_EQ(run(base + "/a", 501), 0);
  ASSERT_EQ(run(base + "/b", 501), 0);
  ASSERT_EQ(run(base + "/c", 502), 0);
  const auto a = synth_test::treeHashes(base + "/a"), b = synth_test::treeHashes(base + "/b"),
             c = synth_test::treeHashes(base + "/c");
  ASSERT_EQ(a.size(),
            2u + 5u + 5u +
                4u);  // sequence.yaml, scene.yaml, 5 frames, 5 depth maps, 4 ground-truth files
  EXPECT_EQ(a, b);
  for (const auto& f :
       {"rgb/000000.jpg", "depth/000004.png", "groundtruth.txt", "objects.csv", "boxes.csv"})
    EXPECT_NE(a.at(f), c.at(f)) << f;
  // The folder reads back with the common readers.
  const SequenceFolder seq = SequenceFolder::open(base + "/a");
  EXPECT_EQ(seq.size(), 5u);
  EXPECT_EQ(seq.info().classes, paperClasses());
  EXPECT_EQ(seq.groundTruth().size(), 5u);
  EXPECT_FALSE(seq.depthPath(4).empty());
}

TEST(SynthScene, RandomScenesSpanTheRangesAndReproduceFromTheirYaml) {
  // The options: valid for every seed, the same for the same seed, and spread over the ranges.
  int round = 0, low_camera = 0, many_objects = 0;
  double smallest = 9, largest = 0;
  for (uint64_t seed = 0; seed < 200; ++seed) {
    const SceneOptions o = randomSceneOptions(seed);
    EXPECT_NO_THROW(validate(o, "random")) << seed;
    EXPECT_EQ(sceneConfigYaml(o), sceneConfigYaml(randomSceneOptions(seed))) << seed;
    round += o.table.shape == "round";
    low_camera += o.trajectory.height_min < 0.3;
    many_objects += o.objects.count - o.objects.distractors >= 8;
    smallest = std::min(smallest, o.table.size[0]);
    largest = std::max(largest, o.table.size[0]);
    EXPECT_GE(o.objects.count - o.objects.distractors, 2);
    EXPECT_LE(o.objects.distractors, 4);
    EXPECT_GT(o.trajectory.radius_min, 0.5 * o.table.size[0])
        << "camera over the table, seed " << seed;
  }
  EXPECT_GT(round, 40);
  EXPECT_GT(low_camera, 20);
  EXPECT_GT(many_objects, 20);
  EXPECT_LT(smallest, 0.7);
  EXPECT_GT(largest, 1.6);

  // A random scene written by the tool re-renders byte for byte from the scene.yaml it wrote.
  const std::string base = test::tempDir("synth_random");
  auto run = [&](const std::string& args, const std::string& out) {
    const std::string cmd = test::binPath("slamaware-synth") + " scene --quiet " + args +
                            " --frames 3 --out " + out + " > " + out + ".log 2>&1";
    return std::system(cmd.c_str());
  };
  ASSERT_EQ(run("--random 4", base + "/a"), 0);
  ASSERT_EQ(run("--config " + base + "/a/scene.yaml", base + "/b"), 0);
  const auto a = synth_test::treeHashes(base + "/a"), b = synth_test::treeHashes(base + "/b");
  for (const auto& f : {"rgb/000002.jpg", "depth/000002.png", "groundtruth.txt", "objects.csv",
                        "boxes.csv", "scene.yaml"})
    EXPECT_EQ(a.at(f), b.at(f)) << f;
  const SceneOptions back = loadSceneOptions(base + "/a/scene.yaml");
  EXPECT_EQ(back.name, "random_4");
  EXPECT_NE(run("--random 4 --config " + base + "/a/scene.yaml", base + "/c"), 0)
      << "either, not both";
}

TEST(SynthScene, ProjectedObjectBoxesMatchTheBoxesOfAxisAlignedCuboids) {
  const SceneOptions o = cuboidScene();
  SyntheticScene scene(o);
  const std::string dir = test::tempDir("synth_cuboids");
  writeSceneFolder(scene, dir, "cuboids", false);
  const SequenceFolder seq = SequenceFolder::open(dir);
  const auto poses = seq.groundTruth();
  std::map<std::string, GroundTruthObject> objects;
  for (const auto& ob : seq.objects()) objects[ob.instance] = ob;
  const auto vis = readVisibility(dir);
  int checked = 0;
  for (const auto& b : seq.boxes()) {
    if (vis.at({b.frame, b.instance}) < 0.999 || !inside(b, 640, 480))
      continue;  // unoccluded, in the image
    const Eigen::Vector4d e =
        projectExtent(boxCorners(objects.at(b.instance)),
                      poses[static_cast<size_t>(b.frame)].T_world_camera, seq.info().camera);
    expectBoxMatches(b, e, 2.0, b.instance + " in frame " + std::to_string(b.frame));
    ++checked;
  }
  EXPECT_GE(checked, 20) << "too few unoccluded cuboids to test";
}

TEST(SynthScene, GroundTruthOfASuiteSceneIsGeometricallyExact) {
  const SceneOptions o = loadSceneOptions(test::sourcePath("config/scenes/office_cluttered.yaml"));
  SyntheticScene scene(o, -1, 16);
  const std::string dir = test::tempDir("synth_geometry");
  writeSceneFolder(scene, dir, "office_cluttered.yaml", false);
  const SequenceFolder seq = SequenceFolder::open(dir);
  const CameraModel cam = seq.info().camera;
  const auto poses = seq.groundTruth();
  ASSERT_EQ(poses.size(), 16u);
  std::map<std::string, GroundTruthObject> objects;
  for (const auto& ob : seq.objects()) objects[ob.instance] = ob;
  std::map<std::string, int> ids;
  for (const auto& so : scene.objects()) ids[so.instance] = so.id;
  ASSERT_GE(objects.size(), 3u);
  ASSERT_LE(objects.size(), 8u);
  const RenderScene& rs = scene.renderScene();
  // objects.csv is the box of each object's vertices.
  for (const auto& [name, ob] : objects) {
    Eigen::AlignedBox3d bb;
    const auto range = rs.objectRanges()[static_cast<size_t>(ids.at(name))];
    for (uint32_t t = range.begin; t < range.end; ++t)
      for (uint32_t v : rs.triangles()[t].v) bb.extend(rs.vertices()[v].p.cast<double>());
    EXPECT_LT((bb.center() - ob.center).norm(), 1e-5) << name;
    EXPECT_LT((bb.sizes() - ob.size).norm(), 1e-5) << name;
    EXPECT_NEAR(bb.min().z(), scene.environment().table.top_z, 1e-4)
        << name << " stands on the table";
  }
  // Unoccluded objects: the box of the projected vertices is the box of the visible pixels, and it
  // lies inside the projection of the objects.csv box.
  const auto vis = readVisibility(dir);
  int checked = 0;
  for (const auto& b : seq.boxes()) {
    EXPECT_GE(b.w, 20);
    EXPECT_GE(b.h, 20);
    EXPECT_GE(vis.at({b.frame, b.instance}), 0.3);
    if (vis.at({b.frame, b.instance}) < 0.999 || !inside(b, 640, 480)) continue;
    const SE3& T = poses[static_cast<size_t>(b.frame)].T_world_camera;
    std::vector<Eigen::Vector3d> verts;
    const auto range = rs.objectRanges()[static_cast<size_t>(ids.at(b.instance))];
    for (uint32_t t = range.begin; t < range.end; ++t)
      for (uint32_t v : rs.triangles()[t].v) verts.push_back(rs.vertices()[v].p.cast<double>());
    expectBoxMatches(b, projectExtent(verts, T, cam), 2.0,
                     b.instance + " frame " + std::to_string(b.frame));
    const Eigen::Vector4d e = projectExtent(boxCorners(objects.at(b.instance)), T, cam);
    EXPECT_GE(b.x, e[0] - 2);
    EXPECT_GE(b.y, e[1] - 2);
    EXPECT_LE(b.x + b.w - 1, e[2] + 2);
    EXPECT_LE(b.y + b.h - 1, e[3] + 2);
    ++checked;
  }
  EXPECT_GE(checked, 15);
  // Depth: at object pixels away from edges, the depth map holds the z of the object's surface
  // along the pixel's ray (ray-cast against the meshes here), to the millimetre.
  int depth_checked = 0;
  for (int f = 0; f < 16; f += 5) {
    const cv::Mat depth = readImageUnchanged(seq.depthPath(static_cast<size_t>(f)));
    ASSERT_EQ(depth.type(), CV_16UC1);
    FrameBuffers fb;
    scene.render(f, &fb);  // object ids of the frame
    const SE3& T = poses[static_cast<size_t>(f)].T_world_camera;
    for (int y = 5; y < 475; y += 6)
      for (int x = 5; x < 635; x += 6) {
        const int id = fb.object[static_cast<size_t>(y) * 640 + x];
        if (id < 0) continue;
        bool interior = true;
        for (int dy = -2; dy <= 2; ++dy)
          for (int dx = -2; dx <= 2; ++dx)
            interior = interior && fb.object[static_cast<size_t>(y + dy) * 640 + x + dx] == id;
        if (!interior) continue;
        const Eigen::Vector3d ray_cam = cam.unproject(Eigen::Vector2d(x, y));  // (x, y, 1)
        const Eigen::Vector3d origin = T.translation(), dir = T.linear() * ray_cam.normalized();
        const double d = synth_test::rayHitObject(rs, id, origin, dir);
        ASSERT_GT(d, 0) << "ray misses object " << id << " at " << x << "," << y;
        const double z = d * ray_cam.normalized().z();
        EXPECT_NEAR(depth.at<uint16_t>(y, x) / 1000.0, z, 0.001) << x << "," << y;
        const Eigen::Vector3d hit = origin + d * dir;
        const GroundTruthObject& ob = objects.at(scene.objects()[static_cast<size_t>(id)].instance);
        EXPECT_TRUE(((hit - ob.center).cwiseAbs() - 0.5 * ob.size).maxCoeff() < 1e-3)
            << "hit outside the objects.csv box";
        ++depth_checked;
      }
  }
  EXPECT_GT(depth_checked, 200);
}

TEST(SynthScene, HandHeldPathCirclesTheTableSmoothly) {
  SceneOptions o = loadSceneOptions(test::sourcePath("config/scenes/living_round.yaml"));
  SyntheticScene scene(o);
  const CameraModel cam = scene.camera();
  double travelled = 0;
  for (int i = 0; i < scene.frames(); ++i) {
    const SE3 T = scene.pose(i);
    const Eigen::Vector3d table(0, 0, scene.environment().table.top_z);
    const double dist = (T.translation() - table).norm();
    EXPECT_GT(dist, 0.65) << i;
    EXPECT_LT(dist, 1.65) << i;
    Eigen::Vector2d px;
    EXPECT_TRUE(cam.project(T.inverse() * table, &px) && cam.inImage(px, 40))
        << "frame " << i << " looks away from the table";
    if (i == 0) continue;
    const SE3 P = scene.pose(i - 1);
    const double step = (T.translation() - P.translation()).norm();
    const double turn = Eigen::AngleAxisd(P.linear().transpose() * T.linear()).angle() * 180 / M_PI;
    EXPECT_LT(step, 0.03) << "frame " << i;  // m per frame at 30 Hz
    EXPECT_LT(turn, 2.0) << "frame " << i;   // deg per frame
    travelled += step;
  }
  EXPECT_GT(travelled, 2.0) << "the camera should go around the table";
}

// What frame-to-frame tracking needs: many corners spread over the image, and most of them matched
// into the next frame consistently with one camera motion (an essential matrix).
TEST(SynthScene, ConsecutiveFramesMatchLikeATrackerNeeds) {
  const SceneOptions o = loadSceneOptions(test::sourcePath("config/scenes/workshop_laminate.yaml"));
  SyntheticScene scene(o);
  const cv::Ptr<cv::ORB> orb = cv::ORB::create(1000);
  cv::BFMatcher matcher(cv::NORM_HAMMING, true);
  FrameBuffers fb;
  for (int i : {0, 120, 240, 360, 480}) {
    cv::Mat g0, g1;
    cv::cvtColor(scene.render(i, &fb), g0, cv::COLOR_BGR2GRAY);
    cv::cvtColor(scene.render(i + 1, &fb), g1, cv::COLOR_BGR2GRAY);
    std::vector<cv::KeyPoint> k0, k1;
    cv::Mat d0, d1;
    orb->detectAndCompute(g0, cv::noArray(), k0, d0);
    orb->detectAndCompute(g1, cv::noArray(), k1, d1);
    EXPECT_GE(k0.size(), 400u) << "frame " << i;
    int cells[6][8] = {};
    for (const auto& k : k0) ++cells[static_cast<int>(k.pt.y) / 80][static_cast<int>(k.pt.x) / 80];
    int filled = 0;
    for (const auto& row : cells)
      for (int c : row) filled += c >= 3;
    EXPECT_GE(filled, 14) << "corners cover too little of frame " << i;
    std::vector<cv::DMatch> matches;
    matcher.match(d0, d1, matches);
    std::vector<cv::Point2f> p0, p1;
    for (const auto& m : matches)
      if (m.distance < 50) {
        p0.push_back(k0[static_cast<size_t>(m.queryIdx)].pt);
        p1.push_back(k1[static_cast<size_t>(m.trainIdx)].pt);
      }
    ASSERT_GE(p0.size(), 8u);
    cv::Mat inliers;
    cv::findEssentialMat(p0, p1, 525.0, cv::Point2d(319.5, 239.5), cv::RANSAC, 0.999, 1.0, inliers);
    EXPECT_GE(cv::countNonZero(inliers), 150) << "frames " << i << "-" << i + 1;
  }
}

TEST(SynthScene, BadConfigsAreRefusedNamingFileAndKey) {
  const std::string dir = test::tempDir("synth_bad_config");
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir + "/" + name) << text;
    return dir + "/" + name;
  };
  auto message = [](const std::string& path) {
    try {
      loadSceneOptions(path);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::string m = message(write("unknown.yaml", "name: x\nseed: 1\ntable:\n  colour: red\n"));
  EXPECT_NE(m.find("unknown.yaml"), std::string::npos) << m;
  EXPECT_NE(m.find("table.colour"), std::string::npos) << m;
  m = message(write("noseed.yaml", "name: x\n"));
  EXPECT_NE(m.find("noseed.yaml"), std::string::npos) << m;
  EXPECT_NE(m.find("'seed'"), std::string::npos) << m;
  m = message(write("style.yaml", "name: x\nseed: 1\nroom:\n  floor: lava\n"));
  EXPECT_NE(m.find("room.floor"), std::string::npos) << m;
  EXPECT_NE(m.find("lava"), std::string::npos) << m;
  m = message(write("type.yaml", "name: x\nseed: 1\nobjects:\n  count: many\n"));
  EXPECT_NE(m.find("objects.count"), std::string::npos) << m;
  m = message(write("small.yaml", "name: x\nseed: 1\nroom:\n  size: [3, 3]\n"));
  EXPECT_NE(m.find("room.size"), std::string::npos) << m;
  m = message(dir + "/absent.yaml");
  EXPECT_NE(m.find("absent.yaml"), std::string::npos) << m;
}

TEST(SynthScene, ContactSheetOfASuiteScene) {
  SceneOptions o = loadSceneOptions(test::sourcePath("config/scenes/kitchen_wood.yaml"));
  SyntheticScene scene(o);
  std::vector<cv::Mat> frames;
  std::vector<std::string> captions;
  FrameBuffers fb;
  const int step = std::max(1, scene.frames() / 12);
  for (int i = 0; i < scene.frames() && frames.size() < 12; i += step) {
    cv::Mat img = scene.render(i, &fb).clone();
    for (const auto& b : scene.boxes(i, scene.visibility(i, fb)))
      cv::rectangle(img,
                    cv::Rect(static_cast<int>(b.x), static_cast<int>(b.y), static_cast<int>(b.w),
                             static_cast<int>(b.h)),
                    cv::Scalar(0, 255, 255), 1);
    frames.push_back(img);
    captions.push_back("frame " + std::to_string(i));
  }
  const fs::path dir = fs::path(SLAMAWARE_BIN_DIR).parent_path() / "synth-sheets";
  fs::create_directories(dir);
  ASSERT_TRUE(
      cv::imwrite((dir / "scene.png").string(), contactSheet(frames, captions, 4, 400, 300)));
}
