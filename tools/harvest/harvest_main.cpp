// slamaware-harvest SESSION.lcm --map DIR --out OBJECT_SET_DIR: the views of the objects a user
// labelled in the map (slamaware-ctl label), cut from every frame of the recording in which they
// are visible, written as an object set (the UW RGB-D layout every trainer tool reads); objects the
// map fused as background are harvested as background examples of the scene.
//
// A view of an object: the frame's SLAM pose (tracking or relocalised, in the map segment of the
// object) projects every occupied voxel of the segment into a depth buffer (each voxel a square
// of its projected size) that keeps, per pixel, the nearest depth and whose voxel it is, and the
// nearest depth of any other owner. The object's silhouette (its own voxels splatted, with their
// front depth per pixel) is visible where no other owner's voxel lies before its front by more
// than `occlusion_margin` of the depth (an object does not hide itself; a part of it that the map
// holds as another object, right in front of it, does not either): those pixels are the mask,
// their bounding box (grown by `margin`) the crop. A view is skipped, and counted, when the object
// is out of view, when the box of all its voxels crosses the image border (truncated), when less
// than `min_visible` of its silhouette is visible (hidden), or when the box is smaller than
// `min_size_px`. A background object's view that
// lies mostly (over half its box) inside a labelled object's box in that frame is a part of it, not
// background, and is skipped too.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <unordered_map>

#include "common/bus/image_msg.h"
#include "common/bus/log_reader.h"
#include "common/bus/system_config.h"
#include "common/camera_model.h"
#include "common/config.h"
#include "common/geometry.h"
#include "common/nearest_depths.h"
#include "common/progress.h"
#include "procs/objectmap/map_store.h"
#include "procs/objectmap/object_map.h"
#include "slamaware/camera_info_t.hpp"
#include "slamaware/image_t.hpp"
#include "slamaware/pose_t.hpp"

using namespace slamaware;
using namespace slamaware::objectmap;

namespace {

struct HarvestOptions {
  int min_size_px = 32;      ///< a crop's shorter side at least this
  double min_visible = 0.5;  ///< share of the object's silhouette that must be visible
  double occlusion_margin =
      0.1;  ///< the object's front this much (of its depth) behind another's still counts
  double margin = 0.05;    ///< the crop grows by this share of the box on every side
  int border_px = 2;       ///< the box of all the object's voxels must stay this far inside
  bool background = true;  ///< also the objects the map fused as background
  int every = 1;           ///< only every n-th camera frame of the recording (30 Hz repeats itself)
};

/// One object to harvest: its folder names and its voxels' centres.
struct Target {
  int32_t object_id = -1;
  int32_t segment = -1;
  std::string category, instance;
  std::vector<VoxelKey> keys;
  std::vector<Eigen::Vector3d> voxels;  ///< the keys' centres
  bool labelled = false;
  int frames = 0, written = 0, out_of_view = 0, truncated = 0, hidden = 0, small = 0, part = 0;
};

struct Segment3d {
  int32_t slam_map_id = -1;
  double resolution = 0;
  std::vector<Eigen::Vector3d> occupied;
  std::vector<int> owner;  ///< per occupied voxel: the index of the target holding it, -1 none
};

/// Per pixel: the nearest depth and its owner (target index, -1: no target), and the nearest depth
/// of any other owner.
struct DepthBuffer {
  int width = 0;
  std::vector<NearestDepths> cells;
  /// The depth in front of which a voxel of `owner` at (x, y) is visible.
  float occluder(int x, int y, int owner) const {
    return cells[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)]
        .nearestOther(owner);
  }
};

/// The mask of `t` in a frame seen from `T_world_camera`, or why not (the counter to raise).
enum class ViewResult { kWritten, kOutOfView, kTruncated, kHidden, kSmall };

struct View {
  ViewResult result = ViewResult::kOutOfView;
  cv::Rect box;
  cv::Mat mask;  ///< frame-sized, 255 on the object's visible pixels
};

int splatRadius(const CameraModel& cam, double resolution, double z) {
  return std::max(0, static_cast<int>(std::lround(0.5 * cam.fx() * resolution / z)));
}

