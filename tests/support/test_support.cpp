#include "tests/support/test_support.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <thread>

#include "common/dataset.h"
#include "common/image_codec.h"
#include "common/spawn.h"

namespace fs = std::filesystem;

namespace slamaware::test {

std::string binPath(const std::string& name) { return std::string(SLAMAWARE_BIN_DIR) + "/" + name; }
std::string sourcePath(const std::string& relative) {
  return std::string(SLAMAWARE_SOURCE_DIR) + "/" + relative;
}

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

std::string readTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string testUrl() { return "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"; }

ChildProcess::ChildProcess(const std::vector<std::string>& argv, const std::string& log_path)
    : log_path_(log_path) {
  pid_ = spawnWithOutput(argv, log_path, false);
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

std::string ChildProcess::log() const { return readTextFile(log_path_); }

const char* const BusRecorder::kProbeChannel = "TEST_RECORDER_PROBE";

namespace {

// Publishes a probe on BusRecorder::kProbeChannel every 30 ms until `landed` (it looks at the
// log file) is true; false after 20 s.
bool publishProbesUntil(const std::function<bool()>& landed) {
  lcm::LCM lcm(testUrl());
  const uint8_t probe[1] = {0};
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < end) {
    lcm.publish(BusRecorder::kProbeChannel, probe, sizeof(probe));
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
    if (landed()) return true;
  }
  return false;
}

// Probe messages in the file beyond byte `from`.
size_t probesInFile(const std::string& path, std::streamoff from) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(from);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  size_t n = 0;
  for (size_t at = bytes.find(BusRecorder::kProbeChannel); at != std::string::npos;
       at = bytes.find(BusRecorder::kProbeChannel, at + 1))
    ++n;
  return n;
}

}  // namespace

BusRecorder::BusRecorder(const std::string& path, const std::string& channels)
    : path_(path),
      logger_({"lcm-logger", "--lcm-url=" + testUrl(), "--flush-interval=10", "-f", "-c",
               "(" + channels + ")|" + kProbeChannel, path},
              path + ".out") {
  // lcm-logger has no ready signal: publish probes until one of them reaches the file, so that
  // nothing published after the constructor returns can be missed by a logger still starting.
  std::error_code ec;
  if (!publishProbesUntil([&] { return fs::exists(path, ec) && fs::file_size(path, ec) > 0; }))
    ADD_FAILURE() << "lcm-logger recording " << path
                  << " did not start within 20 s: " << logger_.log();
}

BusRecorder::~BusRecorder() { stop(); }

void BusRecorder::stop() {
  if (stopped_) return;
  stopped_ = true;
  // What the logger received before this probe is queued ahead of it: once the probe is in the
  // file, so is the rest (a logger short of CPU reads its queue late, and SIGINT would drop what
  // it has not read yet). What it dropped from a full queue stays lost (see the header).
  std::error_code ec;
  const auto size = fs::file_size(path_, ec);
  const std::streamoff from = ec ? 0 : static_cast<std::streamoff>(size);
  const size_t before = probesInFile(path_, from);
  publishProbesUntil([&] { return probesInFile(path_, from) > before; });
  logger_.stop();
}

std::string makeTestSequence(const std::string& name, int frames, double fps) {
  const std::string dir = tempDir(name);
  fs::create_directories(dir + "/rgb");
  SequenceInfo info;
  info.name = name;
  info.source = "generated by a test";
  info.fps = fps;
  info.frames = frames;
  info.camera = CameraModel(640, 480, 525, 525, 319.5, 239.5);
  writeSequenceInfo(dir + "/sequence.yaml", info);
  cv::Mat noise(60, 80, CV_8UC3);
  cv::RNG rng(1234);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
  cv::Mat texture;
  cv::resize(noise, texture, cv::Size(1280, 960), 0, 0, cv::INTER_CUBIC);
  for (int i = 0; i < frames; ++i) {
    const cv::Rect roi((i * 3) % 640, (i * 2) % 480, 640, 480);
    char file[64];
    std::snprintf(file, sizeof(file), "/rgb/%06d.png", i);
    writeImage(dir + file, texture(roi));
  }
  return dir;
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
