// slamaware-bench-system: the whole pipeline as separate processes (camera, slam, proposals,
// recognizer, objectmap) on a recording (default: the bundled logs/sample.lcm), run inside
// scripts/netns-run:
//   lockstep:  every stage on every frame -> pipeline_lockstep_fps (CAMERA of the first frame to
//              OBJECT_MAP of the last, on the logger's clock; it bounds how fast `make eval` runs);
//   real time: the camera plays the recording at its own rate (30 Hz) and every stage keeps up as
//              it can -> realtime_slam_fps (frames SLAM answered per second of camera stream),
//              realtime_slam_located_pct (its poses that are located, not lost),
//              realtime_recognizer_hz (frames answered per second; the recognizer classifies the
//              newest frame and answers those it overtook without classifying:
//              realtime_frames_answered_without_pixels, realtime_boxes_unlabelled_pct of their
//              boxes had no earlier result and were left out), realtime_frames_labelled_pct (frames
//              with boxes whose DETECTIONS came), realtime_boxes_classified_pct (published boxes
//              classified in their frame; the others carried an earlier view's result),
//              latency_ms_p95 (CAMERA to the frame's DETECTIONS; _new_views: frames with a box
//              classified in them),
//              rss_mb_total (sum of the processes' peak resident memory), realtime_cpu_cores
//              (each process's CPU time from the first frame to the last, per second; _total: their
//              sum; _with_startup: the whole process's CPU time per second of stream);
// and lockstep_slam_work / realtime_slam_work: SLAM's keyframes, bundle adjustments, semi-dense
// points and depth-filter frames skipped (its last SLAM_STATUS): what a CPU-starved SLAM gives up.
// Times are the logger's receive times of the messages, so process start-up is not counted.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "common/bus/log_reader.h"
#include "common/bus/system_config.h"
#include "slamaware/detections_t.hpp"
#include "slamaware/image_t.hpp"
#include "slamaware/pose_t.hpp"
#include "slamaware/proposals_t.hpp"
#include "slamaware/status_t.hpp"
#include "tools/eval/pipeline_run.h"

using namespace slamaware;
namespace fs = std::filesystem;

