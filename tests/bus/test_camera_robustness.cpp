// Malformed messages on every channel the camera subscribes to (its lockstep answer channel and
// the start channels it waits for) leave it running and are counted in CAMERA_STATUS; corrupt
// and missing frames of a sequence are reported and skipped. Private network namespace.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <thread>

#include "common/bus/bus.h"
#include "slamaware/image_t.hpp"
#include "slamaware/pose_t.hpp"
#include "slamaware/status_t.hpp"
#include "tests/support/test_support.h"

using namespace slamaware;
using namespace std::chrono_literals;

namespace {

std::vector<uint8_t> encodePose(int32_t seq) {
  pose_t p{};
  p.utime = seq * 1000;
  p.seq = seq;
  std::vector<uint8_t> b(p.getEncodedSize());
  p.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

std::vector<std::vector<uint8_t>> malformedSet() {
  const std::vector<uint8_t> good = encodePose(3);
  std::vector<std::vector<uint8_t>> bad;
  bad.emplace_back(good.begin(), good.end() - 4);  // truncated
  std::vector<uint8_t> wrong = good;
  wrong[0] ^= 0x55;  // wrong fingerprint
  bad.push_back(wrong);
  std::vector<uint8_t> trailing = good;
  trailing.push_back(9);  // trailing bytes
  bad.push_back(trailing);
  status_t s{};  // a huge length field
  s.num_counters = 0;
  std::vector<uint8_t> st(s.getEncodedSize());
  s.encode(st.data(), 0, static_cast<int>(st.size()));
  bad.push_back(st);  // not a per-frame message at all
  std::mt19937 rng(3);
  std::vector<uint8_t> random(200);
  for (auto& b : random) b = static_cast<uint8_t>(rng());
  bad.push_back(random);  // random bytes
  image_t img{};
  img.size = 0;
  std::vector<uint8_t> ib(img.getEncodedSize());
  img.encode(ib.data(), 0, static_cast<int>(ib.size()));
  ib[8 + 8 + 4 + 4 + 4 + 1] = 0x7f;  // image size field = 2^31-ish
  bad.push_back(ib);
  return bad;
}

}  // namespace

TEST(CameraRobustness, MalformedMessagesAreCountedAndTheCameraKeepsRunning) {
  const std::string seq_dir = test::makeTestSequence("camera_malformed", 8, 30.0);
  Bus bus(test::testUrl());
  std::vector<status_t> statuses;
  std::vector<int32_t> frames;
  bus.subscribe<status_t>("CAMERA_STATUS", [&](const status_t& s) { statuses.push_back(s); });
  bus.subscribe<image_t>(
      "CAMERA", [&](const image_t& m) { frames.push_back(m.seq); }, 16 << 20);
  test::ChildProcess camera({test::binPath("slamaware-camera"), "--source", seq_dir, "--lcm-url",
                             test::testUrl(), "--lockstep", "ACK", "--wait-for", "GO"},
                            test::tempDir("camera_malformed_log") + "/camera.txt");
  // The camera is waiting for GO; its first heartbeat says it is up.
  ASSERT_TRUE(test::waitUntil(
      [&] {
        bus.handle(10);
        return !statuses.empty();
      },
      10s))
      << camera.log();
  const auto bad = malformedSet();
  for (const auto& b : bad) {
    bus.publishRaw("ACK", b.data(), b.size());
    bus.publishRaw("GO", b.data(), b.size());  // anything on GO counts as "up": not validated
  }
  // Now answer every frame properly.
  const auto start = std::chrono::steady_clock::now();
  size_t answered = 0;
  while (frames.size() < 8 && std::chrono::steady_clock::now() - start < 20s) {
    bus.handle(10);
    while (answered < frames.size()) {
      const auto ack = encodePose(frames[answered++]);
      bus.publishRaw("ACK", ack.data(), ack.size());
    }
  }
  ASSERT_EQ(frames.size(), 8u) << camera.log();
  for (int i = 0; i < 8; ++i) EXPECT_EQ(frames[i], i);
  const auto ack = encodePose(7);
  bus.publishRaw("ACK", ack.data(), ack.size());
  EXPECT_EQ(camera.wait(10s), 0) << "the camera must finish normally after malformed answers\n"
                                 << camera.log();
  test::waitUntil([&] { return bus.handle(10) <= 0 && false; }, 300ms);
  ASSERT_FALSE(statuses.empty());
  const status_t& last = statuses.back();
  int64_t rejected_ack = -1;
  for (int i = 0; i < last.num_counters; ++i)
    if (last.counter_names[i] == "rejected.ACK") rejected_ack = last.counter_values[i];
  EXPECT_EQ(rejected_ack, static_cast<int64_t>(bad.size())) << "every malformed answer is counted";
  EXPECT_EQ(last.rejected, static_cast<int64_t>(bad.size()));
}

TEST(CameraRobustness, CorruptAndMissingFramesAreReportedAndSkipped) {
  const std::string seq_dir = test::makeTestSequence("camera_corrupt", 6, 30.0);
  {  // frame 2: truncated PNG; frame 4: not an image at all
    std::filesystem::resize_file(seq_dir + "/rgb/000002.png", 500);
    std::ofstream(seq_dir + "/rgb/000004.png") << "not an image";
  }
  Bus bus(test::testUrl());
  std::vector<int32_t> frames;
  std::vector<status_t> statuses;
  bus.subscribe<image_t>(
      "CAMERA", [&](const image_t& m) { frames.push_back(m.seq); }, 16 << 20);
  bus.subscribe<status_t>("CAMERA_STATUS", [&](const status_t& s) { statuses.push_back(s); });
  test::ChildProcess camera({test::binPath("slamaware-camera"), "--source", seq_dir, "--lcm-url",
                             test::testUrl(), "--speed", "0"},
                            test::tempDir("camera_corrupt_log") + "/camera.txt");
  std::atomic<bool> done{false};
  EXPECT_EQ(camera.wait(20s), 0) << camera.log();
  test::waitUntil(
      [&] {
        bus.handle(20);
        return false;
      },
      500ms);
  EXPECT_EQ(frames, (std::vector<int32_t>{0, 1, 3, 5}))
      << "seq stays the frame index; bad frames are skipped";
  const std::string log = camera.log();
  EXPECT_NE(log.find("skipping frame 2"), std::string::npos) << log;
  EXPECT_NE(log.find("000004.png"), std::string::npos) << log;
  ASSERT_FALSE(statuses.empty());
  int64_t corrupt = -1;
  for (int i = 0; i < statuses.back().num_counters; ++i)
    if (statuses.back().counter_names[i] == "frames_corrupt")
      corrupt = statuses.back().counter_values[i];
  EXPECT_EQ(corrupt, 2);
}

TEST(CameraRobustness, BadSourceIsAClearError) {
  test::ChildProcess camera({test::binPath("slamaware-camera"), "--source", "no/such/folder",
                             "--lcm-url", test::testUrl()},
                            test::tempDir("camera_badsrc") + "/camera.txt");
  EXPECT_EQ(camera.wait(10s), 2);
  EXPECT_NE(camera.log().find("no/such/folder"), std::string::npos) << camera.log();
}
