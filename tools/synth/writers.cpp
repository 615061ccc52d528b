#include "tools/synth/writers.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "common/image_codec.h"
#include "common/progress.h"
#include "common/tum.h"
#include "tools/synth/textures.h"

namespace fs = std::filesystem;

namespace slamaware::synth {

namespace {

using Clock = std::chrono::steady_clock;

void writeBytes(const fs::path& path, const std::vector<uint8_t>& bytes, WriteStats* st) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error(path.string() + ": write failed");
  st->files += 1;
  st->bytes += static_cast<int64_t>(bytes.size());
}

void writeText(const fs::path& path, const std::string& text, WriteStats* st) {
  std::ofstream out(path);
  out << text;
  if (!out) throw std::runtime_error(path.string() + ": write failed");
  st->files += 1;
  st->bytes += static_cast<int64_t>(text.size());
}

void clearFrames(const fs::path& dir) {
  if (!fs::is_directory(dir)) return;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string ext = e.path().extension().string();
    if (e.is_regular_file() && (ext == ".jpg" || ext == ".png")) fs::remove(e.path());
  }
}

std::string frameName(int i, const char* ext) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%06d%s", i, ext);
  return buf;
}

cv::Mat depthMillimetres(const FrameBuffers& fb) {
  cv::Mat d(fb.vp.h, fb.vp.w, CV_16UC1);
  for (int y = 0; y < fb.vp.h; ++y) {
    uint16_t* row = d.ptr<uint16_t>(y);
    for (int x = 0; x < fb.vp.w; ++x) {
      const float z = fb.depth[static_cast<size_t>(y) * fb.vp.w + x];
      row[x] = z > 0.f ? static_cast<uint16_t>(std::min(65535L, std::lround(z * 1000.f))) : 0;
    }
  }
  return d;
}

}  // namespace

WriteStats writeSceneFolder(SyntheticScene& scene, const std::string& dir_s,
                            const std::string& config_name, bool progress) {
  const auto t0 = Clock::now();
  WriteStats st;
  const fs::path dir(dir_s);
  fs::create_directories(dir / "rgb");
  clearFrames(dir / "rgb");
  const bool depth = scene.options().write_depth;
  if (depth) {
    fs::create_directories(dir / "depth");
    clearFrames(dir / "depth");
  } else if (fs::is_directory(dir / "depth")) {
    clearFrames(dir / "depth");
  }
  writeSequenceInfo((dir / "sequence.yaml").string(), scene.sequenceInfo(config_name));
  writeObjects((dir / "objects.csv").string(), scene.groundTruthObjects());
  std::vector<TimedPose> poses;
  std::vector<GroundTruthBox> boxes;
  std::string vis_csv = "frame,instance,visible_px,silhouette_px,fraction\n";
  FrameBuffers fb;
  std::unique_ptr<ProgressBar> bar;
  if (progress)
    bar = std::make_unique<ProgressBar>("render " + scene.options().name, scene.frames());
  for (int i = 0; i < scene.frames(); ++i) {
    const cv::Mat img = scene.render(i, &fb);
    writeBytes(dir / "rgb" / frameName(i, ".jpg"),
               encodeJpeg(img, scene.options().sensor.jpeg_quality), &st);
    if (depth)
      writeBytes(dir / "depth" / frameName(i, ".png"), encodePng(depthMillimetres(fb), 3), &st);
    const auto vis = scene.visibility(i, fb);
    for (const auto& b : scene.boxes(i, vis)) boxes.push_back(b);
    for (const auto& v : vis) {
      if (v.visible_px == 0) continue;
      char buf[160];
      std::snprintf(buf, sizeof(buf), "%d,%s,%lld,%lld,%.4f\n", i,
                    scene.objects()[static_cast<size_t>(v.id)].instance.c_str(),
                    static_cast<long long>(v.visible_px), static_cast<long long>(v.silhouette_px),
                    v.fraction);
      vis_csv += buf;
    }
    poses.push_back({scene.time(i), scene.pose(i)});
    if (bar) bar->update(i + 1);
  }
  if (bar) bar->finish();
  writeTum((dir / "groundtruth.txt").string(), poses);
  writeBoxes((dir / "boxes.csv").string(), boxes);
  writeText(dir / "visibility.csv", vis_csv, &st);
  st.files += 4;
  st.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return st;
}

