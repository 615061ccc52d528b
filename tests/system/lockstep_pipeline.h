// The system tests' pipeline run: the project's processes and config/*.yaml, lockstep, on the
// test's own bus URL (each test runs in its own network namespace).
#pragma once

#include <filesystem>

#include "common/bus/system_config.h"
#include "tests/support/test_support.h"
#include "tools/eval/pipeline_run.h"

namespace slamaware::test {

/// Sets the working directory to the project folder (the processes read config/*.yaml and the
/// model path in it relative to it) and returns the lockstep system config and run options.
inline PipelineRunOptions lockstepPipeline(SystemConfig* sys) {
  std::filesystem::current_path(sourcePath(""));
  sys->bus.url = testUrl();
  sys->bus.lockstep = true;
  PipelineRunOptions options;
  options.bin_dir = std::filesystem::path(binPath("slamaware-slam")).parent_path().string();
  options.config_dir = sourcePath("config");
  options.lcm_url = sys->bus.url;
  return options;
}

}  // namespace slamaware::test