DepthBuffer depthBuffer(const Segment3d& seg, const CameraModel& cam, const SE3& T_cw) {
  DepthBuffer b{cam.width(), std::vector<NearestDepths>(static_cast<size_t>(cam.width()) *
                                                        static_cast<size_t>(cam.height()))};
  Eigen::Vector2d px;
  for (size_t i = 0; i < seg.occupied.size(); ++i) {
    const Eigen::Vector3d q = T_cw * seg.occupied[i];
    if (!cam.project(q, &px, 1e-3)) continue;
    const int r = splatRadius(cam, seg.resolution, q.z());
    const int u = static_cast<int>(std::lround(px.x())), v = static_cast<int>(std::lround(px.y()));
    if (u + r < 0 || v + r < 0 || u - r >= cam.width() || v - r >= cam.height()) continue;
    const float d = static_cast<float>(q.z());
    const int o = seg.owner[i];
    for (int y = std::max(0, v - r); y <= std::min(cam.height() - 1, v + r); ++y)
      for (int x = std::max(0, u - r); x <= std::min(cam.width() - 1, u + r); ++x)
        b.cells[static_cast<size_t>(y) * static_cast<size_t>(cam.width()) + static_cast<size_t>(x)]
            .add(d, o);
  }
  return b;
}

View viewOf(const Target& t, int owner, const Segment3d& seg, const DepthBuffer& depth,
            const CameraModel& cam, const SE3& T_cw, const HarvestOptions& o) {
  View v;
  // The object's own front surface per pixel (its silhouette where finite).
  cv::Mat front(cam.height(), cam.width(), CV_32F,
                cv::Scalar(std::numeric_limits<float>::infinity()));
  bool any = false;
  double lo_x = 1e300, lo_y = 1e300, hi_x = -1e300,
         hi_y = -1e300;  // all voxels, in the image or not
  Eigen::Vector2d px;
  for (const Eigen::Vector3d& p : t.voxels) {
    const Eigen::Vector3d q = T_cw * p;
    if (!cam.project(q, &px, 1e-3)) continue;
    lo_x = std::min(lo_x, px.x()), lo_y = std::min(lo_y, px.y());
    hi_x = std::max(hi_x, px.x()), hi_y = std::max(hi_y, px.y());
    if (!cam.inImage(px)) continue;
    any = true;
    const int r = splatRadius(cam, seg.resolution, q.z());
    const int u = static_cast<int>(std::lround(px.x())), w = static_cast<int>(std::lround(px.y()));
    for (int y = std::max(0, w - r); y <= std::min(cam.height() - 1, w + r); ++y)
      for (int x = std::max(0, u - r); x <= std::min(cam.width() - 1, u + r); ++x) {
        float& f = front.at<float>(y, x);
        f = std::min(f, static_cast<float>(q.z()));
      }
  }
  if (!any) return v;
  if (lo_x < o.border_px || lo_y < o.border_px || hi_x > cam.width() - 1 - o.border_px ||
      hi_y > cam.height() - 1 - o.border_px) {
    v.result = ViewResult::kTruncated;
    return v;
  }
  // Visible: the silhouette's pixels whose front no other owner's voxel lies before (by more than
  // occlusion_margin of the depth and a voxel).
  v.mask = cv::Mat::zeros(cam.height(), cam.width(), CV_8U);
  const cv::Rect span =
      cv::Rect(cv::Point(static_cast<int>(lo_x), static_cast<int>(lo_y)),
               cv::Point(static_cast<int>(hi_x) + 2, static_cast<int>(hi_y) + 2)) &
      cv::Rect(0, 0, cam.width(), cam.height());
  int silhouette = 0, visible = 0;
  for (int y = span.y; y < span.br().y; ++y)
    for (int x = span.x; x < span.br().x; ++x) {
      const float f = front.at<float>(y, x);
      if (!std::isfinite(f)) continue;
      ++silhouette;
      if (f > depth.occluder(x, y, owner) * (1 + o.occlusion_margin) + seg.resolution) continue;
      ++visible;
      v.mask.at<uint8_t>(y, x) = 255;
    }
  if (visible < o.min_visible * silhouette || visible == 0) {
    v.result = ViewResult::kHidden;
    return v;
  }
  const cv::Rect tight = cv::boundingRect(v.mask);
  const int mx = static_cast<int>(std::lround(o.margin * tight.width)),
            my = static_cast<int>(std::lround(o.margin * tight.height));
  v.box = cv::Rect(tight.x - mx, tight.y - my, tight.width + 2 * mx, tight.height + 2 * my) &
          cv::Rect(0, 0, cam.width(), cam.height());
  v.result = std::min(v.box.width, v.box.height) < o.min_size_px ? ViewResult::kSmall
                                                                 : ViewResult::kWritten;
  return v;
}