// ---- Object sets
// ----------------------------------------------------------------------------------

namespace {

struct Backdrop {
  RenderScene scene;
  Environment env;
  size_t base_items = 0;
  size_t base_materials = 0;
};

Backdrop makeBackdrop(uint64_t seed, const ObjectSetOptions& o) {
  Backdrop b;
  Rng rng(seed);
  Rng lr = rng.fork(1);
  b.scene.light = makeLight(o.light, lr);
  RoomOptions room;
  room.size = {rng.uniform(4.0, 5.5), rng.uniform(4.0, 5.5)};
  room.pictures = rng.range(4, 8);
  room.furniture = rng.range(2, 5);
  TableOptions table;
  table.shape = rng.chance(0.7) ? "rect" : "round";
  table.size = {rng.uniform(0.9, 1.4), rng.uniform(0.7, 0.9)};
  table.height = rng.uniform(0.7, 0.8);
  Rng er = rng.fork(2);
  b.env = buildEnvironment(&b.scene, room, table, er, static_cast<float>(o.distance_max) + 0.5f);
  std::vector<int> occ = b.env.table_items;
  occ.insert(occ.end(), b.env.furniture_items.begin(), b.env.furniture_items.end());
  bakeReceiver(&b.scene, b.env.floor, occ);
  b.base_items = b.scene.items.size();
  b.scene.freezePrefix(b.base_items);
  b.base_materials = b.scene.materials.size();
  return b;
}

// The turntable: a disc on a short cylinder, its top a light-map receiver; the print on the
// top turns with the object (`yaw`).
Receiver addTurntable(Backdrop& b, float radius, float height, float yaw, const TexturePtr& top_tex,
                      const TexturePtr& side_tex) {
  RenderScene& s = b.scene;
  const float z0 = b.env.table.top_z, z1 = z0 + height;
  Material top;
  top.texture = top_tex;
  top.specular = 0.08f;
  const int n = static_cast<int>(2 * radius / 0.003f);
  top.shadow = std::make_shared<ScalarMap>(n, n);
  top.ao = std::make_shared<ScalarMap>(n, n);
  const int mi = s.addMaterial(top);
  Mesh d = disc(0, 0, radius, z1, 64);
  for (auto& v : d.vertices) {
    const float x = v.p.x() / radius, y = v.p.y() / radius;
    const float c = std::cos(-yaw), sn = std::sin(-yaw);
    v.uv = {0.5f + 0.5f * (c * x - sn * y), 0.5f - 0.5f * (sn * x + c * y)};
    v.uv2 = {0.5f + 0.5f * x, 0.5f + 0.5f * y};
  }
  s.add(std::move(d), mi);
  Material side;
  side.texture = side_tex;
  side.specular = 0.1f;
  const int si = s.addMaterial(side);
  s.add(lathe({{radius, z0, true}, {radius, z1 - 0.0005f, true}, {0, z1 - 0.0005f}}, 64, 3.f), si);
  Receiver rc;
  rc.material = mi;
  rc.x0 = -radius;
  rc.x1 = radius;
  rc.y0 = -radius;
  rc.y1 = radius;
  rc.z = z1;
  rc.ao_radius = 0.012f;
  rc.ao_strength = 0.55f;
  rc.shadow_texel = 0.002f;
  return rc;
}

std::string yamlList(const std::vector<std::string>& v) {
  std::string s = "[";
  for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + v[i];
  return s + "]";
}

}  // namespace

