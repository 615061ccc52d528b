// slamaware-bench-slam: costs of the SLAM stage on 640x480 frames. Renders (or reads) a sequence
// first, then runs the SLAM library lockstep over it and reports the median time to track a frame
// (features + tracking: what the camera-rate thread pays), the median depth-filter update per
// frame (its own thread) and the median local bundle adjustment per keyframe (the mapping thread).
// Writes a flat JSON object for `make bench`.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core/utility.hpp>

#include "common/config.h"
#include "common/frame_source.h"
#include "procs/slam/slam_options.h"
#include "procs/slam/slam_system.h"
#include "tools/synth/synth_source.h"

using namespace slamaware;
using namespace slamaware::slam;

namespace {
double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}
double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(p * v.size()))];
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"slamaware-bench-slam: SLAM tracking and depth-filter times on 640x480 frames"};
  std::string out, source = "synth:config/scenes/sample.yaml", config;
  int64_t max_frames = -1;
  app.add_option("--out", out, "JSON file to write")->required();
  app.add_option("--source", source, "frames: a sequence folder or synth:CONFIG (rendered first)");
  app.add_option("--config", config, "SLAM options (default: built-in, as config/slam.yaml)");
  app.add_option("--frames", max_frames, "use the first N frames (-1: all)");
  CLI11_PARSE(app, argc, argv);
  spdlog::set_pattern("[%H:%M:%S.%e] [bench-slam] [%^%l%$] %v");
  try {
    synth::registerSynthSource();
    cv::setNumThreads(1);  // as the node
    std::unique_ptr<FrameSource> src = openSource(source, SourceOptions());
    std::vector<SourceFrame> frames;
    SourceFrame f;
    while ((max_frames < 0 || static_cast<int64_t>(frames.size()) < max_frames) && src->next(&f))
      if (f.error.empty()) frames.push_back(f);
    spdlog::info("{}: {} frames {}x{}", src->describe(), frames.size(), src->camera().width(),
                 src->camera().height());

    const SlamOptions options = loadConfig<SlamOptions>(config, "slam", false);
    SlamSystem slam(options, true);
    slam.setCamera(src->camera());
    std::vector<double> track_ms, depth_ms, ba_ms;
    int64_t depth_updates = 0, located = 0, bundle_adjustments = 0;
    double ba_total = 0;
    for (const auto& frame : frames) {
      const SlamOutput o = slam.processFrame(frame.utime, frame.seq, frame.bgr);
      const SlamStats s = slam.stats();
      track_ms.push_back(s.track_ms);
      if (s.depth_updates != depth_updates) depth_ms.push_back(s.depth_update_ms);
      depth_updates = s.depth_updates;
      // Lockstep: a keyframe's mapping ends within its frame's processFrame.
      if (s.bundle_adjustments != bundle_adjustments)
        ba_ms.push_back(s.bundle_adjustment_ms - ba_total);
      bundle_adjustments = s.bundle_adjustments;
      ba_total = s.bundle_adjustment_ms;
      located += o.pose.state == PoseState::kTracking || o.pose.state == PoseState::kRelocalized;
    }
    nlohmann::json j;
    j["slam_track_ms_median"] = median(track_ms);
    j["slam_track_ms_p90"] = percentile(track_ms, 0.9);
    j["depth_filter_ms_median"] = median(depth_ms);
    j["depth_filter_ms_p90"] = percentile(depth_ms, 0.9);
    const SlamStats end = slam.stats();
    j["local_ba_ms_median"] = median(ba_ms);
    j["local_ba_count"] = end.bundle_adjustments;
    j["mapping_ms_total"] = end.mapping_ms;
    j["local_ba_ms_total"] = end.bundle_adjustment_ms;
    j["slam_bench_frames"] = static_cast<int64_t>(frames.size());
    j["slam_bench_frames_located"] = located;
    j["slam_bench_width"] = src->camera().width();
    j["slam_bench_height"] = src->camera().height();
    std::ofstream(out) << j.dump(2) << "\n";
    spdlog::info(
        "track {:.2f} ms median ({:.2f} p90), depth filter {:.2f} ms median per frame ({:.2f} "
        "p90), local BA {:.2f} ms median ({} of them, mapping {:.0f} ms in all), {} of {} located",
        median(track_ms), percentile(track_ms, 0.9), median(depth_ms), percentile(depth_ms, 0.9),
        median(ba_ms), ba_ms.size(), end.mapping_ms, located, frames.size());
    return 0;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
}
