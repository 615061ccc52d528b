// slamaware-camera: reads a sequence folder, a video file, a V4L device or the synthetic
// generator, paces the frames (real time, a multiple of it, as fast as possible, or lockstep)
// and publishes CAMERA_INFO and CAMERA.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <thread>

#include "common/bus/bus.h"
#include "common/bus/image_msg.h"
#include "common/bus/lockstep.h"
#include "common/bus/node.h"
#include "common/bus/shutdown.h"
#include "common/bus/status.h"
#include "common/config.h"
#include "procs/camera/camera_options.h"
#include "procs/camera/register_sources.h"
#include "slamaware/camera_info_t.hpp"

using namespace slamaware;
using namespace slamaware::camera;
using Clock = std::chrono::steady_clock;

namespace {

camera_info_t makeInfo(const FrameSource& src, const std::string& frame_id) {
  camera_info_t info{};
  const CameraModel& c = src.camera();
  info.utime = wallUtime();
  info.frame_id = frame_id;
  info.width = c.width();
  info.height = c.height();
  info.fx = c.fx();
  info.fy = c.fy();
  info.cx = c.cx();
  info.cy = c.cy();
  for (int i = 0; i < 5; ++i) info.distortion[i] = c.distortion()[i];
  info.source = src.describe();
  return info;
}

// The wire format of config's camera.pixel_format; a ConfigError naming the file otherwise.
int8_t pixelFormatOf(const CameraOptions& opts, const std::string& config) {
  if (opts.pixel_format == "jpeg") return image_t::PIXEL_FORMAT_JPEG;
  if (opts.pixel_format == "rgb8") return image_t::PIXEL_FORMAT_RGB8;
  throw ConfigError((config.empty() ? std::string("defaults") : config) +
                    ": key 'camera.pixel_format': expected jpeg or rgb8, got '" +
                    opts.pixel_format + "'");
}

// A frame as a CAMERA message: a JPEG file's own bytes when they may pass through, else encoded.
image_t frameMessage(SourceFrame& frame, int8_t format, const CameraOptions& opts) {
  if (format != image_t::PIXEL_FORMAT_JPEG || !opts.passthrough_jpeg || frame.jpeg.empty())
    return makeImageMessage(frame.bgr, frame.utime, frame.seq, format, opts.jpeg_quality);
  image_t msg{};
  msg.utime = frame.utime;
  msg.seq = frame.seq;
  msg.width = frame.bgr.cols;
  msg.height = frame.bgr.rows;
  msg.pixel_format = image_t::PIXEL_FORMAT_JPEG;
  msg.data = std::move(frame.jpeg);
  msg.size = static_cast<int32_t>(msg.data.size());
  return msg;
}

// Pacing against the source's own clock: a frame is due `speed` times faster than its utime says
// after the first frame's (speed 0 or a live device: at once).
class Pacer {
 public:
  Pacer(double speed, bool live) : speed_(live ? 0 : speed) {}
  /// Calls wait(ms) (at most 20 ms each) until the frame of `utime` is due or `stop()`.
  template <class Wait, class Stop>
  void until(int64_t utime, Wait wait, Stop stop) {
    if (!have_first_) {
      have_first_ = true;
      first_utime_ = utime;
      t0_ = Clock::now();
      return;
    }
    if (speed_ <= 0) return;
    const auto due =
        t0_ + std::chrono::microseconds(static_cast<int64_t>((utime - first_utime_) / speed_));
    while (Clock::now() < due && !stop()) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(due - Clock::now()).count();
      wait(static_cast<int>(std::clamp<int64_t>(left, 0, 20)));
    }
  }

 private:
  double speed_;
  bool have_first_ = false;
  int64_t first_utime_ = 0;
  Clock::time_point t0_;
};

/// The camera's command line.
struct CameraArgs {
  NodeArgs node;
  std::string source, lockstep_channel, wait_for;
  double speed = 1.0;
  bool loop = false;
  int64_t max_frames = -1;
};

