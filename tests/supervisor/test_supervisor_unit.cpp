// Supervisor pieces without processes: restart policy and back-off, config checks, log rotation,
// /proc sampling.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "common/config.h"
#include "procs/supervisor/proc_stats.h"
#include "procs/supervisor/process_spec.h"
#include "procs/supervisor/restart_policy.h"
#include "procs/supervisor/rotating_log.h"
#include "tests/support/test_support.h"

using namespace slamaware;
using namespace slamaware::supervisor;

TEST(RestartPolicy, BackoffDoublesUpToTheCapAndResetsAfterAStableRun) {
  RestartPolicy p(RestartPolicy::Mode::kOnFailure, 0.01, 1.0, 10.0);
  double t = 0;
  std::vector<double> delays;
  for (int i = 0; i < 10; ++i) {
    p.started(t);
    t += 0.05;  // dies at once
    delays.push_back(p.ended(t, true));
    t += delays.back();
  }
  EXPECT_DOUBLE_EQ(delays[0], 0.01);
  EXPECT_DOUBLE_EQ(delays[1], 0.02);
  EXPECT_DOUBLE_EQ(delays[2], 0.04);
  EXPECT_DOUBLE_EQ(delays[6], 0.64);
  EXPECT_DOUBLE_EQ(delays[7], 1.0) << "capped";
  EXPECT_DOUBLE_EQ(delays[9], 1.0);
  EXPECT_EQ(p.quickFailures(), 10);
  p.started(t);
  EXPECT_DOUBLE_EQ(p.ended(t + 60, true), 0.01) << "a long run resets the back-off";
  EXPECT_EQ(p.quickFailures(), 1);
}

TEST(RestartPolicy, Modes) {
  RestartPolicy never(RestartPolicy::Mode::kNever, 0.01, 1, 10);
  never.started(0);
  EXPECT_LT(never.ended(1, true), 0);
  RestartPolicy on_failure(RestartPolicy::Mode::kOnFailure, 0.01, 1, 10);
  on_failure.started(0);
  EXPECT_LT(on_failure.ended(1, false), 0) << "a clean exit is not a failure";
  on_failure.started(2);
  EXPECT_GE(on_failure.ended(3, true), 0);
  RestartPolicy always(RestartPolicy::Mode::kAlways, 0.01, 1, 10);
  always.started(0);
  EXPECT_GE(always.ended(1, false), 0);
  EXPECT_THROW(RestartPolicy::parse("sometimes"), std::invalid_argument);
}

namespace {
std::string writeSystem(const std::string& name, const std::string& text) {
  const std::string path = test::tempDir("supervisor_cfg_" + name) + "/system.yaml";
  std::ofstream(path) << text;
  return path;
}
std::string errorOf(const std::string& text) {
  try {
    loadSupervisorConfig(writeSystem("bad", text));
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(SupervisorConfig, LoadsProcessesInOrder) {
  const auto cfg = loadSupervisorConfig(writeSystem(
      "ok",
      "supervisor:\n  host: robot\nprocesses:\n  - name: camera\n    command: [a, b]\n    host: "
      "robot\n"
      "  - name: slam\n    command: [c]\n    restart: always\n    stop_signal: TERM\n"));
  EXPECT_EQ(cfg.options.host, "robot");
  ASSERT_EQ(cfg.processes.size(), 2u);
  EXPECT_EQ(cfg.processes[0].command, (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(cfg.processes[1].restart, "always");
  EXPECT_EQ(cfg.processes[1].host, "local");
}

TEST(SupervisorConfig, BadEntriesNamed) {
  EXPECT_NE(errorOf("processes:\n  - name: a\n").find("'command' is required"), std::string::npos);
  EXPECT_NE(errorOf("processes:\n  - name: a\n    command: [x]\n  - name: a\n    command: [y]\n")
                .find("duplicate"),
            std::string::npos);
  EXPECT_NE(errorOf("processes:\n  - name: a\n    command: [x]\n    restart: sometimes\n")
                .find("key 'restart'"),
            std::string::npos);
  EXPECT_NE(errorOf("processes:\n  - name: a\n    command: [x]\n    stop_signal: NOPE\n")
                .find("unknown signal"),
            std::string::npos);
  const std::string e = errorOf("processes:\n  - name: a\n    command: [x]\n    restrat: always\n");
  EXPECT_NE(e.find("unknown key 'restrat'"), std::string::npos) << e;
  EXPECT_NE(e.find("processes[0]"), std::string::npos) << e;
  EXPECT_NE(errorOf("processes: 3\n").find("expected a list"), std::string::npos);
  EXPECT_NE(errorOf("procesess: []\n").find("unknown section"), std::string::npos);
}

TEST(SupervisorConfig, ShippedSystemYamlLoads) {
  const auto cfg = loadSupervisorConfig(test::sourcePath("config/system.yaml"));
  EXPECT_FALSE(cfg.processes.empty()) << "config/system.yaml lists the pipeline";
}

TEST(RotatingLog, RotatesBySizeAndKeepsN) {
  const std::string dir = test::tempDir("rotating_log");
  {
    RotatingLog log(dir + "/p.log", 1000, 2);
    const std::string chunk(300, 'x');
    for (int i = 0; i < 12; ++i) log.write(chunk.data(), chunk.size());
  }
  namespace fs = std::filesystem;
  EXPECT_TRUE(fs::exists(dir + "/p.log"));
  EXPECT_TRUE(fs::exists(dir + "/p.log.1"));
  EXPECT_TRUE(fs::exists(dir + "/p.log.2"));
  EXPECT_FALSE(fs::exists(dir + "/p.log.3"));
  EXPECT_LE(fs::file_size(dir + "/p.log"), 1000u);
  EXPECT_EQ(fs::file_size(dir + "/p.log.1"), 900u);
}

TEST(ProcStats, SamplesThisProcess) {
  const auto a = sampleProcess(getpid());
  ASSERT_TRUE(a.has_value());
  EXPECT_GT(a->rss_kb, 1000);
  volatile double x = 0;
  for (int i = 0; i < 50000000; ++i) x = x + i * 1e-9;
  const auto b = sampleProcess(getpid());
  EXPECT_GT(b->cpu_ticks, a->cpu_ticks);
  EXPECT_FALSE(sampleProcess(999999).has_value());
}

TEST(SupervisorConfig, EnvironmentExpansion) {
  setenv("SLAMAWARE_TEST_X", "value", 1);
  unsetenv("SLAMAWARE_TEST_UNSET");
  const auto out = expandEnvironment({"a${SLAMAWARE_TEST_X}b", "${SLAMAWARE_TEST_UNSET:-dflt}",
                                      "${SLAMAWARE_TEST_UNSET}", "plain", "${SLAMAWARE_TEST_X:-no}",
                                      "${broken"});
  EXPECT_EQ(out, (std::vector<std::string>{"avalueb", "dflt", "", "plain", "value", "${broken"}));
}