namespace {

// Turntable tops: a few printed / plain discs with index marks; metal sides.
void turntableTextures(Rng& tt_rng, std::vector<TexturePtr>* tops, std::vector<TexturePtr>* sides) {
  for (int i = 0; i < 3; ++i) {
    const cv::Vec3f c = hsvColor(tt_rng.uniformf(0.f, 360.f), tt_rng.uniformf(0.f, 0.25f),
                                 tt_rng.uniformf(0.55f, 0.9f));
    cv::Mat t = i == 0 ? tableTexture(tt_rng, "laminate", 0.5f, 0.5f, 0.001f)
                       : (i == 1 ? tableTexture(tt_rng, "wood", 0.5f, 0.5f, 0.001f)
                                 : plasticTexture(tt_rng, 512, 512, c, 0.08f));
    // Index marks around the edge, as turntables have.
    for (int k = 0; k < 36; ++k) {
      const double a = k * CV_PI / 18;
      cv::line(t,
               cv::Point(256 + static_cast<int>(235 * std::cos(a)),
                         256 + static_cast<int>(235 * std::sin(a))),
               cv::Point(256 + static_cast<int>(250 * std::cos(a)),
                         256 + static_cast<int>(250 * std::sin(a))),
               cv::Scalar(30, 30, 30), k % 9 == 0 ? 3 : 1, cv::LINE_AA);
    }
    tops->push_back(std::make_shared<const Texture>(t, false, false));
    sides->push_back(std::make_shared<const Texture>(
        metalTexture(tt_rng, 256, 32, {0.3f, 0.3f, 0.32f}, true), true, false));
  }
}

// A camera at `dist` from `target` at elevation `el` and azimuth `az`, looking at it, x level.
Eigen::Isometry3d lookAtFromSphere(const Eigen::Vector3d& target, double dist, double el,
                                   double az) {
  const Eigen::Vector3d cam =
      target + dist * Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                                      std::sin(el));
  const Eigen::Vector3d zc = (target - cam).normalized();
  const Eigen::Vector3d xc = zc.cross(Eigen::Vector3d::UnitZ()).normalized();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = xc;
  T.linear().col(1) = zc.cross(xc);
  T.linear().col(2) = zc;
  T.translation() = cam;
  return T;
}

// The set's set.yaml: what was rendered and how the files are named.
std::string objectSetYaml(const ObjectSetOptions& o, const std::vector<std::string>& cats,
                          uint64_t set_seed, int views_per_instance) {
  std::string e_list = "[", v_list = "[";
  for (size_t i = 0; i < o.elevations_deg.size(); ++i) {
    e_list += (i ? ", " : "") + std::to_string(static_cast<int>(std::lround(o.elevations_deg[i])));
    v_list += (i ? ", " : "") + std::to_string(o.video_ids[i]);
  }
  return "name: " + o.name +
         "\nsource: synth (slamaware-synth objects)\nseed: " + std::to_string(set_seed) +
         "\ncategories: " + yamlList(cats) +
         "\ninstances_per_category: " + std::to_string(o.instances) +
         "\nelevations_deg: " + e_list + "]\nvideo_ids: " + v_list +
         "]\nazimuth_step_deg: " + std::to_string(o.azimuth_step_deg) +
         "\nviews_per_instance: " + std::to_string(views_per_instance) +
         "\nnotes: \"turntable views rendered by slamaware-synth; "
         "<instance>_<video>_<frame>: video = elevation, frame = "
         "azimuth step from 1; crop = object box plus margin; maskcrop = object "
         "pixels; loc = crop corner in the "
         "640x480 frame\"\n";
}

}  // namespace