void addCameraOptions(CLI::App& app, CameraArgs* a) {
  addNodeOptions(app, a->node, false);
  app.add_option("--source", a->source,
                 "sequence folder, video file, LCM log (.lcm), v4l:N or synth:CONFIG")
      ->required();
  app.add_option("--speed", a->speed, "1 = real time, 2 = twice as fast, 0 = as fast as possible")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--lockstep", a->lockstep_channel,
                 "publish frame n+1 only after a message with seq n appeared on this channel");
  app.add_option(
      "--wait-for", a->wait_for,
      "comma-separated *_STATUS channels to hear from before the first frame (lockstep start)");
  app.add_flag("--loop", a->loop, "start again at the end of the source");
  app.add_option("--max-frames", a->max_frames, "stop after this many frames (-1: all)");
  addPrintConfigOption(app, [] { return defaultConfigFileText<CameraOptions>("camera"); });
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "slamaware-camera: publishes CAMERA_INFO and CAMERA frames from a sequence folder, a video "
      "file, a V4L device (v4l:N) or the synthetic generator (synth:CONFIG)"};
  CameraArgs args;
  addCameraOptions(app, &args);
  CLI11_PARSE(app, argc, argv);
  NodeArgs& node = args.node;
  const std::string &source = args.source, &lockstep_channel = args.lockstep_channel,
                    &wait_for = args.wait_for;
  double& speed = args.speed;
  const bool loop = args.loop;
  const int64_t max_frames = args.max_frames;

  return runNode("camera", node, [&]() -> int {
    registerBuiltinSourceSchemes();
    const SystemConfig sys = loadSystem(node);
    const CameraOptions opts = loadConfig<CameraOptions>(node.config, "camera");
    const int8_t format = pixelFormatOf(opts, node.config);
    std::unique_ptr<FrameSource> src = openSource(source, opts.source);
    const bool lockstep = !lockstep_channel.empty();
    if (lockstep && speed == 1.0 && !app.count("--speed"))
      speed = 0;  // lockstep alone: as fast as acks come

    Bus bus(sys.bus.url);
    StatusReporter status(bus, node.nameOr("camera"), sys.channels.statusOf(node.nameOr("camera")));
    const Channels& ch = sys.channels;

    std::unique_ptr<LockstepGate> gate;
    if (lockstep)
      gate = std::make_unique<LockstepGate>(bus, lockstep_channel, sys.bus.lockstep_window);
    auto last_info = Clock::now();
    const camera_info_t info = makeInfo(*src, opts.frame_id);
    auto publishInfo = [&]() {
      camera_info_t i = info;
      i.utime = wallUtime();
      bus.publish(ch.camera_info, i);
      last_info = Clock::now();
    };
    const auto info_period = std::chrono::duration<double>(1.0 / std::max(0.01, opts.info_rate_hz));
    auto idle = [&]() {
      status.tick();
      if (Clock::now() - last_info > info_period) publishInfo();
    };

    spdlog::info("source {} ({}x{}, {:.2f} fps, {} frames), speed {}, {}", src->describe(),
                 src->camera().width(), src->camera().height(), src->fps(), src->length(), speed,
                 lockstep ? "lockstep on " + lockstep_channel : std::string("free running"));

    // Start: wait until the listed stages are up (their first heartbeat).
    const auto missing =
        waitForChannels(bus, splitList(wait_for), sys.bus.lockstep_timeout_s, idle);
    for (const auto& c : missing)
      spdlog::warn("no message on {} after {:.0f} s; starting anyway", c,
                   sys.bus.lockstep_timeout_s);
    status.setState(StatusReporter::State::kRunning);
    publishInfo();
    bus.handle(20);  // let CAMERA_INFO go out before the first frame

    SourceFrame frame;
    int64_t published = 0, corrupt = 0, timeouts = 0;
    Pacer pacer(speed, src->live());
    int exit_code = 0;
    while (!shutdownRequested()) {
      if (max_frames >= 0 && published >= max_frames) break;
      // Lockstep: wait until fewer than lockstep_window frames wait for the last stage.
      int32_t unanswered = -1;
      if (gate && !gate->waitForRoom(false, sys.bus.lockstep_timeout_s, idle, &unanswered)) {
        if (shutdownRequested()) break;
        ++timeouts;
        status.count("lockstep_timeouts");
        status.setMessage("lockstep: no answer on " + lockstep_channel + " for seq " +
                          std::to_string(unanswered));
        spdlog::warn("lockstep: no message with seq {} on {} within {:.0f} s; going on", unanswered,
                     lockstep_channel, sys.bus.lockstep_timeout_s);
      }
      if (!src->next(&frame)) {
        if (loop && src->rewind()) continue;
        break;
      }
      if (!frame.error.empty()) {
        ++corrupt;
        status.count("frames_corrupt");
        status.setMessage(frame.error);
        spdlog::warn("skipping frame {}: {}", frame.seq, frame.error);
        continue;
      }
      pacer.until(
          frame.utime,
          [&](int ms) {
            bus.handle(ms);
            idle();
          },
          shutdownRequested);
      const image_t msg = frameMessage(frame, format, opts);
      if (!bus.publish(ch.camera, msg)) {
        exit_code = 1;
        break;
      }
      ++published;
      if (gate) gate->published(frame.seq);
      status.noteInput(frame.utime, frame.seq);
      status.addProcessed();
      bus.handle(0);
      idle();
    }
    // In lockstep, let the pipeline finish the last frame before we go.
    int32_t unanswered = -1;
    while (gate && !shutdownRequested() &&
           !gate->waitForRoom(true, sys.bus.lockstep_timeout_s, idle, &unanswered))
      ++timeouts;
    status.setState(StatusReporter::State::kStopping);
    status.setCounter("frames_published", published);
    status.publish();
    spdlog::info("published {} frames, skipped {} unreadable, {} lockstep timeouts", published,
                 corrupt, timeouts);
    return exit_code;
  });
}
