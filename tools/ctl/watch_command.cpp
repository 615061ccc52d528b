// slamaware-ctl watch: one live status line of the running pipeline — camera rate, SLAM state,
// tracked frames, proposals per frame, frames recognised and dropped, objects in the map, and the
// objects in view: the last OBJECT_DETECTIONS' objects with their fused labels. On a terminal
// the line is rewritten in place; otherwise one line every --period seconds (for logs).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include "common/bus/bus.h"
#include "common/bus/object_detections_msg.h"
#include "common/bus/shutdown.h"
#include "slamaware/detections_t.hpp"
#include "slamaware/object_detections_t.hpp"
#include "slamaware/object_map_t.hpp"
#include "slamaware/pose_t.hpp"
#include "slamaware/proposals_t.hpp"
#include "slamaware/status_t.hpp"
#include "tools/ctl/ctl_commands.h"
#include "tools/ctl/rate_meter.h"

namespace slamaware {

namespace {

using Clock = std::chrono::steady_clock;

const char* slamStateName(int state) {
  switch (state) {
    case pose_t::STATE_INITIALIZING:
      return "INITIALIZING";
    case pose_t::STATE_TRACKING:
      return "TRACKING";
    case pose_t::STATE_LOST:
      return "LOST";
    case pose_t::STATE_RELOCALIZED:
      return "RELOCALIZED";
    default:
      return "?";
  }
}

struct WatchState {
  RateMeter camera, poses, detections;
  int slam_state = -1, map_id = -1, last_seq = -1;
  int64_t tracked = 0, boxes = 0, proposal_msgs = 0, dropped = 0;
  std::map<std::string, int> labels;  // objects per label (background left out)
  int objects = 0;
  std::string
      in_view;  // the last frame's objects as the map labelled them ("#12 coffee_mug 0.93, ...")
};

std::string statusLine(const WatchState& s, double elapsed_s, Clock::time_point now) {
  char head[512];
  std::snprintf(
      head, sizeof(head),
      "%5.0f s | camera %4.1f fps seq %d | SLAM %s map %d, %lld/%lld tracked | %.1f boxes/frame "
      "| recognised %4.1f Hz, %lld dropped | %d objects",
      elapsed_s, s.camera.hz(now), s.last_seq, s.slam_state < 0 ? "-" : slamStateName(s.slam_state),
      s.map_id, static_cast<long long>(s.tracked), static_cast<long long>(s.poses.count()),
      s.proposal_msgs ? static_cast<double>(s.boxes) / static_cast<double>(s.proposal_msgs) : 0.0,
      s.detections.hz(now), static_cast<long long>(s.dropped), s.objects);
  std::string line = head;
  std::string sep = ": ";
  for (const auto& [label, n] : s.labels) {
    line += sep + label + (n > 1 ? " x" + std::to_string(n) : "");
    sep = ", ";
  }
  if (!s.in_view.empty()) line += " | in view: " + s.in_view;
  return line;
}

int runWatch(const NodeArgs& node, double duration_s, double period_s) {
  const SystemConfig sys = loadSystem(node);
  const Channels& ch = sys.channels;
  Bus bus(sys.bus.url);
  WatchState s;
  // The camera's images are large: only their arrival is counted, never decoded.
  bus.subscribeRaw(
      ch.camera, [&](const Bus::RawMessage&) { s.camera.tick(Clock::now()); },
      static_cast<size_t>(sys.bus.max_image_bytes));
  bus.subscribe<pose_t>(ch.slam_pose, [&](const pose_t& p) {
    s.poses.tick(Clock::now());
    s.slam_state = p.state;
    s.map_id = p.map_id;
    s.last_seq = p.seq;
    s.tracked += p.state == pose_t::STATE_TRACKING || p.state == pose_t::STATE_RELOCALIZED;
  });
  bus.subscribe<proposals_t>(ch.proposals, [&](const proposals_t& p) {
    ++s.proposal_msgs;
    s.boxes += p.num_boxes;
  });
  bus.subscribe<detections_t>(ch.detections,
                              [&](const detections_t&) { s.detections.tick(Clock::now()); });
  bus.subscribe<object_detections_t>(ch.object_detections, [&](const object_detections_t& d) {
    s.in_view.clear();
    for (size_t i = 0; i < d.labels.size(); ++i)
      if (isLabelledObject(d, i))
        s.in_view += (s.in_view.empty() ? "" : ", ") + objectLabelText(d, i);
  });
  bus.subscribe<status_t>(ch.statusOf("recognizer"),
                          [&](const status_t& st) { s.dropped = st.frames_dropped; });
  bus.subscribe<object_map_t>(
      ch.object_map,
      [&](const object_map_t& m) {
        s.labels.clear();
        s.objects = 0;
        for (const auto& o : m.objects) {
          if (o.label == "background") continue;
          ++s.objects;
          ++s.labels[o.label];
        }
      },
      static_cast<size_t>(sys.bus.max_map_bytes));
  const bool tty = isatty(STDOUT_FILENO) != 0;
  if (tty) period_s = std::min(period_s, 0.5);
  const auto start = Clock::now();
  auto last_print = start;
  std::string line;
  while (!shutdownRequested()) {
    bus.handle(100);
    const auto now = Clock::now();
    const double elapsed = std::chrono::duration<double>(now - start).count();
    if (duration_s > 0 && elapsed >= duration_s) break;
    if (now - last_print >= std::chrono::duration<double>(period_s)) {
      last_print = now;
      line = statusLine(s, elapsed, now);
      if (tty)
        std::printf("\r\033[K%s", line.c_str());
      else
        std::printf("%s\n", line.c_str());
      std::fflush(stdout);
    }
  }
  std::printf(
      "%s%s\n", tty ? "\r\033[K" : "",
      statusLine(s, std::chrono::duration<double>(Clock::now() - start).count(), Clock::now())
          .c_str());
  return 0;
}

}  // namespace

void addWatchCommand(CLI::App& app, CtlContext& ctx) {
  auto* cmd = app.add_subcommand("watch",
                                 "one live status line: camera fps, SLAM state, boxes per frame, "
                                 "recognised/dropped frames, objects");
  auto duration = std::make_shared<double>(0.0);
  auto period = std::make_shared<double>(5.0);
  cmd->add_option("--duration", *duration, "s to watch (0: until Ctrl-C)");
  cmd->add_option(
      "--period", *period,
      "s between lines when the output is not a terminal (a terminal: 0.5 s, in place)");
  cmd->callback([&ctx, duration, period]() {
    ctx.exit_code =
        runNode("ctl", ctx.node, [&]() { return runWatch(ctx.node, *duration, *period); });
  });
}

}  // namespace slamaware
