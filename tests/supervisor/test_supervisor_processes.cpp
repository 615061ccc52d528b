// The supervisor with real processes, each case in its own network namespace: restarts after a
// kill, hung detection, back-off of a crash loop, commands, clean shutdown, and two hosts.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <fstream>
#include <map>
#include <thread>

#include "common/bus/bus.h"
#include "common/bus/log_reader.h"
#include "slamaware/proc_status_t.hpp"
#include "tests/support/test_support.h"

using namespace slamaware;
using namespace std::chrono_literals;

namespace {

bool alive(pid_t pid) { return pid > 0 && kill(pid, 0) == 0; }

std::string cameraEntry(const std::string& name, const std::string& seq,
                        const std::string& extra = "") {
  return "  - name: " + name + "\n    command: [" + test::binPath("slamaware-camera") +
         ", --source, " + seq + ", --loop, --name, " + name + ", --lcm-url, \"" + test::testUrl() +
         "\", --log-level, warn]\n    group: sensors\n" + extra;
}

// A supervisor on the test bus with the given `processes:` entries.
class SupervisorFixture : public ::testing::Test {
 protected:
  void start(const std::string& name, const std::string& entries,
             const std::string& host = "local") {
    dir_ = test::tempDir("supervisor_" + name);
    system_ = dir_ + "/system.yaml";
    std::ofstream(system_) << "bus:\n  url: \"" << test::testUrl()
                           << "\"\nsupervisor:\n  host: " << host << "\n  log_dir: " << dir_
                           << "/logs\nprocesses:\n"
                           << entries;
    bus_.subscribe<proc_status_t>("PROC_STATUS", [this](const proc_status_t& s) {
      for (const auto& p : s.procs) latest_[p.name] = p;
      ++statuses_;
    });
    sup_ = std::make_unique<test::ChildProcess>(
        std::vector<std::string>{test::binPath("slamaware-supervisor"), "--system", system_},
        dir_ + "/supervisor.txt");
  }
  // Handles the bus until pred() holds or the timeout passes.
  bool until(const std::function<bool()>& pred, std::chrono::milliseconds timeout) {
    return test::waitUntil(
        [&] {
          bus_.handle(10);
          return pred();
        },
        timeout);
  }
  proc_info_t info(const std::string& name) {
    return latest_.count(name) ? latest_[name] : proc_info_t{};
  }
  bool running(const std::string& name) {
    auto p = info(name);
    return p.state == proc_info_t::STATE_RUNNING && alive(p.pid);
  }
  std::string ctl(const std::string& args) {
    const std::string cmd = test::binPath("slamaware-ctl") + " --lcm-url '" + test::testUrl() +
                            "' --system " + system_ + " " + args + " 2>&1";
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
  ASSERT_TRUE(until([&] { return info("camera").pid != first && running("camera"); }, 5s))
      << sup_->log();
  const double restart_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
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
  ASSERT_TRUE(until([&] { return info("camera").restarts == 1 && running("camera"); }, 8s))
      << sup_->log();
  const double detect_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(detect_s, 2.0 + 1.5) << "heartbeat timeout 2 s (+1 s heartbeat period, +0.5 s restart)";
  EXPECT_FALSE(alive(first)) << "the hung process is killed, not left behind";
  EXPECT_NE(info("camera").message.find("hung"), std::string::npos) << info("camera").message;
}

TEST_F(SupervisorFixture, CrashLoopIsBackedOff) {
  start("crashloop",
        "  - name: crasher\n    command: [false]\n    wait_running: false\n    "
        "heartbeat_timeout_s: 0\n"
        "    backoff_initial_s: 0.01\n    backoff_max_s: 1.0\n");
  float max_backoff = 0;
  bool saw_backoff = false;
  std::string crash_loop_message;  // what PROC_STATUS said while it waited, once a loop was seen
  until(
      [&] {
        const proc_info_t p = info("crasher");
        if (p.state == proc_info_t::STATE_BACKOFF) {
          saw_backoff = true;
          max_backoff = std::max(max_backoff, p.backoff_s);
          if (p.message.find("crash loop") != std::string::npos) crash_loop_message = p.message;
        }
        return false;
      },
      4000ms);
  const int restarts = info("crasher").restarts;
  // 'false' exits at once: a tight loop would restart it thousands of times in 4 s. With back-off
  // 10 ms doubling to 1 s there are about ten.
  EXPECT_GE(restarts, 5) << "it is restarted";
  EXPECT_LE(restarts, 12) << "but not in a tight loop";
  EXPECT_TRUE(saw_backoff);
  EXPECT_GE(max_backoff, 0.5f);
  // Said while it waits; at the end it may be between a restart and its exit ("restart 9 ...").
  EXPECT_FALSE(crash_loop_message.empty()) << info("crasher").message;
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
  ASSERT_TRUE(until(
      [&] {
        return running("cam1") && running("cam2") && info("cam1").pid != a && info("cam2").pid != b;
      },
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

namespace {

// Runs a shell command; its exit code.
int sh(const std::string& cmd) { return std::system(cmd.c_str()); }

// Output of a shell command.
std::string shOut(const std::string& cmd) {
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  std::string out;
  char buf[512];
  while (p && fgets(buf, sizeof(buf), p)) out += buf;
  if (p) pclose(p);
  return out;
}

// A "host": a network namespace kept alive by a sleeping process, joined to the other host by a
// veth pair; its multicast goes out on the veth (ttl=1 crosses it, as between two machines).
struct Host {
  std::string name, address;
  std::unique_ptr<test::ChildProcess> holder;
  std::string enter() const { return "nsenter -t " + std::to_string(holder->pid()) + " -n"; }
};

}  // namespace

TEST(SupervisorTwoHosts, PipelineMessagesCrossAndCtlSeesBothHosts) {
  const std::string dir = test::tempDir("supervisor_two_hosts");
  Host a{"a", "10.77.0.1", {}}, b{"b", "10.77.0.2", {}};
  for (Host* h : {&a, &b}) {
    h->holder = std::make_unique<test::ChildProcess>(
        std::vector<std::string>{"unshare", "-n", "sleep", "300"},
        dir + "/holder_" + h->name + ".txt");
    // unshare runs sleep in the new namespace once it has made it.
    ASSERT_TRUE(test::waitUntil(
        [&] {
          return shOut("readlink /proc/" + std::to_string(h->holder->pid()) + "/exe")
                     .find("sleep") != std::string::npos;
        },
        2000ms));
  }
  ASSERT_EQ(sh("ip link add sw_a type veth peer name sw_b"), 0)
      << "needs a network namespace with CAP_NET_ADMIN";
  ASSERT_EQ(sh("ip link set sw_a netns " + std::to_string(a.holder->pid())), 0);
  ASSERT_EQ(sh("ip link set sw_b netns " + std::to_string(b.holder->pid())), 0);
  for (Host* h : {&a, &b}) {
    const std::string dev = "sw_" + h->name;
    ASSERT_EQ(
        sh(h->enter() + " sh -c 'ip link set lo up && ip addr add " + h->address + "/24 dev " +
           dev + " && ip link set " + dev + " up && ip route add 224.0.0.0/4 dev " + dev + "'"),
        0);
  }
  // One system.yaml for both hosts, ttl=1; each supervisor runs the entries of its host.
  const std::string url = "udpm://239.255.76.67:7667?ttl=1&recv_buf_size=4194304";
  const std::string seq = test::makeTestSequence("sup_two_hosts_seq", 60, 10.0);
  const std::string system = dir + "/system.yaml";
  auto entry = [&](const std::string& name, const std::string& host, const std::string& args) {
    return "  - name: " + name + "\n    host: " + host + "\n    command: [" +
           test::binPath("slamaware-" + name) + ", --lcm-url, \"" + url + "\", --log-level, warn" +
           args + "]\n";
  };
  std::ofstream(system) << "bus:\n  url: \"" << url << "\"\nsupervisor:\n  log_dir: " << dir
                        << "/logs\nprocesses:\n"
                        << entry("slam", "a", "")
                        << entry("camera", "a", ", --source, " + seq + ", --loop")
                        << entry("recognizer", "b", "");
  test::ChildProcess sup_a(
      {"nsenter", "-t", std::to_string(a.holder->pid()), "-n",
       test::binPath("slamaware-supervisor"), "--system", system, "--host", "a"},
      dir + "/supervisor_a.txt");
  test::ChildProcess sup_b(
      {"nsenter", "-t", std::to_string(b.holder->pid()), "-n",
       test::binPath("slamaware-supervisor"), "--system", system, "--host", "b"},
      dir + "/supervisor_b.txt");
  // Host b hears host a's pipeline: camera frames and SLAM poses.
  const std::string log_b = dir + "/heard_on_b.lcm";
  test::ChildProcess logger_b(
      {"nsenter", "-t", std::to_string(b.holder->pid()), "-n", "lcm-logger", "--lcm-url=" + url,
       "-f", "-c", "CAMERA|SLAM_POSE|RECOGNIZER_STATUS", log_b},
      dir + "/logger_b.txt");
  // slamaware-ctl on host a lists the processes of both hosts.
  const std::string ctl =
      a.enter() + " " + test::binPath("slamaware-ctl") + " --system " + system + " status --wait 2";
  std::string status;
  const bool both = test::waitUntil(
      [&] {
        status = shOut(ctl);
        return status.find("slam") != std::string::npos &&
               status.find("recognizer") != std::string::npos &&
               status.find("camera") != std::string::npos &&
               status.find("running") != std::string::npos;
      },
      30s);
  EXPECT_TRUE(both) << status << sup_a.log() << sup_b.log();
  // Counted from the log as it grows (lcm-logger flushes every 100 ms; a half-written last event
  // ends the count), until enough has crossed or 30 s: a slow build (sanitizers) starts late.
  std::map<std::string, int> heard;
  auto count = [&] {
    heard.clear();
    try {
      LogReader reader(log_b);
      while (auto ev = reader.next()) ++heard[ev->channel];
    } catch (const LogError&) {
    }
    return heard["CAMERA"] > 5 && heard["SLAM_POSE"] > 5 && heard["RECOGNIZER_STATUS"] > 0;
  };
  test::waitUntil(count, 30s);
  logger_b.stop();
  count();
  std::printf("heard on host b: CAMERA %d, SLAM_POSE %d, RECOGNIZER_STATUS %d\n", heard["CAMERA"],
              heard["SLAM_POSE"], heard["RECOGNIZER_STATUS"]);
  std::printf("%s", status.c_str());
  EXPECT_GT(heard["CAMERA"], 5) << "camera frames from host a reach host b";
  EXPECT_GT(heard["SLAM_POSE"], 5) << "SLAM poses from host a reach host b";
  EXPECT_GT(heard["RECOGNIZER_STATUS"], 0) << "host b's own recognizer runs";
  // A command from host a reaches host b's supervisor.
  const std::string out = shOut(a.enter() + " " + test::binPath("slamaware-ctl") + " --system " +
                                system + " restart recognizer --host b");
  EXPECT_NE(out.find("recognizer"), std::string::npos) << out;
  sup_a.signal(SIGTERM);
  sup_b.signal(SIGTERM);
  EXPECT_EQ(sup_a.wait(10s), 0) << sup_a.log();
  EXPECT_EQ(sup_b.wait(10s), 0) << sup_b.log();
}
