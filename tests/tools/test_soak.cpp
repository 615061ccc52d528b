// slamaware-soak for 45 s on the bundled sample: the whole supervised system runs, nothing
// restarts, frames get poses and detections, and the report, the plot and the samples behind them
// agree. Private network namespace.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "tests/support/test_support.h"
#include "tools/eval/stats.h"

using namespace slamaware;
using nlohmann::json;

namespace {

// config/system.yaml with this build's binaries (a sanitized build runs its own).
std::string systemForThisBuild(const std::string& dir) {
  std::string text = test::readTextFile(test::sourcePath("config/system.yaml"));
  const std::string from = "build/bin/", to = test::binPath("");
  for (size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
  const std::string path = dir + "/system.yaml";
  std::ofstream(path) << text;
  return path;
}

}  // namespace

TEST(Soak, TheSupervisedSystemRunsAndTheReportAgreesWithItsSamples) {
  const std::string dir = test::tempDir("soak");
  const std::string system = systemForThisBuild(dir);
  const std::string out = dir + "/out";
  // The processes' config paths in system.yaml are relative to the project folder.
  ASSERT_EQ(chdir(test::sourcePath("").c_str()), 0);
  test::ChildProcess soak({test::binPath("slamaware-soak"), "--minutes", "0.75", "--source",
                           test::sourcePath("logs/sample.lcm"), "--system", system, "--bin-dir",
                           test::binPath(""), "--out-dir", out},
                          dir + "/soak.log");
  ASSERT_EQ(soak.wait(std::chrono::seconds(180)), 0) << soak.log();

  const json r = json::parse(test::readTextFile(out + "/report.json"));
  EXPECT_GT(r["loops"].get<double>(), 2.0);  // 150 frames a loop at 30 Hz, 45 s
  EXPECT_GT(r["first_loop_end_s"].get<double>(), 0.0);
  const json& frames = r["frames"];
  const int64_t camera = frames["camera"].get<int64_t>();
  EXPECT_GT(camera, 600);
  if (test::kSlowdown == 1) {  // real time: every frame tracked, most labelled
    // At most the frame in flight when the soak stops counting (its pose comes a moment later).
    EXPECT_LE(frames["frames_without_pose"].get<int64_t>(), 1) << r.dump(2);
    EXPECT_GT(frames["detections"].get<int64_t>(), camera / 2);
  } else {  // sanitized code cannot keep up with 30 Hz: it drops frames, but runs
    EXPECT_GT(frames["slam_pose"].get<int64_t>(), 0) << r.dump(2);
    EXPECT_GT(frames["detections"].get<int64_t>(), 0);
  }
  EXPECT_GT(frames["detections_in_last_5_s"].get<int64_t>(), 0);
  for (const char* name : {"camera", "slam", "proposals", "recognizer", "objectmap"}) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(r["processes"].contains(name)) << r.dump(2);
    const json& p = r["processes"][name];
    EXPECT_EQ(p["restarts"].get<int>(), 0);
    EXPECT_GT(p["rss_mb_at_end"].get<double>(), 10.0);
    EXPECT_GT(p["cpu_pct_mean"].get<double>(), 0.0);
  }
  EXPECT_FALSE(r["latency_windows"].empty());
  EXPECT_TRUE(std::filesystem::file_size(out + "/rss.png") > 1000);

  // The samples: one a second per process; the report's RSS at the end is the median of those of
  // the last 30 s.
  std::ifstream csv(out + "/samples.csv");
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  EXPECT_EQ(line, "t_s,process,rss_mb,cpu_pct");
  const double duration = 0.75 * 60;
  std::map<std::string, int> rows;
  std::map<std::string, std::vector<double>> last_30_s;
  while (std::getline(csv, line)) {
    std::stringstream s(line);
    std::string t, name, rss;
    ASSERT_TRUE(std::getline(s, t, ',') && std::getline(s, name, ',') && std::getline(s, rss, ','))
        << line;
    ++rows[name];
    const double t_s = std::stod(t);
    if (t_s >= duration - 30 && t_s < duration + 1) last_30_s[name].push_back(std::stod(rss));
  }
  for (const char* name : {"camera", "slam", "proposals", "recognizer", "objectmap"}) {
    SCOPED_TRACE(name);
    EXPECT_GE(rows[name], 35);  // 45 s at 1 Hz, less the supervisor's start
    ASSERT_GE(last_30_s[name].size(), 25u);
    const double end = r["processes"][name]["rss_mb_at_end"].get<double>();
    EXPECT_NEAR(median(last_30_s[name]), end, 0.01 * end);
  }
}
