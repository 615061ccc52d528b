// slamaware-slam: monocular keyframe SLAM with semi-dense depth. Reads CAMERA_INFO and CAMERA;
// publishes SLAM_POSE for every frame handled (with the tracking state and the map id),
// SLAM_KEYFRAME when keyframes are created, moved or culled, and SLAM_MAP (incremental per
// keyframe, full every few seconds of sequence time). In lockstep every frame is handled and its
// keyframe and map messages go out before its pose; in real time, frames that queued up behind a
// newer one are dropped and counted.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <deque>
#include <opencv2/core/utility.hpp>

#include "common/bus/bus.h"
#include "common/bus/image_msg.h"
#include "common/bus/input_loop.h"
#include "common/bus/node.h"
#include "common/bus/shutdown.h"
#include "common/bus/status.h"
#include "common/config.h"
#include "common/heap.h"
#include "common/image_codec.h"
#include "procs/slam/slam_messages.h"
#include "procs/slam/slam_options.h"
#include "procs/slam/slam_system.h"

using namespace slamaware;
using namespace slamaware::slam;

namespace {

void publish(Bus& bus, const Channels& ch, const SlamOutput& out, StatusReporter& status) {
  for (const auto& k : out.keyframes) bus.publish(ch.slam_keyframe, toMessage(k));
  for (const auto& c : out.clouds) bus.publish(ch.slam_map, toMessage(c));
  if (out.has_pose) bus.publish(ch.slam_pose, toMessage(out.pose));
  for (const auto& e : out.events) {
    spdlog::info("{}", e);
    status.setMessage(e);
  }
}

void reportStats(const SlamSystem& slam, StatusReporter& status) {
  const SlamStats s = slam.stats();
  status.setCounter("map_id", s.map_id);
  status.setCounter("maps", s.maps);
  status.setCounter("keyframes", s.keyframes);
  status.setCounter("map_points", s.points);
  status.setCounter("frames_located", s.frames_located);
  status.setCounter("frames_lost", s.frames_lost);
  status.setCounter("frames_unusable", s.frames_unusable);
  status.setCounter("frames_duplicate", s.frames_duplicate);
  status.setCounter("time_discontinuities", s.discontinuities);
  status.setCounter("relocalizations", s.relocalizations);
  status.setCounter("reinitializations", s.reinitializations);
  status.setCounter("depth_seeds", s.depth_seeds);
  status.setCounter("depth_points", s.depth_points);
  status.setCounter("depth_frames_skipped", s.depth_frames_skipped);
  status.setCounter("bundle_adjustments", s.bundle_adjustments);
  status.setCounter("keyframes_culled", s.keyframes_culled);
  status.setCounter("track_us", static_cast<int64_t>(s.track_ms * 1000));
  status.setCounter("depth_update_us", static_cast<int64_t>(s.depth_update_ms * 1000));
  status.setState(s.state == "LOST" ? StatusReporter::State::kDegraded
                                    : StatusReporter::State::kRunning);
}

// A frame's buffers (the image, its pyramid, per-frame matches) come and go at the camera's rate
// and are best reused from the heap; a block over twice a colour frame (the full map's cloud and
// its message) is mapped on its own and handed back to the system when freed. With glibc's
// sliding threshold SLAM's RSS settled 78-95 MB from run to run on the same replay
// (docs/experiments/slam.md, 2026-12-05).
void holdFramesInTheHeap(const CameraModel& camera) {
  const size_t frame = static_cast<size_t>(camera.width()) * camera.height() * 3;
  mapBlocksApartFrom(2 * frame);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "slamaware-slam: monocular SLAM with semi-dense depth (CAMERA_INFO, CAMERA -> SLAM_POSE, "
      "SLAM_KEYFRAME, SLAM_MAP)"};
  NodeArgs node;
  addNodeOptions(app, node);
  addPrintConfigOption(app, [] { return defaultConfigFileText<SlamOptions>("slam"); });
  CLI11_PARSE(app, argc, argv);

