#pragma once
// Runs the multi-process pipeline on one sequence folder, lockstep (or real time), and records the
// bus: lcm-logger, then every stage of the pipeline whose binary is built, then the camera, which
// publishes frame n+1 only after the last stage answered frame n. The stages are a table (the
// order of docs/architecture.md §1) so that later stages join by being built.
#include <map>
#include <string>
#include <vector>

#include "common/bus/system_config.h"
#include "tools/eval/slam_metrics.h"

namespace slamaware {

struct PipelineStage {
  std::string name;            ///< process name: binary slamaware-<name>, heartbeat <NAME>_STATUS
  std::string output_channel;  ///< what it publishes once per frame in lockstep
};

/// Every stage of the pipeline after the camera, in order, with its per-frame output channel.
std::vector<PipelineStage> pipelineStages(const Channels& channels);

/// The stage names of a comma-separated list ("slam,proposals"; "" = none: every built stage).
std::vector<std::string> stageList(const std::string& comma_separated);

struct PipelineRunOptions {
  std::string bin_dir;                ///< where slamaware-* binaries are
  std::string config_dir = "config";  ///< <name>.yaml passed as --config when it exists
  std::string
      system_path;  ///< system.yaml passed to every process as --system ("" = built-in defaults)
  std::string lcm_url;
  std::vector<std::string> only;  ///< stage names to run ("" = every built stage)
  std::string objectmap_dir;      ///< --map-dir of the objectmap stage: a fresh folder per sequence
  std::string recognizer_model;   ///< --model of the recognizer stage ("" = its config's)
  double timeout_per_frame_s = 20.0;
  /// false: lockstep (every stage handles every frame, deterministic); true: the camera plays the
  /// source in real time and the stages keep up as they can (bounded queues, drops counted).
  bool realtime = false;
};

/// A process's CPU time (all threads) at one wall-clock moment.
struct CpuSample {
  int64_t wall_us = 0;  ///< system clock, µs since the epoch (as a recording's event times)
  double cpu_s = 0;
};

/// CPU seconds a process used between two wall-clock moments, interpolated between the samples
/// around each (clamped to the first and last sample).
double cpuSecondsBetween(const std::vector<CpuSample>& trace, int64_t from_us, int64_t to_us);

struct PipelineRun {
  bool ok = false;
  std::string error;
  std::vector<std::string> stages;  ///< the stages that ran
  std::string lockstep_channel;
  double rss_mb_total = 0;  ///< sum of the peak resident memory of the camera and every stage
  std::map<std::string, double> cpu_s;  ///< CPU time (all threads) of the camera and each stage
  /// Real time only: the same, sampled every 50 ms while the camera ran: what each process used
  /// while frames streamed, start-up apart (its start-up is before the camera's first frame).
  std::map<std::string, std::vector<CpuSample>> cpu_trace;
};

/// Runs the pipeline on `sequence_dir` (a sequence folder or an LCM log with CAMERA), recording the
/// bus into `log_path` (process outputs go to <log_path>.<name>.txt).
PipelineRun runPipeline(const std::string& sequence_dir, const std::string& log_path,
                        const SystemConfig& system, const PipelineRunOptions& options);

/// Reads SLAM_POSE, SLAM_KEYFRAME and SLAM_MAP from a recorded log. Throws LogError for a
/// damaged log.
SlamRecording readSlamRecording(const std::string& log_path, const Channels& channels);

}  // namespace slamaware
