// slamaware-eval: runs the pipeline (the processes that exist: camera -> slam -> ...) lockstep on
// each sequence folder, records the bus, and computes the report sections of the stages from the
// recording and the ground truth (DESIGN.md §7): for now the "slam" section of every sequence, and
// "overall" over the synthetic suite, plus a top-down trajectory plot per sequence. Runs inside a
// private network namespace (scripts/eval). --offline runs the SLAM library in-process instead
// (no bus; for development).
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "common/bus/log_reader.h"
#include "common/bus/system_config.h"
#include "common/config.h"
#include "common/dataset.h"
#include "procs/slam/slam_options.h"
#include "tools/eval/offline_run.h"
#include "tools/eval/pipeline_run.h"
#include "tools/eval/slam_metrics.h"

using namespace slamaware;
namespace fs = std::filesystem;

namespace {

std::string selfDir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(".") : exe.parent_path().string();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "slamaware-eval: the pipeline on sequence folders, lockstep, scored against ground truth"};
  std::string out, out_dir = "build/eval", system_path, slam_config, stages, log_level = "info";
  std::vector<std::string> sequences;
  bool offline = false, verbose = false;
  PipelineRunOptions pipeline;
  pipeline.bin_dir = selfDir();
  app.add_option("sequences", sequences, "sequence folders")->required();
  app.add_option("--out", out, "JSON fragment to write")->required();
  app.add_option("--out-dir", out_dir, "folder for recordings and plots");
  app.add_option("--system", system_path, "system.yaml (bus URL, channels)");
  app.add_option("--lcm-url", pipeline.lcm_url, "bus URL (default: the system's)");
  app.add_option("--config-dir", pipeline.config_dir, "folder of the processes' <name>.yaml");
  app.add_option("--stages", stages, "comma-separated stages to run (default: every built stage)");
  app.add_flag("--offline", offline, "run the SLAM library in-process instead of the processes");
  app.add_option("--slam-config", slam_config,
                 "offline: SLAM options file (default: <config-dir>/slam.yaml)");
  app.add_flag("--verbose", verbose, "offline: a line per frame");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error");
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::from_str(log_level));
  spdlog::set_pattern("[%H:%M:%S.%e] [eval] [%^%l%$] %v");

  try {
    const SystemConfig system = loadSystemConfig(system_path, false);
    if (pipeline.lcm_url.empty()) pipeline.lcm_url = system.bus.url;
    for (const auto& s : CLI::detail::split(stages, ','))
      if (!s.empty()) pipeline.only.push_back(s);
    fs::create_directories(fs::path(out_dir) / "plots");
    fs::create_directories(fs::path(out_dir) / "logs");
    SlamOptions slam_options;
    if (offline) {
      if (slam_config.empty() && fs::exists(fs::path(pipeline.config_dir) / "slam.yaml"))
        slam_config = (fs::path(pipeline.config_dir) / "slam.yaml").string();
      slam_options = loadConfig<SlamOptions>(slam_config, "slam", false);
    }

    nlohmann::json report = nlohmann::json::object();
    std::vector<nlohmann::json> synthetic;
    int failures = 0;
    for (const auto& dir : sequences) {
      const std::string name = fs::path(dir).filename().string();
      nlohmann::json section;
      try {
        const SequenceFolder seq = SequenceFolder::open(dir);
        SlamRecording run;
        if (offline) {
          run = runSlamOffline(seq, slam_options, verbose);
        } else {
          const std::string log = (fs::path(out_dir) / "logs" / (name + ".lcm")).string();
          spdlog::info("{}: running the pipeline, recording {}", name, log);
          const PipelineRun pr = runPipeline(dir, log, system, pipeline);
          section["pipeline_stages"] = pr.stages;
          if (!pr.ok) {
            section["pipeline_error"] = pr.error;
            spdlog::error("{}: {}", name, pr.error);
            ++failures;
          }
          run = readSlamRecording(log, system.channels);
        }
        SlamEvalOptions eo;
        eo.plot_path = (fs::path(out_dir) / "plots" / (name + "_trajectory.png")).string();
        nlohmann::json slam = evaluateSlam(run, seq, eo);
        for (auto it = slam.begin(); it != slam.end(); ++it) section[it.key()] = it.value();
        if (isSyntheticSequence(seq)) synthetic.push_back(slam);
        spdlog::info("{}: tracked {}%, ATE {} m ({}% of path), {} maps", name,
                     slam.value("tracked_pct", 0.0), slam.value("ate_rmse", 0.0),
                     slam.value("ate_rmse_pct_of_path", 0.0), slam.value("maps", 0));
      } catch (const std::exception& e) {
        section["error"] = e.what();
        spdlog::error("{}: {}", name, e.what());
        ++failures;
      }
      report["sequences"][name]["slam"] = section;
    }
    if (!synthetic.empty()) report["overall"]["slam"] = summarizeSlam(synthetic);
    std::ofstream(out) << report.dump(2) << "\n";
    return failures ? 1 : 0;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
}