  return runNode("slam", node, [&]() -> int {
    const SystemConfig sys = loadSystem(node);
    const SlamOptions opts = loadConfig<SlamOptions>(node.config, "slam");
    const bool lockstep = sys.bus.lockstep;
    // OpenCV's own thread pool would compete with tracking, mapping and the depth filter for
    // the cores; those three are the parallelism we want.
    cv::setNumThreads(1);
    const Channels& ch = sys.channels;
    Bus bus(sys.bus.url);
    StatusReporter status(bus, node.nameOr("slam"), ch.statusOf(node.nameOr("slam")));
    SlamSystem slam(
        opts, lockstep,
        SlamThreadNice{sys.scheduling.slam_mapping_nice, sys.scheduling.slam_depth_nice});

    bus.subscribe<camera_info_t>(
        ch.camera_info,
        [&](const camera_info_t& info) {
          CameraModel camera;
          std::string why;
          if (!cameraFromMessage(info, &camera, &why)) {
            bus.reject(ch.camera_info, why);
            return;
          }
          const bool first = !slam.hasCamera();
          const bool changed = slam.setCamera(camera);
          if (first || changed) holdFramesInTheHeap(camera);
          if (changed) {
            status.count("camera_changes");
            status.setMessage("camera changed: SLAM restarted");
            spdlog::warn("CAMERA_INFO changed to {}x{} fx {:.1f}: SLAM restarted", camera.width(),
                         camera.height(), camera.fx());
          } else if (first) {
            spdlog::info("camera {}x{} fx {:.1f} fy {:.1f} from {}", camera.width(),
                         camera.height(), camera.fx(), camera.fy(), info.source);
          }
        },
        sys.bus.max_message_bytes);

    std::deque<image_t> pending;
    bus.subscribe<image_t>(
        ch.camera, [&](const image_t& img) { pending.push_back(img); }, sys.bus.max_image_bytes);

    auto handleFrame = [&](const image_t& img) {
      status.noteInput(img.utime, img.seq);
      SlamOutput out;
      const std::string what = ch.camera + " seq " + std::to_string(img.seq);
      if (!slam.hasCamera()) {
        status.count("frames_before_camera_info");
        out = slam.skipFrame(img.utime, img.seq);
      } else {
        cv::Mat bgr;
        try {
          // The camera's size is checked before decoding (a frame of another size is refused
          // whatever it holds; the decoder checks the image's own header against the message).
          bgr = decodeImageMessage(img, what, false,
                                   cv::Size(slam.camera().width(), slam.camera().height()));
        } catch (const ImageSizeError& e) {
          bus.reject(ch.camera, e.what());
          status.count("frames_wrong_size");
        } catch (const ImageError& e) {
          bus.reject(ch.camera, e.what());
          status.count("frames_corrupt");
        }
        out = bgr.empty() ? slam.skipFrame(img.utime, img.seq)
                          : slam.processFrame(img.utime, img.seq, bgr);
      }
      publish(bus, ch, out, status);
      status.addProcessed();
    };

    status.setState(StatusReporter::State::kRunning);
    status.publish();
    spdlog::info("{} on {}", lockstep ? "lockstep" : "real time", sys.bus.url);
    int64_t last_utime = 0;
    int32_t last_seq = -1;
    const int rc = runInputLoop(
        bus, status, pending, lockstep,
        [&](const image_t& img) {
          last_utime = img.utime;
          last_seq = img.seq;
          handleFrame(img);
        },
        [&] {
          if (!lockstep && slam.hasCamera())
            publish(bus, ch, slam.collectBackground(last_utime, last_seq), status);
          reportStats(slam, status);
        });
    slam.flush();
    status.setState(StatusReporter::State::kStopping);
    reportStats(slam, status);
    status.publish();
    const SlamStats s = slam.stats();
    spdlog::info(
        "handled {} frames: {} located, {} lost, {} relocalisations, {} re-initialisations, {} "
        "maps",
        s.frames + s.frames_unusable, s.frames_located, s.frames_lost, s.relocalizations,
        s.reinitializations, s.maps);
    return rc;
  });
}
