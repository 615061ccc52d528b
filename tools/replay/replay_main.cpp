// slamaware-replay: plays an LCM log back onto the bus, in real time (like lcm-logplayer) or
// lockstep: each CAMERA message waits until the last stage has answered the previous frame, so
// that the same log gives the same outputs, byte for byte (docs/architecture.md §4).
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <regex>

#include "common/bus/bus.h"
#include "common/bus/frame_stamp.h"
#include "common/bus/lockstep.h"
#include "common/bus/log_reader.h"
#include "common/bus/node.h"
#include "common/bus/shutdown.h"
#include "common/bus/status.h"

using namespace slamaware;
using Clock = std::chrono::steady_clock;

int main(int argc, char** argv) {
  CLI::App app{
      "slamaware-replay: replays an LCM log in real time or in lockstep with the pipeline"};
  NodeArgs node;
  std::string log_path, lockstep_channel, wait_for;
  std::string channels = ".*", exclude = "(.*_STATUS|PROC_.*)";
  double speed = 1.0;
  int64_t max_frames = -1;
  addNodeOptions(app, node, false);
  app.add_option("log", log_path, "LCM log file (lcm-logger format)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--speed", speed, "real-time factor (0: as fast as possible)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--lockstep", lockstep_channel,
                 "lockstep: each CAMERA frame waits for the previous frame's seq on this channel");
  app.add_option("--wait-for", wait_for,
                 "comma-separated channels to hear from before the first event");
  app.add_option("--channels", channels, "regular expression of channels to play");
  app.add_option("--exclude", exclude,
                 "regular expression of channels not to play (heartbeats by default)");
  app.add_option("--max-frames", max_frames, "stop after this many CAMERA frames (-1: all)");
  CLI11_PARSE(app, argc, argv);

  return runNode("replay", node, [&]() -> int {
    const SystemConfig sys = loadSystem(node);
    const std::regex keep(channels), drop(exclude);
    LogReader reader(log_path);
    Bus bus(sys.bus.url);
    StatusReporter status(bus, node.nameOr("replay"), sys.channels.statusOf(node.nameOr("replay")));
    auto idle = [&]() { status.tick(); };
    const bool lockstep = !lockstep_channel.empty();
    std::unique_ptr<LockstepGate> gate;
    if (lockstep) {
      gate = std::make_unique<LockstepGate>(bus, lockstep_channel, sys.bus.lockstep_window);
      if (!app.count("--speed")) speed = 0;
    }
    for (const auto& c :
         waitForChannels(bus, splitList(wait_for), sys.bus.lockstep_timeout_s, idle))
      spdlog::warn("no message on {} after {:.0f} s; starting anyway", c,
                   sys.bus.lockstep_timeout_s);
    status.setState(StatusReporter::State::kRunning);

    int64_t events = 0, frames = 0, timeouts = 0, first_ts = -1;
    const auto t0 = Clock::now();
    int rc = 0;
    try {
      while (!shutdownRequested()) {
        std::optional<LogRecord> ev = reader.next();
        if (!ev) break;
        if (!std::regex_match(ev->channel, keep) || std::regex_match(ev->channel, drop)) continue;
        if (first_ts < 0) first_ts = ev->timestamp;
        const bool is_frame = ev->channel == sys.channels.camera;
        if (is_frame && max_frames >= 0 && frames >= max_frames) break;
        int32_t unanswered = -1;
        if (is_frame && gate &&
            !gate->waitForRoom(false, sys.bus.lockstep_timeout_s, idle, &unanswered)) {
          if (shutdownRequested()) break;
          ++timeouts;
          status.count("lockstep_timeouts");
          spdlog::warn("lockstep: no message with seq {} on {} within {:.0f} s; going on",
                       unanswered, lockstep_channel, sys.bus.lockstep_timeout_s);
        }
        if (speed > 0) {
          const auto due = t0 + std::chrono::microseconds(
                                    static_cast<int64_t>((ev->timestamp - first_ts) / speed));
          while (Clock::now() < due && !shutdownRequested()) {
            const auto left =
                std::chrono::duration_cast<std::chrono::milliseconds>(due - Clock::now()).count();
            bus.handle(static_cast<int>(std::clamp<int64_t>(left, 0, 20)));
            idle();
          }
        }
        if (!bus.publishRaw(ev->channel, ev->data.data(), ev->data.size())) {
          rc = 1;
          break;
        }
        ++events;
        if (is_frame) {
          ++frames;
          if (auto s = peekFrameStamp(ev->data.data(), ev->data.size())) {
            if (gate) gate->published(s->seq);
            status.noteInput(s->utime, s->seq);
          }
          status.addProcessed();
        }
        bus.handle(0);
        idle();
      }
    } catch (const LogError& e) {
      spdlog::error("{}", e.what());
      rc = 3;
    }
    int32_t unanswered = -1;
    while (gate && !shutdownRequested() &&
           !gate->waitForRoom(true, sys.bus.lockstep_timeout_s, idle, &unanswered))
      ++timeouts;
    status.setState(StatusReporter::State::kStopping);
    status.publish();
    spdlog::info("replayed {} events ({} frames), {} lockstep timeouts", events, frames, timeouts);
    return rc;
  });
}
