#pragma once
// A child process of a tool (the evaluator's stages, the soak's supervisor) with its stdout and
// stderr in a file. It gets SIGTERM when the tool dies, and is stopped (SIGINT, then SIGKILL) when
// this object goes.
#include <signal.h>
#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "common/spawn.h"

namespace slamaware {

class ChildProcess {
 public:
  ChildProcess(const std::vector<std::string>& argv, const std::string& output) {
    std::string line;
    for (const auto& a : argv) line += a + " ";
    spdlog::debug("start: {}", line);
    // A stage outlives no evaluation or bench that was killed.
    pid_ = spawnWithOutput(argv, output, true);
  }
  ~ChildProcess() { stop(std::chrono::milliseconds(2000)); }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;
  pid_t pid() const { return pid_; }

  bool running() {
    if (pid_ <= 0 || exited_) return false;
    struct rusage usage {};
    if (wait4(pid_, &status_, WNOHANG, &usage) == pid_) {
      exited_ = true;
      max_rss_kb_ = usage.ru_maxrss;
      cpu_s_ = static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
               1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
    }
    return !exited_;
  }
  /// Exit code, or -1 if it did not exit within the timeout.
  int wait(std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (running()) {
      if (std::chrono::steady_clock::now() > end) return -1;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return WIFEXITED(status_) ? WEXITSTATUS(status_) : 128 + WTERMSIG(status_);
  }
  /// SIGINT, then SIGKILL after `grace`.
  int stop(std::chrono::milliseconds grace) {
    if (!running())
      return exited_ ? (WIFEXITED(status_) ? WEXITSTATUS(status_) : 128 + WTERMSIG(status_)) : -1;
    kill(pid_, SIGINT);
    int rc = wait(grace);
    if (rc == -1) {
      kill(pid_, SIGKILL);
      rc = wait(std::chrono::milliseconds(2000));
    }
    return rc;
  }
  /// Peak resident memory in kB, once the process has exited.
  long maxRssKb() const { return max_rss_kb_; }
  /// CPU time (user + system, every thread) in s, once the process has exited.
  double cpuSeconds() const { return cpu_s_; }

 private:
  pid_t pid_ = -1;
  int status_ = 0;
  bool exited_ = false;
  long max_rss_kb_ = 0;
  double cpu_s_ = 0;
};

}  // namespace slamaware
