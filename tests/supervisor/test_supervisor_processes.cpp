// The supervisor with real processes, each case in its own network namespace: restarts after a
// kill, hung detection, back-off of a crash loop, commands, clean shutdown, and two hosts.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <fstream>
#include <map>
#include <thread>

#include "common/bus/bus.h"
#include "slamaware/proc_status_t.hpp"
#include "tests/support/test_support.h"

using namespace slamaware;
using namespace std::chrono_literals;

namespace {

bool alive(pid_t pid) { return pid > 0 && kill(pid, 0) == 0; }

std::string cameraEntry(const std::string& name, const std::string& seq, const std::string& extra = "") {
  return "  - name: " + name + "\n    command: [" + test::binPath("slamaware-camera") + ", --source, " + seq +
         ", --loop, --name, " + name +
         ", --lcm-url, \"" + test::testUrl() + "\", --log-level, warn]\n    group: sensors\n" + extra;
}

// A supervisor on the test bus with the given `processes:` entries.
class SupervisorFixture : public ::testing::Test {
 protected:
  void start(const std::string& name, const std::string& entries, const std::string& host = "local") {
    dir_ = test::tempDir("supervisor_" + name);
    system_ = dir_ + "/system.yaml";
    std::ofstream(system_) << "bus:\n  url: \"" << test::testUrl() << "\"\nsupervisor:\n  host: " << host
                           << "\n  log_dir: " << dir_ << "/logs\nprocesses:\n"
                           << entries;
    bus_.subscribe<proc_status_t>("PROC_STATUS", [this](const proc_status_t& s) {
      for (const auto& p : s.procs) latest_[p.name] = p;
      ++statuses_;
    });
    sup_ = std::make_unique<test::ChildProcess>(
        std::vector<std::string>{test::binPath("slamaware-supervisor"), "--system", system_}, dir_ + "/supervisor.txt");
  }
  // Handles the bus until pred() holds or the timeout passes.
  bool until(const std::function<bool()>& pred, std::chrono::milliseconds timeout) {
    return test::waitUntil([&] {
      bus_.handle(10);
      return pred();
    }, timeout);
  }
  proc_info_t info(const std::string& name) { return latest_.count(name) ? latest_[name] : proc_info_t{}; }
  bool running(const std::string& name) {
    auto p = info(name);
    return p.state == proc_info_t::STATE_RUNNING && alive(p.pid);
  }
  std::string ctl(const std::string& args) {
    const std::string cmd = test::binPath("slamaware-ctl") + " --lcm-url '" + test::testUrl() + "' --system " + system_ +
                            " " + args + " 2>&1";
    FILE* p = popen(cmd.c_str(), "r");
    std::string out;
    char buf[512];
    while (p && fgets(buf, sizeof(buf), p)) out += buf;
    last_ctl_rc_ = p ? pclose(p) : -1;
    return out;
  }

  std::string dir_, system_;
  Bus bus_{test::testUrl()};
  std::map<std::string, proc_info_t> latest_;
  int statuses_ = 0;
  int last_ctl_rc_ = 0;
  std::unique_ptr<test::ChildProcess> sup_;
};

}  // namespace

TEST_F(SupervisorFixture, KilledChildRunsAgainWithinOneSecond) {
  const std::string seq = test::makeTestSequence("sup_kill_seq", 10, 10.0);
  start("kill", cameraEntry("camera", seq, "    heartbeat_timeout_s: 3\n"));
  ASSERT_TRUE(until([&] { return running("camera"); }, 10s)) << sup_->log();
  const pid_t first = info("camera").pid;
  kill(first, SIGKILL);
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_TRUE(until([&] { return info("camera").pid != first && running("camera"); }, 5s)) << sup_->log();
  const double restart_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(restart_s, 1.0) << "running again within 1 s";
  EXPECT_EQ(info("camera").restarts, 1);
  EXPECT_EQ(info("camera").exit_code, -SIGKILL);
}