/// The frames of the recording that a localised pose goes with: seq -> (pose, camera frame offset).
struct Recording {
  std::optional<CameraModel> camera;
  std::map<int32_t, pose_t> poses;
  int64_t frames = 0;
};

Recording readPoses(const std::string& log, const Channels& ch) {
  Recording r;
  LogReader reader(log);
  try {
    while (auto ev = reader.next()) {
      if (ev->channel == ch.slam_pose) {
        pose_t p;
        if (decodeRecord(*ev, &p) &&
            (p.state == pose_t::STATE_TRACKING || p.state == pose_t::STATE_RELOCALIZED))
          r.poses[p.seq] = p;
      } else if (ev->channel == ch.camera_info && !r.camera) {
        camera_info_t info;
        CameraModel cam;
        std::string why;
        if (decodeRecord(*ev, &info) && cameraFromMessage(info, &cam, &why)) r.camera = cam;
      } else if (ev->channel == ch.camera) {
        ++r.frames;
      }
    }
  } catch (const LogError& e) {
    spdlog::warn("{} (harvesting what comes before it)", e.what());
  }
  return r;
}

std::string viewName(const Target& t, int32_t seq) {
  return fmt::format("{}_1_{}", t.instance, seq);
}

void writeView(const std::string& out, const Target& t, int32_t seq, const cv::Mat& frame,
               const View& v) {
  const std::string dir = out + "/" + t.category + "/" + t.instance;
  std::filesystem::create_directories(dir);
  const std::string base = dir + "/" + viewName(t, seq);
  if (!cv::imwrite(base + "_crop.png", frame(v.box)) ||
      !cv::imwrite(base + "_maskcrop.png", v.mask(v.box)))
    throw std::runtime_error("cannot write " + base + "_crop.png");
  std::ofstream(base + "_loc.txt") << v.box.x << "," << v.box.y << "\n";
}

// The objects to harvest: every one a user labelled, and with o.background those the map fused
// as background; their voxels, per segment. Labelled ones first.
std::vector<Target> collectTargets(const ObjectMapEngine& engine, const HarvestOptions& o,
                                   std::map<int32_t, Segment3d>* segments, int* labelled) {
  const auto& classes = engine.classes();
  const int background =
      classes.empty() || classes.back() != "background" ? -1 : static_cast<int>(classes.size()) - 1;
  std::vector<Target> targets;
  *labelled = 0;
  for (const auto& [sid, seg] : engine.segments()) {
    Segment3d& s = (*segments)[sid];
    s.slam_map_id = seg->slam_map_id;
    s.resolution = seg->occupancy.resolution();
    for (const auto& [oid, obj] : seg->table.objects()) {
      const bool user = !obj.user_label.empty();
      if (!user && !(o.background && background >= 0 && obj.label == background)) continue;
      Target t;
      t.object_id = oid;
      t.segment = sid;
      t.category = user ? obj.user_label : "background";
      t.labelled = user;
      t.instance = fmt::format("{}_{}", t.category, oid);
      for (int32_t cid : obj.candidates) {
        const auto& vox = seg->table.candidates().at(cid).voxels;
        t.keys.insert(t.keys.end(), vox.begin(), vox.end());
      }
      std::sort(t.keys.begin(), t.keys.end());
      t.keys.erase(std::unique(t.keys.begin(), t.keys.end()), t.keys.end());
      for (VoxelKey k : t.keys) t.voxels.push_back(voxelCentre(k, s.resolution));
      if (t.voxels.empty()) continue;
      *labelled += user;
      targets.push_back(std::move(t));
    }
  }
  // Labelled objects first: a background view inside one of the frame's labelled views is a part.
  std::stable_partition(targets.begin(), targets.end(), [](const Target& t) { return t.labelled; });
  return targets;
}

