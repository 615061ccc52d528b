#include "tools/synth/scene.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>

#include "tools/synth/sensor.h"

namespace slamaware::synth {

namespace {

std::vector<std::string> distractorPool(const ObjectOptions& o) {
  if (!o.distractor_categories.empty()) return o.distractor_categories;
  std::vector<std::string> out;
  const auto& paper = paperClasses();
  for (const auto& c : categoryNames())
    if (std::find(paper.begin(), paper.end(), c) == paper.end()) out.push_back(c);
  return out;
}

}  // namespace

SyntheticScene::SyntheticScene(const SceneOptions& options, int64_t seed, int frames)
    : opt_(options) {
  if (seed >= 0) opt_.seed = seed;
  frames_ = frames > 0 ? std::min(frames, opt_.frames) : opt_.frames;
  if (opt_.seed < 0) throw std::invalid_argument("scene: no seed given");
  seed_ = static_cast<uint64_t>(opt_.seed);
  K_.fx = static_cast<float>(opt_.camera.fx);
  K_.fy = static_cast<float>(opt_.camera.fy);
  K_.cx = static_cast<float>(opt_.camera.cx);
  K_.cy = static_cast<float>(opt_.camera.cy);
  Rng rng(hashCombine(seed_, hashString("scene")));
  Rng light_rng = rng.fork(1);
  scene_.light = makeLight(opt_.light, light_rng);
  Rng env_rng = rng.fork(2);
  const float clear = static_cast<float>(opt_.trajectory.radius_max) + 0.45f;
  env_ = buildEnvironment(&scene_, opt_.room, opt_.table, env_rng, clear);
  Rng obj_rng = rng.fork(3);
  placeObjects(obj_rng);
  // Light maps: objects shadow the table top; the table, the furniture and the objects the floor.
  std::vector<int> object_items, floor_occluders = env_.table_items;
  for (size_t i = 0; i < scene_.items.size(); ++i)
    if (scene_.items[i].object >= 0) object_items.push_back(static_cast<int>(i));
  floor_occluders.insert(floor_occluders.end(), env_.furniture_items.begin(),
                         env_.furniture_items.end());
  floor_occluders.insert(floor_occluders.end(), object_items.begin(), object_items.end());
  bakeReceiver(&scene_, env_.table_top, object_items);
  bakeReceiver(&scene_, env_.floor, floor_occluders);
  scene_.finalize();
  trajectory_ =
      std::make_unique<Trajectory>(opt_.trajectory, Eigen::Vector3d(0, 0, env_.table.top_z),
                                   std::max(1, opt_.frames - 1) / opt_.camera.fps, rng.fork(4));
}

void SyntheticScene::placeObjects(Rng& rng) {
  const ObjectOptions& o = opt_.objects;
  std::vector<std::string> classes = o.classes.empty() ? paperClasses() : o.classes;
  rng.shuffle(classes);
  const std::vector<std::string> pool = distractorPool(o);
  std::vector<std::pair<std::string, bool>> wanted;  // category, is distractor
  for (int i = 0; i < o.count - o.distractors; ++i)
    wanted.push_back({classes[static_cast<size_t>(i) % classes.size()], false});
  for (int i = 0; i < o.distractors; ++i) wanted.push_back({rng.pick(pool), true});

  std::map<std::string, uint64_t> seeds_used;  // per category: instance index for the seed
  std::map<std::string, int> names_used;       // per category: instance number in the name
  struct Placed {
    float x, y, r;
  };
  std::vector<Placed> placed;
  const TableGeometry& T = env_.table;
  const float spread = static_cast<float>(std::clamp(o.spread, 0.2, 1.0));
  int next_id = 0;
  for (auto& [category, distractor] : wanted) {
    bool done = false;
    for (int attempt = 0; attempt < 12 && !done; ++attempt) {
      if (attempt > 0 && distractor) category = rng.pick(pool);
      const uint64_t iseed =
          instanceSeed(SeedDomain::kScene, seed_, category, seeds_used[category]++);
      ObjectModel model = makeObject(category, iseed);
      const float r = model.footprintRadius();
      for (int k = 0; k < 400 && !done; ++k) {
        const float x = rng.uniformf(-T.half_x, T.half_x) * spread,
                    y = rng.uniformf(-T.half_y, T.half_y) * spread;
        if (!T.fits(x, y, r, static_cast<float>(o.edge_margin))) continue;
        bool clear = true;
        for (const auto& p : placed)
          clear = clear && std::hypot(p.x - x, p.y - y) >= p.r + r + static_cast<float>(o.min_gap);
        if (!clear) continue;
        const double random_yaw = rng.uniform(0, 2 * 3.141592653589793);
        const double yaw = o.yaw_deg >= 0 ? o.yaw_deg * 3.141592653589793 / 180.0 : random_yaw;
        Eigen::Affine3f pose = Eigen::Affine3f::Identity();
        pose.translate(Eigen::Vector3f(x, y, T.top_z));
        pose.rotate(Eigen::AngleAxisf(static_cast<float>(yaw), Eigen::Vector3f::UnitZ()));
        SceneObject so;
        so.category = category;
        so.instance = category + "_" + std::to_string(++names_used[category]);
        so.instance_seed = iseed;
        so.id = next_id++;
        so.yaw = yaw;
        for (auto& part : model.parts) {
          part.mesh.transform(pose);
          for (const auto& v : part.mesh.vertices) so.world_box.extend(v.p.cast<double>());
          const int mi = scene_.addMaterial(part.material);
          scene_.add(std::move(part.mesh), mi, so.id);
        }
        objects_.push_back(so);
        placed.push_back({x, y, r});
        done = true;
      }
    }
    if (!done)
      throw std::invalid_argument("cannot place " + std::to_string(o.count) +
                                  " objects on the table (placing a " + category +
                                  "); enlarge table.size or lower objects.count / objects.min_gap");
  }
}

CameraModel SyntheticScene::camera() const {
  return CameraModel(opt_.camera.width, opt_.camera.height, opt_.camera.fx, opt_.camera.fy,
                     opt_.camera.cx, opt_.camera.cy);
}

Eigen::Isometry3d SyntheticScene::pose(int frame) const { return trajectory_->pose(time(frame)); }

cv::Mat SyntheticScene::render(int frame, FrameBuffers* fb) {
  const Eigen::Isometry3d T = pose(frame);
  raster_.render(scene_, K_, T, Viewport{0, 0, opt_.camera.width, opt_.camera.height}, fb, true);
  ShutterMotion motion;
  if (opt_.sensor.shutter_s > 0) {
    motion.enabled = true;
    motion.T_world_camera_open = trajectory_->pose(time(frame) - 0.5 * opt_.sensor.shutter_s);
  }
  return applySensor(*fb, K_, T, opt_.sensor, motion,
                     hashCombine(seed_, static_cast<uint64_t>(frame) + 0x100000000ull));
}

std::vector<ObjectVisibility> SyntheticScene::visibility(int frame, const FrameBuffers& fb) {
  const int W = fb.vp.w, H = fb.vp.h;
  std::vector<ObjectVisibility> vis(objects_.size());
  for (size_t i = 0; i < vis.size(); ++i) {
    vis[i].id = static_cast<int>(i);
    vis[i].x0 = W;
    vis[i].y0 = H;
  }
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const int id = fb.object[static_cast<size_t>(y) * W + x];
      if (id < 0 || static_cast<size_t>(id) >= vis.size()) continue;
      ObjectVisibility& v = vis[static_cast<size_t>(id)];
      ++v.visible_px;
      v.x0 = std::min(v.x0, x + fb.vp.x0);
      v.x1 = std::max(v.x1, x + fb.vp.x0);
      v.y0 = std::min(v.y0, y + fb.vp.y0);
      v.y1 = std::max(v.y1, y + fb.vp.y0);
    }
  const Eigen::Isometry3d T = pose(frame);
  for (auto& v : vis) {
    if (v.visible_px == 0) continue;
    Eigen::Vector4f b;
    if (Rasterizer::projectedBounds(scene_, v.id, K_, T, &b)) {
      // The whole silhouette, also where it leaves the image (up to one image size beyond).
      const int x0 = std::max(-W, static_cast<int>(std::floor(b[0])) - 1),
                y0 = std::max(-H, static_cast<int>(std::floor(b[1])) - 1);
      const int x1 = std::min(2 * W, static_cast<int>(std::ceil(b[2])) + 1),
                y1 = std::min(2 * H, static_cast<int>(std::ceil(b[3])) + 1);
      v.silhouette_px =
          raster_.silhouettePixels(scene_, v.id, K_, T, Viewport{x0, y0, x1 - x0 + 1, y1 - y0 + 1});
    }
    v.silhouette_px = std::max(v.silhouette_px, v.visible_px);
    v.fraction = static_cast<double>(v.visible_px) / static_cast<double>(v.silhouette_px);
    v.listed = v.fraction >= kMinVisibleFraction && v.x1 - v.x0 + 1 >= kMinBoxSide &&
               v.y1 - v.y0 + 1 >= kMinBoxSide;
  }
  return vis;
}