WriteStats writeObjectSet(const ObjectSetOptions& o, const std::string& dir_s, int64_t seed,
                          bool progress) {
  const auto t0 = Clock::now();
  WriteStats st;
  const uint64_t set_seed = static_cast<uint64_t>(seed >= 0 ? seed : o.seed);
  std::vector<std::string> cats = o.categories;
  if (cats.empty() || std::find(cats.begin(), cats.end(), "all") != cats.end())
    cats = categoryNames();
  const int steps = std::max(1, static_cast<int>(std::lround(360.0 / o.azimuth_step_deg)));
  const int views_per_instance = steps * static_cast<int>(o.elevations_deg.size());
  const fs::path dir(dir_s);
  fs::create_directories(dir);
  Intrinsics K;
  K.fx = static_cast<float>(o.camera.fx);
  K.fy = static_cast<float>(o.camera.fy);
  K.cx = static_cast<float>(o.camera.cx);
  K.cy = static_cast<float>(o.camera.cy);
  const int W = o.camera.width, H = o.camera.height;

  std::vector<std::unique_ptr<Backdrop>> backdrops(static_cast<size_t>(o.backgrounds));
  Rng set_rng(hashCombine(set_seed, hashString("object-set")));
  const uint64_t backdrop_seed = set_rng.next();
  Rng tt_rng = set_rng.fork(9);
  std::vector<TexturePtr> tt_tops, tt_sides;
  turntableTextures(tt_rng, &tt_tops, &tt_sides);

  int64_t total = static_cast<int64_t>(cats.size()) * o.instances * views_per_instance;
  std::unique_ptr<ProgressBar> bar;
  if (progress) bar = std::make_unique<ProgressBar>("render " + o.name, total);
  int64_t done = 0;
  Rasterizer raster;
  FrameBuffers fb;
  for (const auto& cat : cats) {
    for (int n = 1; n <= o.instances; ++n) {
      const std::string inst = cat + "_" + std::to_string(n);
      const uint64_t iseed =
          instanceSeed(SeedDomain::kObjectSet, set_seed, cat, static_cast<uint64_t>(n));
      const ObjectModel model = makeObject(cat, iseed);
      Rng irng(hashCombine(iseed, hashString("views")));
      const size_t bi = static_cast<size_t>(irng.range(0, o.backgrounds - 1));
      if (!backdrops[bi])
        backdrops[bi] = std::make_unique<Backdrop>(makeBackdrop(hashCombine(backdrop_seed, bi), o));
      Backdrop& bd = *backdrops[bi];
      const float dist = static_cast<float>(irng.uniform(o.distance_min, o.distance_max));
      const double cam_az = irng.uniform(0, 2 * M_PI), yaw0 = irng.uniform(0, 2 * M_PI);
      const float tt_radius = std::max(0.18f, model.footprintRadius() + 0.06f), tt_h = 0.02f;
      const size_t tt = static_cast<size_t>(irng.range(0, 2));
      const fs::path idir = dir / cat / inst;
      fs::create_directories(idir);
      for (size_t e = 0; e < o.elevations_deg.size(); ++e) {
        const double el = o.elevations_deg[e] * M_PI / 180.0;
        for (int k = 0; k < steps; ++k) {
          const double yaw = yaw0 + k * o.azimuth_step_deg * M_PI / 180.0;
          // Scene for this view: backdrop + turntable + the object turned by yaw.
          RenderScene& s = bd.scene;
          s.items.resize(bd.base_items);
          s.materials.resize(bd.base_materials);
          const Receiver rc =
              addTurntable(bd, tt_radius, tt_h, static_cast<float>(yaw), tt_tops[tt], tt_sides[tt]);
          const float base_z = bd.env.table.top_z + tt_h;
          Eigen::Affine3f pose = Eigen::Affine3f::Identity();
          pose.translate(Eigen::Vector3f(0, 0, base_z));
          pose.rotate(Eigen::AngleAxisf(static_cast<float>(yaw), Eigen::Vector3f::UnitZ()));
          std::vector<int> obj_items;
          for (const auto& part : model.parts) {
            Mesh m = part.mesh;
            m.transform(pose);
            const int mi = s.addMaterial(part.material);
            s.add(std::move(m), mi, 0);
            obj_items.push_back(static_cast<int>(s.items.size()) - 1);
          }
          bakeReceiver(&s, rc, obj_items);
          s.finalize();
          // Camera: on a sphere around the object's centre, a little turntable wobble.
          const Eigen::AlignedBox3f ob = model.bounds();
          const Eigen::Vector3d target(0, 0, base_z + 0.5 * ob.sizes().z());
          const double wob = 0.004 * std::sin(k * 0.7 + static_cast<double>(e));
          const Eigen::Isometry3d T = lookAtFromSphere(target, dist, el + wob, cam_az);
          Eigen::Vector4f pb;
          if (!Rasterizer::projectedBounds(s, 0, K, T, &pb))
            throw std::runtime_error(inst + ": object behind the camera");
          const float bw = pb[2] - pb[0], bh = pb[3] - pb[1];
          const float m = static_cast<float>(o.crop_margin) * std::max(bw, bh) + 4.f;
          const int x0 = std::clamp(static_cast<int>(std::floor(pb[0] - m)), 0, W - 1);
          const int y0 = std::clamp(static_cast<int>(std::floor(pb[1] - m)), 0, H - 1);
          const int x1 = std::clamp(static_cast<int>(std::ceil(pb[2] + m)), x0, W - 1);
          const int y1 = std::clamp(static_cast<int>(std::ceil(pb[3] + m)), y0, H - 1);
          const Viewport vp{x0, y0, x1 - x0 + 1, y1 - y0 + 1};
          raster.render(s, K, T, vp, &fb, true);
          const uint64_t noise_seed =
              hashCombine(iseed, static_cast<uint64_t>(e * 100000 + static_cast<size_t>(k)));
          const cv::Mat crop = applySensor(fb, K, T, o.sensor, ShutterMotion{}, noise_seed);
          cv::Mat mask(vp.h, vp.w, CV_8UC1);
          for (int y = 0; y < vp.h; ++y)
            for (int x = 0; x < vp.w; ++x)
              mask.at<uint8_t>(y, x) = fb.object[static_cast<size_t>(y) * vp.w + x] == 0 ? 255 : 0;
          const std::string stem =
              inst + "_" + std::to_string(o.video_ids[e]) + "_" + std::to_string(k + 1);
          writeBytes(idir / (stem + "_crop.png"), encodePng(crop, 6), &st);
          std::vector<uint8_t> mbytes;
          cv::imencode(".png", mask, mbytes,
                       {cv::IMWRITE_PNG_BILEVEL, 1, cv::IMWRITE_PNG_COMPRESSION, 9});
          writeBytes(idir / (stem + "_maskcrop.png"), mbytes, &st);
          writeText(idir / (stem + "_loc.txt"),
                    std::to_string(x0) + "," + std::to_string(y0) + "\n", &st);
          if (bar) bar->update(++done);
        }
      }
    }
  }
  if (bar) bar->finish();
  const std::string yaml = objectSetYaml(o, cats, set_seed, views_per_instance);
  writeText(dir / "set.yaml", yaml, &st);
  st.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return st;
}