TEST_F(SupervisorFixture, StoppedChildIsDetectedAsHungAndRestarted) {
  const std::string seq = test::makeTestSequence("sup_hung_seq", 10, 10.0);
  start("hung", cameraEntry("camera", seq, "    heartbeat_timeout_s: 2\n"));
  ASSERT_TRUE(until([&] { return running("camera"); }, 10s)) << sup_->log();
  const pid_t first = info("camera").pid;
  kill(first, SIGSTOP);
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_TRUE(until([&] { return info("camera").restarts == 1 && running("camera"); }, 8s)) << sup_->log();
  const double detect_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(detect_s, 2.0 + 1.5) << "heartbeat timeout 2 s (+1 s heartbeat period, +0.5 s restart)";
  EXPECT_FALSE(alive(first)) << "the hung process is killed, not left behind";
  EXPECT_NE(info("camera").message.find("hung"), std::string::npos) << info("camera").message;
}

TEST_F(SupervisorFixture, CrashLoopIsBackedOff) {
  start("crashloop",
        "  - name: crasher\n    command: [false]\n    wait_running: false\n    heartbeat_timeout_s: 0\n"
        "    backoff_initial_s: 0.01\n    backoff_max_s: 1.0\n");
  float max_backoff = 0;
  bool saw_backoff = false;
  until([&] {
    if (info("crasher").state == proc_info_t::STATE_BACKOFF) {
      saw_backoff = true;
      max_backoff = std::max(max_backoff, info("crasher").backoff_s);
    }
    return false;
  }, 4000ms);
  const int restarts = info("crasher").restarts;
  // 'false' exits at once: a tight loop would restart it thousands of times in 4 s. With back-off
  // 10 ms doubling to 1 s there are about ten.
  EXPECT_GE(restarts, 5) << "it is restarted";
  EXPECT_LE(restarts, 12) << "but not in a tight loop";
  EXPECT_TRUE(saw_backoff);
  EXPECT_GE(max_backoff, 0.5f);
  EXPECT_NE(info("crasher").message.find("crash loop"), std::string::npos) << info("crasher").message;
}

TEST_F(SupervisorFixture, CommandsAndCleanShutdown) {
  const std::string seq = test::makeTestSequence("sup_cmd_seq", 10, 10.0);
  start("commands", cameraEntry("cam1", seq) + cameraEntry("cam2", seq));
  ASSERT_TRUE(until([&] { return running("cam1") && running("cam2"); }, 15s)) << sup_->log();

  const pid_t cam1 = info("cam1").pid;
  std::string out = ctl("stop cam1");
  EXPECT_EQ(last_ctl_rc_, 0) << out;
  ASSERT_TRUE(until([&] { return info("cam1").state == proc_info_t::STATE_STOPPED; }, 5s));
  EXPECT_FALSE(alive(cam1));
  EXPECT_TRUE(running("cam2"));

  out = ctl("start cam1");
  EXPECT_EQ(last_ctl_rc_, 0) << out;
  ASSERT_TRUE(until([&] { return running("cam1"); }, 5s));

  const pid_t a = info("cam1").pid, b = info("cam2").pid;
  out = ctl("restart sensors");
  EXPECT_EQ(last_ctl_rc_, 0) << out;
  ASSERT_TRUE(until([&] { return running("cam1") && running("cam2") && info("cam1").pid != a && info("cam2").pid != b; },
                    10s));
  EXPECT_FALSE(alive(a));
  EXPECT_FALSE(alive(b));

  out = ctl("status");
  EXPECT_NE(out.find("cam1"), std::string::npos) << out;
  EXPECT_NE(out.find("running"), std::string::npos) << out;
  out = ctl("logs cam1 -n 5");
  EXPECT_NE(out.find("started pid"), std::string::npos) << out;

  const pid_t c1 = info("cam1").pid, c2 = info("cam2").pid;
  sup_->signal(SIGTERM);
  EXPECT_EQ(sup_->wait(10s), 0) << sup_->log();
  EXPECT_FALSE(alive(c1)) << "no child outlives the supervisor";
  EXPECT_FALSE(alive(c2));
}
