// Recording and replay: a recorded camera session replayed lockstep twice gives byte-identical
// payloads in the same order; a damaged log is reported with its byte offset. Private netns.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "common/bus/log_reader.h"
#include "tests/support/test_support.h"

using namespace slamaware;
using namespace std::chrono_literals;

namespace {

std::vector<std::vector<uint8_t>> payloads(const std::string& log, const std::string& channel) {
  std::vector<std::vector<uint8_t>> out;
  for (auto& ev : LogReader::readAll(log))
    if (ev.channel == channel) out.push_back(std::move(ev.data));
  return out;
}

std::string recordSession(const std::string& dir, int frames) {
  // A sequence of its own per test: the tests of this file run in parallel.
  const std::string seq_dir =
      test::makeTestSequence(std::filesystem::path(dir).filename().string() + "_seq", frames, 30.0);
  const std::string log = dir + "/session.lcm";
  test::BusRecorder recorder(log);
  test::ChildProcess camera({test::binPath("slamaware-camera"), "--source", seq_dir, "--lcm-url",
                             test::testUrl(), "--speed", "4"},
                            dir + "/camera.txt");
  EXPECT_EQ(camera.wait(30s), 0) << camera.log();
  recorder.stop();
  return log;
}

}  // namespace

TEST(Replay, LockstepReplayTwiceIsByteIdentical) {
  const std::string dir = test::tempDir("replay_lockstep");
  const std::string log = recordSession(dir, 40);
  const auto original = payloads(log, "CAMERA");
  ASSERT_EQ(original.size(), 40u);
  std::vector<std::vector<std::vector<uint8_t>>> runs;
  for (int run = 0; run < 2; ++run) {
    const std::string out = dir + "/replay" + std::to_string(run) + ".lcm";
    test::BusRecorder recorder(out, "CAMERA.*");
    // The replayer is its own last stage here: each frame waits until it is seen on CAMERA. At
    // the camera's rate, not as fast as possible: 40 frames in a burst are more than the recorder
    // keeps (BusRecorder; a loaded machine lost frames 32-39).
    test::ChildProcess replay({test::binPath("slamaware-replay"), log, "--lcm-url", test::testUrl(),
                               "--lockstep", "CAMERA", "--speed", "1"},
                              dir + "/replay" + std::to_string(run) + ".txt");
    ASSERT_EQ(replay.wait(60s), 0) << replay.log();
    recorder.stop();
    runs.push_back(payloads(out, "CAMERA"));
    EXPECT_NE(replay.log().find("replayed"), std::string::npos);
  }
  ASSERT_EQ(runs[0].size(), original.size());
  EXPECT_EQ(runs[0], original);
  EXPECT_EQ(runs[0], runs[1]);
}

TEST(Replay, DamagedLogIsReportedWithByteOffset) {
  const std::string dir = test::tempDir("replay_damaged");
  const std::string log = recordSession(dir, 10);
  const auto size = std::filesystem::file_size(log);
  std::filesystem::resize_file(log, size - 100);
  test::ChildProcess replay(
      {test::binPath("slamaware-replay"), log, "--lcm-url", test::testUrl(), "--speed", "0"},
      dir + "/replay.txt");
  EXPECT_EQ(replay.wait(30s), 3) << replay.log();
  EXPECT_NE(replay.log().find("byte offset"), std::string::npos) << replay.log();
}

// A log as the camera's source: the frames come out again byte for byte (JPEG passes through,
// utime and seq are the recorded ones), paced by the camera, lockstep-able like any source.
TEST(Replay, CameraPlaysALogAsItsSource) {
  const std::string dir = test::tempDir("replay_camera_log");
  const std::string log = recordSession(dir, 12);
  const auto original = payloads(log, "CAMERA");
  ASSERT_EQ(original.size(), 12u);
  const std::string out = dir + "/played.lcm";
  {
    test::BusRecorder recorder(out, "CAMERA.*");
    test::ChildProcess camera({test::binPath("slamaware-camera"), "--source", log, "--lcm-url",
                               test::testUrl(), "--speed", "0", "--lockstep", "CAMERA"},
                              dir + "/played.txt");
    ASSERT_EQ(camera.wait(30s), 0) << camera.log();
    EXPECT_NE(camera.log().find("12 frames"), std::string::npos) << camera.log();
  }
  EXPECT_EQ(payloads(out, "CAMERA"), original);
  EXPECT_FALSE(payloads(out, "CAMERA_INFO").empty());

  // A damaged log: the frames before the damage are played, the damage is reported.
  std::filesystem::resize_file(log, std::filesystem::file_size(log) - 100);
  test::ChildProcess damaged({test::binPath("slamaware-camera"), "--source", log, "--lcm-url",
                              test::testUrl(), "--speed", "0"},
                             dir + "/damaged.txt");
  EXPECT_EQ(damaged.wait(30s), 0) << damaged.log();
  EXPECT_NE(damaged.log().find("byte offset"), std::string::npos) << damaged.log();
  // A file that is not a log at all is a clear error.
  const std::string bogus = dir + "/bogus.lcm";
  std::ofstream(bogus) << "not a log";
  test::ChildProcess bad(
      {test::binPath("slamaware-camera"), "--source", bogus, "--lcm-url", test::testUrl()},
      dir + "/bogus.txt");
  EXPECT_EQ(bad.wait(10s), 2) << bad.log();
  EXPECT_NE(bad.log().find("bogus.lcm"), std::string::npos) << bad.log();
}