cv::Mat contactSheet(const std::vector<cv::Mat>& images, const std::vector<std::string>& captions,
                     int cols, int cell_w, int cell_h) {
  const int n = static_cast<int>(images.size());
  const int rows = std::max(1, (n + cols - 1) / cols);
  const int cap_h = 16;
  cv::Mat sheet(rows * (cell_h + cap_h), cols * cell_w, CV_8UC3, cv::Scalar(40, 40, 40));
  for (int i = 0; i < n; ++i) {
    cv::Mat img = images[static_cast<size_t>(i)];
    if (img.empty()) continue;
    if (img.channels() == 1) cv::cvtColor(img, img, cv::COLOR_GRAY2BGR);
    const double s = std::min(static_cast<double>(cell_w - 4) / img.cols,
                              static_cast<double>(cell_h - 4) / img.rows);
    cv::Mat r;
    cv::resize(img, r,
               cv::Size(std::max(1, static_cast<int>(img.cols * s)),
                        std::max(1, static_cast<int>(img.rows * s))),
               0, 0, s < 1 ? cv::INTER_AREA : cv::INTER_NEAREST);
    const int cx = (i % cols) * cell_w + (cell_w - r.cols) / 2,
              cy = (i / cols) * (cell_h + cap_h) + (cell_h - r.rows) / 2;
    r.copyTo(sheet(cv::Rect(cx, cy, r.cols, r.rows)));
    if (static_cast<size_t>(i) < captions.size())
      cv::putText(sheet, captions[static_cast<size_t>(i)],
                  cv::Point((i % cols) * cell_w + 3, (i / cols) * (cell_h + cap_h) + cell_h + 11),
                  cv::FONT_HERSHEY_SIMPLEX, 0.38, cv::Scalar(230, 230, 230), 1, cv::LINE_AA);
  }
  return sheet;
}

}  // namespace slamaware::synth
