#include "tools/eval/pipeline_run.h"

#include <signal.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <sstream>
#include <thread>

#include "common/bus/log_reader.h"
#include "common/dataset.h"
#include "procs/supervisor/proc_stats.h"
#include "slamaware/keyframe_t.hpp"
#include "slamaware/point_cloud_t.hpp"
#include "slamaware/pose_t.hpp"
#include "tools/eval/child_process.h"

namespace fs = std::filesystem;

namespace slamaware {

namespace {

using Clock = std::chrono::steady_clock;

double cpuAt(const std::vector<CpuSample>& trace, int64_t t_us) {
  if (trace.empty()) return 0;
  if (t_us <= trace.front().wall_us) return trace.front().cpu_s;
  if (t_us >= trace.back().wall_us) return trace.back().cpu_s;
  const auto after = std::lower_bound(trace.begin(), trace.end(), t_us,
                                      [](const CpuSample& s, int64_t t) { return s.wall_us < t; });
  const auto before = after - 1;
  const double f = static_cast<double>(t_us - before->wall_us) /
                   static_cast<double>(std::max<int64_t>(1, after->wall_us - before->wall_us));
  return before->cpu_s + f * (after->cpu_s - before->cpu_s);
}

SE3 poseOf(const double position[3], const double orientation[4]) {
  return se3FromArrays(position, orientation);
}

}  // namespace

std::vector<PipelineStage> pipelineStages(const Channels& ch) {
  return {{"slam", ch.slam_pose},
          {"proposals", ch.proposals},
          {"recognizer", ch.detections},
          {"objectmap", ch.object_map}};
}

std::vector<std::string> stageList(const std::string& comma_separated) {
  std::vector<std::string> names;
  std::istringstream in(comma_separated);
  for (std::string name; std::getline(in, name, ',');)
    if (!name.empty()) names.push_back(name);
  return names;
}

double cpuSecondsBetween(const std::vector<CpuSample>& trace, int64_t from_us, int64_t to_us) {
  return cpuAt(trace, to_us) - cpuAt(trace, from_us);
}

PipelineRun runPipeline(const std::string& sequence_dir, const std::string& log_path,
                        const SystemConfig& system, const PipelineRunOptions& options) {
  PipelineRun result;
  // The source: a sequence folder, or a recording (.lcm) whose CAMERA messages are played.
  size_t frames = 0;
  if (fs::path(sequence_dir).extension() == ".lcm") {
    LogReader reader(sequence_dir);
    while (auto r = reader.next()) frames += r->channel == system.channels.camera;
  } else {
    frames = SequenceFolder::open(sequence_dir).size();
  }
  std::vector<PipelineStage> stages;
  for (const auto& s : pipelineStages(system.channels)) {
    if (!options.only.empty() &&
        std::find(options.only.begin(), options.only.end(), s.name) == options.only.end())
      continue;
    // Each stage consumes the one before it: the pipeline is the built beginning of the chain.
    if (!fs::exists(fs::path(options.bin_dir) / ("slamaware-" + s.name))) break;
    stages.push_back(s);
  }
  if (stages.empty()) {
    result.error = "no pipeline stage is built in " + options.bin_dir;
    return result;
  }
  result.lockstep_channel = stages.back().output_channel;
  std::string wait_for;
  for (const auto& s : stages) {
    result.stages.push_back(s.name);
    wait_for += (wait_for.empty() ? "" : ",") + system.channels.statusOf(s.name);
  }

  ChildProcess logger({"lcm-logger", "--lcm-url=" + options.lcm_url, "-f", log_path},
                      log_path + ".logger.txt");
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // lcm-logger has no ready signal
  // Every process reads the caller's system.yaml (its channels and scheduling; the bus URL and
  // lockstep mode are given on the command line).
  const std::string& system_yaml = options.system_path;
  std::vector<std::unique_ptr<ChildProcess>> procs;
  for (const auto& s : stages) {
    std::vector<std::string> argv = {(fs::path(options.bin_dir) / ("slamaware-" + s.name)).string(),
                                     "--lcm-url", options.lcm_url, "--log-level", "warn"};
    if (!options.realtime) argv.push_back("--lockstep");
    if (!system_yaml.empty()) argv.insert(argv.end(), {"--system", system_yaml});
    const fs::path config = fs::path(options.config_dir) / (s.name + ".yaml");
    if (fs::exists(config)) {
      argv.push_back("--config");
      argv.push_back(config.string());
    }
    if (s.name == "recognizer" && !options.recognizer_model.empty()) {
      argv.push_back("--model");
      argv.push_back(options.recognizer_model);
    }
    if (s.name == "objectmap" && !options.objectmap_dir.empty()) {
      // Each sequence its own map folder (lockstep starts empty anyway; the saves stay apart).
      fs::create_directories(options.objectmap_dir);
      argv.push_back("--map-dir");
      argv.push_back(options.objectmap_dir);
    }
    procs.push_back(std::make_unique<ChildProcess>(argv, log_path + "." + s.name + ".txt"));
  }
  std::vector<std::string> camera_argv = {(fs::path(options.bin_dir) / "slamaware-camera").string(),
                                          "--source",
                                          sequence_dir,
                                          "--wait-for",
                                          wait_for,
                                          "--lcm-url",
                                          options.lcm_url,
                                          "--log-level",
                                          "warn"};
  if (!system_yaml.empty()) camera_argv.insert(camera_argv.end(), {"--system", system_yaml});
  if (options.realtime) {
    camera_argv.insert(camera_argv.end(), {"--speed", "1"});
  } else {
    camera_argv.insert(camera_argv.end(), {"--lockstep", result.lockstep_channel});
  }
  ChildProcess camera(camera_argv, log_path + ".camera.txt");
  const auto timeout = std::chrono::milliseconds(static_cast<int64_t>(
      1000 * (30 + options.timeout_per_frame_s * std::max<size_t>(1, frames))));
  // Wait for the camera; in real time, sampling every process's CPU time meanwhile.
  const auto sampleCpu = [&] {
    if (!options.realtime) return;
    const int64_t now_us = std::chrono::duration_cast<std::chrono::microseconds>(
                               std::chrono::system_clock::now().time_since_epoch())
                               .count();
    const double tick_s = 1.0 / static_cast<double>(sysconf(_SC_CLK_TCK));
    const auto add = [&](const std::string& name, pid_t pid) {
      if (const auto s = supervisor::sampleProcess(pid))
        result.cpu_trace[name].push_back({now_us, static_cast<double>(s->cpu_ticks) * tick_s});
    };
    add("camera", camera.pid());
    for (size_t i = 0; i < procs.size(); ++i) add(stages[i].name, procs[i]->pid());
  };
  const auto camera_deadline = Clock::now() + timeout;
  int camera_rc = -1;
  do {
    sampleCpu();
    camera_rc = camera.wait(std::chrono::milliseconds(50));
  } while (camera_rc == -1 && Clock::now() < camera_deadline);
  sampleCpu();
  // The last messages reach the logger (in real time, the stages also finish their last frames).
  std::this_thread::sleep_for(std::chrono::milliseconds(options.realtime ? 2000 : 300));
  bool crashed = false;
  for (size_t i = 0; i < procs.size(); ++i) {
    const bool alive = procs[i]->running();
    const int rc = procs[i]->stop(std::chrono::milliseconds(10000));
    if (!alive || (rc != 0 && rc != 128 + SIGINT)) {
      crashed = true;
      result.error += "stage " + stages[i].name +
                      (alive ? " exited with " + std::to_string(rc) : " died early") + "; ";
    }
  }
  logger.stop(std::chrono::milliseconds(3000));
  result.rss_mb_total = static_cast<double>(camera.maxRssKb()) / 1024.0;
  result.cpu_s["camera"] = camera.cpuSeconds();
  for (size_t i = 0; i < procs.size(); ++i) {
    result.rss_mb_total += static_cast<double>(procs[i]->maxRssKb()) / 1024.0;
    result.cpu_s[stages[i].name] = procs[i]->cpuSeconds();
  }
  if (camera_rc != 0) result.error += "camera exited with " + std::to_string(camera_rc) + "; ";
  result.ok = camera_rc == 0 && !crashed;
  return result;
}

SlamRecording readSlamRecording(const std::string& log_path, const Channels& ch) {
  SlamRecording run;
  LogReader reader(log_path);
  while (auto r = reader.next()) {
    if (r->channel == ch.slam_pose) {
      pose_t m;
      if (!decodeRecord(*r, &m)) continue;
      run.poses[m.seq] = {m.state, poseOf(m.position, m.orientation), m.map_id};
    } else if (r->channel == ch.slam_keyframe) {
      keyframe_t m;
      if (!decodeRecord(*r, &m)) continue;
      SlamRecording::Keyframe& k = run.keyframes[m.id];
      k.seq = m.seq;
      k.map_id = m.map_id;
      k.culled = k.culled || m.culled;
      if (!m.culled) k.T_world_camera = poseOf(m.position, m.orientation);
    } else if (r->channel == ch.slam_map) {
      point_cloud_t m;
      if (!decodeRecord(*r, &m)) continue;
      std::vector<SlamRecording::Point> pts(m.num_points);
      for (int i = 0; i < m.num_points; ++i)
        pts[i] = {Eigen::Vector3f(m.x[i], m.y[i], m.z[i]), m.keyframe_ids[i], m.depth_std[i]};
      run.addCloud(m.map_id, m.full, m.keyframe_id, std::move(pts));
    }
  }
  return run;
}

}  // namespace slamaware
