// slamaware-proposals: object candidates from the semi-dense map, projected into every frame.
// Reads CAMERA_INFO, SLAM_MAP (clusters again when the map changed), SLAM_POSE and SLAM_KEYFRAME;
// publishes one PROPOSALS per SLAM_POSE (empty when the frame is not localised or nothing is in
// view), and one more, later, for a keyframe whose frame got none (a map's reference frame).
#include <malloc.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <deque>

#include "common/bus/bus.h"
#include "common/bus/input_loop.h"
#include "common/bus/node.h"
#include "common/bus/shutdown.h"
#include "common/bus/status.h"
#include "common/config.h"
#include "common/heap.h"
#include "procs/proposals/proposal_engine.h"

using namespace slamaware;
using namespace slamaware::proposals;

int main(int argc, char** argv) {
  CLI::App app{
      "slamaware-proposals: object candidates from the SLAM map (CAMERA_INFO, SLAM_MAP, SLAM_POSE, "
      "SLAM_KEYFRAME -> PROPOSALS)"};
  NodeArgs node;
  addNodeOptions(app, node);
  addPrintConfigOption(app, [] { return defaultConfigFileText<ProposalOptions>("proposals"); });
  CLI11_PARSE(app, argc, argv);

  return runNode("proposals", node, [&]() -> int {
    const SystemConfig sys = loadSystem(node);
    const ProposalOptions opts = loadConfig<ProposalOptions>(node.config, "proposals");
    const bool lockstep = sys.bus.lockstep;
    // A re-clustering works on every point of the map at several scales (about 15 MB on a 100k
    // point map) and frees it all; while SLAM builds the map it runs four times a second. Its
    // buffers come from the heap (each is far under the threshold, fixed at glibc's largest,
    // 32 MB): mapping each one apart and unmapping it again cost a fifth of the stage's CPU on a
    // first pass. The trim after each re-clustering hands their pages back, so the RSS does not
    // swing with the time since the last one (docs/experiments/proposals.md, 2026-12-05 and
    // 2026-12-07).
    mapBlocksApartFrom(32u << 20);
    const Channels& ch = sys.channels;
    Bus bus(sys.bus.url);
    StatusReporter status(bus, node.nameOr("proposals"), ch.statusOf(node.nameOr("proposals")));
    // Real time: clustering on a worker thread, so that no frame's boxes wait for it.
    ProposalEngine engine(opts, /*background_clustering=*/!lockstep);

    bus.subscribe<camera_info_t>(
        ch.camera_info,
        [&](const camera_info_t& info) {
          std::string why;
          if (!engine.onCameraInfo(info, &why)) bus.reject(ch.camera_info, why);
        },
        sys.bus.max_message_bytes);
    bus.subscribe<point_cloud_t>(
        ch.slam_map,
        [&](const point_cloud_t& c) {
          std::string why;
          if (!engine.onMap(c, &why)) bus.reject(ch.slam_map, why);
        },
        sys.bus.max_map_bytes);
    bus.subscribe<keyframe_t>(
        ch.slam_keyframe, [&](const keyframe_t& k) { engine.onKeyframe(k); },
        sys.bus.max_message_bytes);
    std::deque<pose_t> pending;
    bus.subscribe<pose_t>(
        ch.slam_pose, [&](const pose_t& p) { pending.push_back(p); }, sys.bus.max_message_bytes);

    auto handlePose = [&](const pose_t& pose) {
      status.noteInput(pose.utime, pose.seq);
      std::string why;
      bool reclustered = false;
      const proposals_t out = engine.onPose(pose, &why, &reclustered);
      if (!why.empty()) bus.reject(ch.slam_pose, why);
      if (reclustered) {
        const ClusterStats& s = engine.map().stats();
        status.setCounter("map_points", s.input_points);
        status.setCounter("candidates", s.clusters);
        status.setCounter("retired_candidates", s.retired);
        status.setCounter("retired_points", s.retired_points);
        status.setCounter("support", s.support ? 1 : 0);
        status.setCounter("recluster_ms", static_cast<int64_t>(s.ms));
        status.count("reclusters");
        // Its buffers leave free pages inside the heaps: handed back at once.
        malloc_trim(0);
        spdlog::debug(
            "map {}: {} points, {} single-view, {} seen through, planes {}, {} clustered -> {} "
            "candidates in {:.0f} ms",
            engine.map().mapId(), s.input_points, s.single_view, s.seen_through, s.plane_points,
            s.clustered_points, s.clusters, s.ms);
      }
      // A keyframe's late proposals first: in lockstep the frame's answer then comes after theirs.
      for (const proposals_t& late : engine.takeLateProposals()) {
        bus.publish(ch.proposals, late);
        status.count("late_keyframe_proposals");
      }
      bus.publish(ch.proposals, out);
      status.setCounter("boxes_last_frame", out.num_boxes);
      status.addProcessed();
    };

    status.setState(StatusReporter::State::kRunning);
    status.publish();
    spdlog::info("{} on {}", lockstep ? "lockstep" : "real time", sys.bus.url);
    const int rc = runInputLoop(bus, status, pending, lockstep, handlePose, [] {});
    status.setState(StatusReporter::State::kStopping);
    status.publish();
    return rc;
  });
}
