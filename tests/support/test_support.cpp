#include "tests/support/test_support.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

namespace fs = std::filesystem;

namespace slamaware::test {

std::string binPath(const std::string& name) { return std::string(SLAMAWARE_BIN_DIR) + "/" + name; }
std::string sourcePath(const std::string& relative) { return std::string(SLAMAWARE_SOURCE_DIR) + "/" + relative; }

std::string sharedData(const std::string& relative) {
  const fs::path p = fs::path(SLAMAWARE_SHARED_DATA) / relative;
  return fs::exists(p) ? p.string() : "";
}

std::string tempDir(const std::string& name) {
  const fs::path p = fs::path(SLAMAWARE_BIN_DIR).parent_path() / "test-tmp" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p.string();
}

std::string testUrl() { return "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"; }

ChildProcess::ChildProcess(const std::vector<std::string>& argv, const std::string& log_path) : log_path_(log_path) {
  pid_ = fork();
  if (pid_ == 0) {
    const int fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      dup2(fd, 1);
      dup2(fd, 2);
      close(fd);
    }
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execvp(args[0], args.data());
    std::perror("exec");
    _exit(127);
  }
}

ChildProcess::~ChildProcess() {
  if (pid_ > 0 && running()) {
    kill(pid_, SIGKILL);
    waitpid(pid_, &status_, 0);
  }
}

bool ChildProcess::running() {
  if (exited_ || pid_ <= 0) return false;
  const pid_t r = waitpid(pid_, &status_, WNOHANG);
  if (r == pid_) exited_ = true;
  return !exited_;
}

void ChildProcess::signal(int sig) {
  if (running()) kill(pid_, sig);
}

int ChildProcess::wait(std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (running()) {
    if (std::chrono::steady_clock::now() > end) return -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  if (WIFEXITED(status_)) return WEXITSTATUS(status_);
  if (WIFSIGNALED(status_)) return 128 + WTERMSIG(status_);
  return -1;
}

int ChildProcess::stop(std::chrono::milliseconds grace) {
  signal(SIGINT);
  int rc = wait(grace);
  if (rc == -1) {
    signal(SIGKILL);
    rc = wait(std::chrono::milliseconds(2000));
  }
  return rc;
}

std::string ChildProcess::log() const {
  std::ifstream in(log_path_);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

BusRecorder::BusRecorder(const std::string& path, const std::string& channels)
    : logger_({"lcm-logger", "--lcm-url=" + testUrl(), "-f", "-c", channels, path}, path + ".out") {
  // lcm-logger has no ready signal: give it time to join the group.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
}

BusRecorder::~BusRecorder() { stop(); }

void BusRecorder::stop() {
  if (stopped_) return;
  stopped_ = true;
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // let the last messages land
  logger_.stop();
}

bool waitUntil(const std::function<bool()>& pred, std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (!pred()) {
    if (std::chrono::steady_clock::now() > end) return pred();
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

}  // namespace slamaware::test
