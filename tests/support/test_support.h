#pragma once
// Helpers shared by tests: paths of binaries and data, child processes, recording the bus.
#include <gtest/gtest.h>
#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <vector>

namespace slamaware::test {

/// How many times slower code runs in this build than in the optimised one: the few loose bounds
/// on time in tests (against a pathological slowdown; speed targets are in `make bench`) are
/// multiplied by it. Sanitized code ran 2-10 times slower here, most with two tests at once.
#if defined(SLAMAWARE_SANITIZE)
inline constexpr double kSlowdown = 10;
#else
inline constexpr double kSlowdown = 1;
#endif

/// build/bin/<name>
std::string binPath(const std::string& name);
/// <source>/<relative>
std::string sourcePath(const std::string& relative);
/// ../shared/data/<relative>, or "" if the shared data is not beside the project.
std::string sharedData(const std::string& relative);
/// A fresh empty folder under the build tree for one test.
std::string tempDir(const std::string& name);
/// The whole content of a file ("" if it cannot be read).
std::string readTextFile(const std::string& path);
/// The bus URL tests use (inside their own network namespace).
std::string testUrl();

/// Appends message `m` on `channel` to a log as its event number `n` (timestamp 1000 + n).
template <class Msg>
void writeEvent(lcm::LogFile& log, const std::string& channel, const Msg& m, int64_t n) {
  std::vector<uint8_t> buf(static_cast<size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  lcm::LogEvent ev;
  ev.eventnum = n;
  ev.timestamp = 1000 + n;
  ev.channel = channel;
  ev.datalen = static_cast<int32_t>(buf.size());
  ev.data = buf.data();
  log.writeEvent(&ev);
}

/// Skips the current test with a clear message when the shared data is absent.
#define SKIP_WITHOUT_SHARED_DATA(path)                                                         \
  if ((path).empty()) {                                                                        \
    GTEST_SKIP() << "../shared/data is not beside the project: this test needs the real data"; \
  }

/// A child process with its output in a log file; killed (SIGKILL) when destroyed.
class ChildProcess {
 public:
  ChildProcess(const std::vector<std::string>& argv, const std::string& log_path);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  pid_t pid() const { return pid_; }
  /// True while the process has not exited (reaps it if it has).
  bool running();
  void signal(int sig);
  /// Waits for exit; returns the exit code, 128+signal if killed, -1 on timeout.
  int wait(std::chrono::milliseconds timeout);
  /// SIGINT, then SIGKILL after `grace`; returns the exit status as wait().
  int stop(std::chrono::milliseconds grace = std::chrono::milliseconds(3000));
  std::string log() const;

 private:
  pid_t pid_ = -1;
  int status_ = -1;
  bool exited_ = false;
  std::string log_path_;
};

/// lcm-logger recording the test bus into `path` while alive (stopped with SIGINT). The
/// constructor returns once the logger is recording, and stop() once everything the logger
/// received before it is in the file; the log also holds a few messages on kProbeChannel from
/// these handshakes. Pace what a test records: lcm-logger keeps at most 30 received, unhandled
/// messages (LCM's default subscription queue; it has no option to raise it), so a logger short of
/// CPU drops the newest of a longer burst, and no handshake can bring them back.
class BusRecorder {
 public:
  static const char* const kProbeChannel;
  BusRecorder(const std::string& path, const std::string& channels = ".*");
  ~BusRecorder();
  void stop();

 private:
  std::string path_;
  ChildProcess logger_;
  bool stopped_ = false;
};

/// Writes a sequence folder of `frames` textured 640x480 PNG frames (a pattern that moves from
/// frame to frame) at `fps`; returns its path.
std::string makeTestSequence(const std::string& name, int frames, double fps);

/// Polls `pred` every 10 ms until true or timeout; returns its last value.
bool waitUntil(const std::function<bool()>& pred, std::chrono::milliseconds timeout);

}  // namespace slamaware::test