std::vector<GroundTruthBox> SyntheticScene::boxes(int frame,
                                                  const std::vector<ObjectVisibility>& vis) const {
  std::vector<GroundTruthBox> out;
  for (const auto& v : vis) {
    if (!v.listed) continue;
    GroundTruthBox b;
    b.frame = frame;
    b.x = v.x0;
    b.y = v.y0;
    b.w = v.x1 - v.x0 + 1;
    b.h = v.y1 - v.y0 + 1;
    b.cls = objects_[static_cast<size_t>(v.id)].category;
    b.instance = objects_[static_cast<size_t>(v.id)].instance;
    out.push_back(b);
  }
  return out;
}

std::vector<GroundTruthObject> SyntheticScene::groundTruthObjects() const {
  std::vector<GroundTruthObject> out;
  for (const auto& o : objects_) {
    GroundTruthObject g;
    g.instance = o.instance;
    g.cls = o.category;
    g.center = o.world_box.center();
    g.size = o.world_box.sizes();
    out.push_back(g);
  }
  return out;
}

SequenceInfo SyntheticScene::sequenceInfo(const std::string& config_name) const {
  SequenceInfo info;
  info.name = opt_.name;
  std::ostringstream src;
  src << "slamaware-synth scene, config " << config_name << ", seed " << seed_;
  info.source = src.str();
  info.fps = opt_.camera.fps;
  info.frames = frames_;
  info.camera = camera();
  info.classes = paperClasses();
  std::ostringstream notes;
  notes << "synthetic tabletop scene (rendered, exact ground truth). World frame: metres, z up, "
           "origin on the floor "
           "under the table centre, table top at z = "
        << env_.table.top_z
        << ". groundtruth.txt: T_world_camera (camera x right, y down, z forward) at mid-exposure. "
           "boxes.csv: x, y = "
           "first pixel column / row of the visible pixels, w, h = their extent in pixels; objects "
           "at least 30 % "
           "visible (z-buffer pixels over the silhouette) with a box of at least 20 x 20. "
           "objects.csv: axis-aligned "
           "world box of each object's vertices. depth/: 16-bit PNG, z in millimetres (0 = none). "
           "visibility.csv: "
           "per frame and object, visible and silhouette pixels.";
  if (!opt_.notes.empty()) notes << " " << opt_.notes;
  info.notes = notes.str();
  return info;
}

}  // namespace slamaware::synth