// Each segment's occupied voxels with their owner: the first target holding the voxel (-1: none).
void assignVoxelOwners(const ObjectMapEngine& engine, const std::vector<Target>& targets,
                       std::map<int32_t, Segment3d>* segments) {
  for (const auto& [sid, seg] : engine.segments()) {
    std::unordered_map<VoxelKey, int> owner_of;
    for (size_t i = 0; i < targets.size(); ++i)
      if (targets[i].segment == sid)
        for (VoxelKey k : targets[i].keys) owner_of.emplace(k, static_cast<int>(i));
    Segment3d& s = (*segments)[sid];
    for (const OccupiedVoxel& v : seg->occupancy.occupied()) {
      s.occupied.push_back(v.centre.cast<double>());
      auto it = owner_of.find(v.key);
      s.owner.push_back(it == owner_of.end() ? -1 : it->second);
    }
  }
}

// The object set's set.yaml, and a table of what became of each object's views.
void finishSet(const std::string& out, const std::string& log, const std::string& map_dir,
               const std::vector<Target>& targets, int64_t unposed, int64_t seen) {
  std::filesystem::create_directories(out);
  std::ofstream(out + "/set.yaml")
      << "name: " << std::filesystem::path(out).filename().string()
      << "\nsource: harvest\nsession: " << log << "\nmap: " << map_dir
      << "\nnotes: views of the objects labelled in the map (slamaware-harvest); "
         "background: objects the map fused as background\n";
  std::printf("%-8s %-24s %7s %8s %11s %9s %7s %6s %5s\n", "OBJECT", "INSTANCE", "FRAMES",
              "WRITTEN", "OUT_OF_VIEW", "TRUNCATED", "HIDDEN", "SMALL", "PART");
  for (const Target& t : targets)
    std::printf("%-8d %-24s %7d %8d %11d %9d %7d %6d %5d\n", t.object_id, t.instance.c_str(),
                t.frames, t.written, t.out_of_view, t.truncated, t.hidden, t.small, t.part);
  std::printf("%lld of %lld frames had no localised pose\n", static_cast<long long>(unposed),
              static_cast<long long>(seen));
}