namespace {

/// What the recording of one run says, on the logger's clock (µs).
struct RunTimes {
  std::map<int32_t, int64_t> camera, pose, proposals, detections;  ///< seq -> first receive time
  std::map<int32_t, int64_t>
      new_views;  ///< seq -> receive time, DETECTIONS with a box classified in it
  int64_t proposals_with_boxes = 0;  ///< PROPOSALS messages with at least one box
  int64_t labelled = 0;              ///< of them, frames whose DETECTIONS came
  int64_t boxes_classified = 0,
          boxes_carried = 0;  ///< published boxes classified in their frame / carried
  int64_t poses_located = 0;  ///< SLAM_POSE in TRACKING or RELOCALIZED
  int64_t first_camera = -1, last_camera = -1, last_object_map = -1;
  std::map<std::string, int64_t> slam_counters;        ///< of SLAM's last SLAM_STATUS
  std::map<std::string, int64_t> recognizer_counters;  ///< of the last RECOGNIZER_STATUS
};

RunTimes readRun(const std::string& log_path, const Channels& ch) {
  RunTimes t;
  std::set<int32_t> with_boxes;
  LogReader reader(log_path);
  const std::string slam_status = ch.statusOf("slam");
  const std::string recognizer_status = ch.statusOf("recognizer");
  while (auto r = reader.next()) {
    if (r->channel == slam_status || r->channel == recognizer_status) {
      status_t m;
      if (!decodeRecord(*r, &m)) continue;
      auto& counters = r->channel == slam_status ? t.slam_counters : t.recognizer_counters;
      for (int i = 0; i < m.num_counters; ++i)
        counters[m.counter_names[static_cast<size_t>(i)]] =
            m.counter_values[static_cast<size_t>(i)];
      continue;
    }
    if (r->channel == ch.camera) {
      image_t m;
      if (!decodeRecord(*r, &m)) continue;
      t.camera.emplace(m.seq, r->timestamp);
      if (t.first_camera < 0) t.first_camera = r->timestamp;
      t.last_camera = r->timestamp;
    } else if (r->channel == ch.slam_pose) {
      pose_t m;
      if (!decodeRecord(*r, &m)) continue;
      t.pose.emplace(m.seq, r->timestamp);
      t.poses_located += m.state == pose_t::STATE_TRACKING || m.state == pose_t::STATE_RELOCALIZED;
    } else if (r->channel == ch.proposals) {
      proposals_t m;
      if (!decodeRecord(*r, &m)) continue;
      t.proposals.emplace(m.seq, r->timestamp);
      if (m.num_boxes > 0) with_boxes.insert(m.seq);
    } else if (r->channel == ch.detections) {
      detections_t m;
      if (!decodeRecord(*r, &m)) continue;
      t.detections.emplace(m.seq, r->timestamp);
      t.labelled += with_boxes.count(m.seq) > 0;
      int classified = 0;
      for (int32_t s : m.classified_seq) classified += s == m.seq;
      t.boxes_classified += classified;
      t.boxes_carried += m.num_boxes - classified;
      if (classified > 0) t.new_views.emplace(m.seq, r->timestamp);
    } else if (r->channel == ch.object_map) {
      t.last_object_map = r->timestamp;
    }
  }
  t.proposals_with_boxes = static_cast<int64_t>(with_boxes.size());
  return t;
}

/// Per frame answered by both stages: ms from `from`'s message to `to`'s.
std::vector<double> delays(const std::map<int32_t, int64_t>& from,
                           const std::map<int32_t, int64_t>& to) {
  std::vector<double> ms;
  for (const auto& [seq, t] : to) {
    auto f = from.find(seq);
    if (f != from.end()) ms.push_back(1e-3 * static_cast<double>(t - f->second));
  }
  return ms;
}

/// Of the published boxes, the share classified in their own frame (the others carried the
/// result of an earlier view: procs/recognizer/view_selector.h).
double classifiedPct(const RunTimes& t) {
  const int64_t n = t.boxes_classified + t.boxes_carried;
  return n > 0 ? 100.0 * static_cast<double>(t.boxes_classified) / static_cast<double>(n) : 0;
}

/// What SLAM built in a run: a real-time run starved of CPU skips depth-filter frames (fewer
/// semi-dense points for the proposals) and makes fewer keyframes.
nlohmann::json slamWork(const RunTimes& t) {
  nlohmann::json j;
  for (const char* k : {"keyframes", "bundle_adjustments", "depth_points", "depth_frames_skipped"})
    if (auto it = t.slam_counters.find(k); it != t.slam_counters.end()) j[k] = it->second;
  return j;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())))];
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"slamaware-bench-system: the whole pipeline, lockstep and in real time"};
  std::string out, source = "logs/sample.lcm", work;
  std::string bin_dir = fs::path(argv[0]).parent_path().string();
  std::string config_dir = "config", stages, system_path;
  app.add_option("--out", out, "JSON file to write")->required();
  app.add_option("--source", source, "recording (.lcm with CAMERA) or sequence folder");
  app.add_option("--bin-dir", bin_dir, "where the slamaware-* binaries are");
  app.add_option("--config-dir", config_dir, "the processes' <name>.yaml");
  app.add_option("--system", system_path,
                 "system.yaml of every process (default: <config-dir>/system.yaml)");
  app.add_option("--stages", stages, "comma-separated stages to run (default: every built stage)");
  app.add_option("--work-dir", work, "recordings of the runs (default: beside --out)");
  CLI11_PARSE(app, argc, argv);
  if (work.empty()) work = (fs::path(out).parent_path() / "system").string();
  fs::create_directories(work);

  if (system_path.empty() && fs::exists(fs::path(config_dir) / "system.yaml"))
    system_path = (fs::path(config_dir) / "system.yaml").string();
  // The bus (ttl=0) inside the bench's network namespace; the processes' scheduling.
  const SystemConfig sys = loadSystemConfig(system_path, false);
  PipelineRunOptions options;
  options.bin_dir = bin_dir;
  options.config_dir = config_dir;
  options.system_path = system_path;
  options.lcm_url = sys.bus.url;
  options.only = stageList(stages);
  nlohmann::json j;
  j["system_source"] = source;

  // Lockstep.
  options.objectmap_dir = work + "/map-lockstep";
  fs::remove_all(options.objectmap_dir);
  const std::string lockstep_log = work + "/lockstep.lcm";
  PipelineRun run = runPipeline(source, lockstep_log, sys, options);
  if (!run.ok) {
    std::fprintf(stderr, "lockstep run failed: %s (outputs: %s.<stage>.txt)\n", run.error.c_str(),
                 lockstep_log.c_str());
    return 1;
  }
  const RunTimes lock = readRun(lockstep_log, sys.channels);
  const double lock_s = 1e-6 * static_cast<double>(lock.last_object_map - lock.first_camera);
  j["system_frames"] = lock.camera.size();
  j["pipeline_lockstep_fps"] = lock_s > 0 ? static_cast<double>(lock.camera.size()) / lock_s : 0;
  j["lockstep_slam_work"] = slamWork(lock);
  j["lockstep_boxes_classified_pct"] = classifiedPct(lock);

  // Real time.
  options.realtime = true;
  options.objectmap_dir = work + "/map-realtime";
  fs::remove_all(options.objectmap_dir);
  const std::string realtime_log = work + "/realtime.lcm";
  run = runPipeline(source, realtime_log, sys, options);
  if (!run.ok) {
    std::fprintf(stderr, "real-time run failed: %s (outputs: %s.<stage>.txt)\n", run.error.c_str(),
                 realtime_log.c_str());
    return 1;
  }
  const RunTimes rt = readRun(realtime_log, sys.channels);
  // The stream lasts from the first to the last frame, plus one frame period.
  const double n = static_cast<double>(rt.camera.size());
  const double stream_s =
      n > 1 ? 1e-6 * static_cast<double>(rt.last_camera - rt.first_camera) * n / (n - 1) : 0;
  const std::vector<double> latency = delays(rt.camera, rt.detections);
  j["realtime_camera_fps"] = stream_s > 0 ? n / stream_s : 0;
  j["realtime_slam_fps"] = stream_s > 0 ? static_cast<double>(rt.pose.size()) / stream_s : 0;
  j["realtime_slam_frames_missed"] =
      static_cast<int64_t>(rt.camera.size()) - static_cast<int64_t>(rt.pose.size());
  // Keeping up is not enough: starved of CPU, local mapping falls behind and tracking thins out
  // until it is lost (the same recording lockstep is located throughout).
  j["realtime_slam_located_pct"] = rt.pose.empty() ? 0
                                                   : 100.0 * static_cast<double>(rt.poses_located) /
                                                         static_cast<double>(rt.pose.size());
  j["realtime_slam_work"] = slamWork(rt);
  j["realtime_recognizer_hz"] =
      stream_s > 0 ? static_cast<double>(rt.detections.size()) / stream_s : 0;
  j["latency_ms_p95"] = percentile(latency, 0.95);
  j["latency_ms_median"] = percentile(latency, 0.5);
  // Every frame with boxes should get its labels (classified or carried), and a new view its
  // classification promptly.
  j["realtime_frames_labelled_pct"] =
      rt.proposals_with_boxes > 0
          ? 100.0 * static_cast<double>(rt.labelled) / static_cast<double>(rt.proposals_with_boxes)
          : 0;
  j["realtime_boxes_classified_pct"] = classifiedPct(rt);
  // Frames a newer one overtook are answered without classifying (their candidates' last
  // results); a box whose candidate had none is left out of its frame.
  const auto counter = [&](const char* k) {
    const auto it = rt.recognizer_counters.find(k);
    return it == rt.recognizer_counters.end() ? int64_t{0} : it->second;
  };
  j["realtime_frames_answered_without_pixels"] = counter("frames_carried");
  const int64_t unlabelled = counter("boxes_unlabelled");
  const int64_t boxes = counter("boxes_classified") + counter("boxes_carried") + unlabelled;
  j["realtime_boxes_unlabelled_pct"] =
      boxes > 0 ? 100.0 * static_cast<double>(unlabelled) / static_cast<double>(boxes) : 0;
  j["latency_ms_p95_new_views"] = percentile(delays(rt.camera, rt.new_views), 0.95);
  // Where the latency goes (median and p95 of each hop).
  const std::vector<std::pair<std::string, std::vector<double>>> hops = {
      {"camera_to_slam_pose", delays(rt.camera, rt.pose)},
      {"slam_pose_to_proposals", delays(rt.pose, rt.proposals)},
      {"proposals_to_detections", delays(rt.proposals, rt.detections)}};
  for (const auto& [name, ms] : hops) {
    j["latency_breakdown_ms"][name] = {{"median", percentile(ms, 0.5)},
                                       {"p95", percentile(ms, 0.95)}};
  }
  j["rss_mb_total"] = run.rss_mb_total;
  // CPU each process used while the frames streamed (first to last frame), per second: where the
  // cores go at 30 Hz. With its start-up (loading, warming up; a sample of seconds makes it a
  // large share) as before: the process's whole CPU time per second of stream.
  double total = 0;
  const double window_s = 1e-6 * static_cast<double>(rt.last_camera - rt.first_camera);
  for (const auto& [name, trace] : run.cpu_trace) {
    const double cores =
        window_s > 0 ? cpuSecondsBetween(trace, rt.first_camera, rt.last_camera) / window_s : 0;
    j["realtime_cpu_cores"][name] = cores;
    total += cores;
  }
  j["realtime_cpu_cores_total"] = total;
  for (const auto& [name, s] : run.cpu_s)
    j["realtime_cpu_cores_with_startup"][name] = stream_s > 0 ? s / stream_s : 0;
  std::ofstream f(out);
  f << j.dump(2) << "\n";
  std::printf("%s\n", j.dump(2).c_str());
  return f ? 0 : 1;
}
