#include "tools/eval/offline_run.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <opencv2/core/utility.hpp>

#include "common/image_codec.h"
#include "procs/slam/slam_system.h"

namespace slamaware {

SlamRecording runSlamOffline(const SequenceFolder& sequence, const slam::SlamOptions& options,
                             bool verbose, OfflineRunStats* stats) {
  SlamRecording run;
  cv::setNumThreads(1);  // as the node does: our own threads are the parallelism
  slam::SlamSystem system(options, true);
  system.setCamera(sequence.info().camera);
  int64_t depth_updates = 0;
  for (size_t i = 0; i < sequence.size(); ++i) {
    const cv::Mat bgr = readImage(sequence.framePath(i));
    const int64_t utime = static_cast<int64_t>(std::llround(sequence.timestamp(i) * 1e6));
    const slam::SlamOutput out = system.processFrame(utime, static_cast<int32_t>(i), bgr);
    const slam::SlamStats st = system.stats();
    if (stats) {
      stats->track_ms.push_back(st.track_ms);
      if (st.depth_updates != depth_updates) stats->depth_ms.push_back(st.depth_update_ms);
      depth_updates = st.depth_updates;
    }
    for (const auto& k : out.keyframes) {
      SlamRecording::Keyframe& r = run.keyframes[k.id];
      r.seq = k.seq;
      r.map_id = k.map_id;
      r.culled = r.culled || k.culled;
      if (!k.culled) r.T_world_camera = k.T_world_camera;
    }
    for (const auto& c : out.clouds) {
      std::vector<SlamRecording::Point> pts;
      pts.reserve(c.points.size());
      for (const auto& p : c.points) pts.push_back({p.p_world, p.keyframe_id, p.depth_std});
      run.addCloud(c.map_id, c.full, c.keyframe_id, std::move(pts));
    }
    run.poses[out.pose.seq] = {static_cast<int8_t>(out.pose.state), out.pose.T_world_camera,
                               out.pose.map_id};
    if (verbose) {
      spdlog::info(
          "seq {:4d} {:12s} map {} tracked {:4d} kfs {:3d} points {:5d} seeds {:6d} dpts {:7d} "
          "track {:.1f} ms (orb {:.1f}) depth {:.1f} ms",
          i, slam::poseStateName(out.pose.state), out.pose.map_id, out.pose.num_tracked,
          st.keyframes, st.points, st.depth_seeds, st.depth_points, st.track_ms, st.extract_ms,
          st.depth_update_ms);
      for (const auto& e : out.events) spdlog::info("  {}", e);
    }
  }
  system.flush();
  return run;
}

}  // namespace slamaware