int harvest(const std::string& log, const std::string& map_dir, const std::string& out,
            const HarvestOptions& o, const ObjectMapOptions& map_options, const Channels& ch) {
  MapStore store(map_dir);
  std::optional<ObjectMapEngine> engine;
  const LoadReport report = store.load([&](const MapSnapshot& s) {
    ObjectMapEngine e(map_options);
    e.restore(s);
    engine = std::move(e);
  });
  for (const auto& f : report.failures) spdlog::error("refused {}", f);
  if (!engine) {
    spdlog::error("{}: no usable map", map_dir);
    return 1;
  }
  std::map<int32_t, Segment3d> segments;
  int labelled = 0;
  std::vector<Target> targets = collectTargets(*engine, o, &segments, &labelled);
  assignVoxelOwners(*engine, targets, &segments);
  if (labelled == 0)
    spdlog::warn(
        "{}: no object has a user's label (slamaware-ctl label OBJECT_ID CLASS); harvesting only "
        "background",
        report.json_path);
  const Recording rec = readPoses(log, ch);
  if (!rec.camera) {
    spdlog::error("{}: no usable {} message", log, ch.camera_info);
    return 1;
  }
  spdlog::info(
      "{}: generation {}, {} object(s) to harvest ({} labelled); {}: {} frames, {} localised",
      map_dir, report.generation, targets.size(), labelled, log, rec.frames, rec.poses.size());

  ProgressBar bar("harvest", rec.frames);
  int64_t seen = 0, unposed = 0;
  LogReader reader(log);
  try {
    while (auto ev = reader.next()) {
      if (ev->channel != ch.camera) continue;
      bar.update(++seen);
      if ((seen - 1) % o.every != 0) continue;
      image_t msg;
      if (!decodeRecord(*ev, &msg)) continue;
      auto pose = rec.poses.find(msg.seq);
      if (pose == rec.poses.end()) {
        ++unposed;
        continue;
      }
      const SE3 T_cw = se3FromArrays(pose->second.position, pose->second.orientation).inverse();
      cv::Mat frame;
      std::map<int32_t, DepthBuffer> depth;  // per segment, computed when an object of it needs it
      std::vector<cv::Rect> labelled_boxes;  // of this frame (labelled targets come first)
      for (size_t ti = 0; ti < targets.size(); ++ti) {
        Target& t = targets[ti];
        const Segment3d& seg = segments.at(t.segment);
        if (seg.slam_map_id != pose->second.map_id) continue;
        ++t.frames;
        if (!depth.count(t.segment)) depth[t.segment] = depthBuffer(seg, *rec.camera, T_cw);
        const View v = viewOf(t, static_cast<int>(ti), seg, depth[t.segment], *rec.camera, T_cw, o);
        if (t.labelled && !v.mask.empty()) labelled_boxes.push_back(cv::boundingRect(v.mask));
        if (!t.labelled && v.result == ViewResult::kWritten &&
            std::any_of(labelled_boxes.begin(), labelled_boxes.end(),
                        [&](const cv::Rect& l) { return 2 * (l & v.box).area() > v.box.area(); })) {
          ++t.part;
          continue;
        }
        switch (v.result) {
          case ViewResult::kOutOfView:
            ++t.out_of_view;
            continue;
          case ViewResult::kTruncated:
            ++t.truncated;
            continue;
          case ViewResult::kHidden:
            ++t.hidden;
            continue;
          case ViewResult::kSmall:
            ++t.small;
            continue;
          case ViewResult::kWritten:
            break;
        }
        if (frame.empty()) {
          try {
            frame = decodeImageMessage(msg, ch.camera + " seq " + std::to_string(msg.seq));
          } catch (const std::exception& e) {
            spdlog::warn("{}", e.what());
            break;
          }
          if (frame.cols != rec.camera->width() || frame.rows != rec.camera->height()) {
            spdlog::warn("{} seq {}: {}x{} frame, the camera is {}x{}; skipped", ch.camera, msg.seq,
                         frame.cols, frame.rows, rec.camera->width(), rec.camera->height());
            break;
          }
        }
        writeView(out, t, msg.seq, frame, v);
        ++t.written;
      }
    }
  } catch (const LogError& e) {
    spdlog::warn("{} (harvested what comes before it)", e.what());
  }
  bar.finish();

  finishSet(out, log, map_dir, targets, unposed, seen);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "slamaware-harvest: the views of the objects labelled in an object map, cut from the "
      "recording of "
      "the session that built it, as an object set"};
  std::string log, map_dir, out, config, system;
  HarvestOptions o;
  bool no_background = false;
  app.add_option("session", log, "recording of the session (CAMERA, CAMERA_INFO, SLAM_POSE)")
      ->required();
  app.add_option("--map", map_dir, "the object map's folder (its newest good generation is read)")
      ->required();
  app.add_option("--out", out, "object set folder to write (<class>/<class>_<object id>/...)")
      ->required();
  app.add_option(
      "--config", config,
      "objectmap config (voxel size, grouping; default: built-in = config/objectmap.yaml)");
  app.add_option("--system", system, "system config (channel names)");
  app.add_option("--min-size-px", o.min_size_px, "shorter side of a crop at least this (px)");
  app.add_option("--min-visible", o.min_visible,
                 "share of the object's silhouette that must be visible");
  app.add_option("--margin", o.margin, "crop margin, share of the box on every side");
  app.add_flag("--no-background", no_background, "do not harvest the objects fused as background");
  app.add_option("--every", o.every,
                 "only every n-th camera frame (a 30 Hz session repeats itself)")
      ->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);
  o.background = !no_background;
  try {
    const ObjectMapOptions map_options = loadConfig<ObjectMapOptions>(config, "objectmap", false);
    const SystemConfig sys = system.empty() ? SystemConfig{} : loadSystemConfig(system, false);
    return harvest(log, map_dir, out, o, map_options, sys.channels);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
}
