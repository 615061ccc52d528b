// The camera streams 300 VGA frames at 30 Hz; a subscriber and lcm-logger receive all of them,
// in seq order, byte-identical to a direct encode. Runs in a private network namespace.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "common/bus/bus.h"
#include "common/bus/image_msg.h"
#include "common/bus/log_reader.h"
#include "common/dataset.h"
#include "common/image_codec.h"
#include "tests/support/test_support.h"

using namespace slamaware;
using namespace std::chrono_literals;

namespace {
std::vector<uint8_t> encodeMessage(const image_t& m) {
  std::vector<uint8_t> b(m.getEncodedSize());
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}
}  // namespace

TEST(CameraStream, ThreeHundredVgaFramesAt30HzArriveIntactAndInOrder) {
  constexpr int kFrames = 300;
  const std::string seq_dir = test::makeTestSequence("camera_stream", kFrames, 30.0);
  const std::string log_path = test::tempDir("camera_stream_log") + "/session.lcm";

  Bus bus(test::testUrl());
  std::vector<std::vector<uint8_t>> received;
  bus.subscribeRaw(
      "CAMERA", [&](const Bus::RawMessage& m) { received.emplace_back(m.data, m.data + m.size); },
      16 << 20);
  std::atomic<bool> stop{false};
  std::thread listener([&] {
    while (!stop) bus.handle(50);
  });
  test::BusRecorder recorder(log_path);
  test::ChildProcess camera(
      {test::binPath("slamaware-camera"), "--source", seq_dir, "--lcm-url", test::testUrl()},
      log_path + ".camera.txt");
  const int rc = camera.wait(60s);
  std::this_thread::sleep_for(300ms);
  stop = true;
  listener.join();
  recorder.stop();
  ASSERT_EQ(rc, 0) << camera.log();

  // The expected messages: the frames encoded directly with the camera's default JPEG quality.
  const SequenceFolder seq = SequenceFolder::open(seq_dir);
  std::vector<std::vector<uint8_t>> expected;
  for (int i = 0; i < kFrames; ++i) {
    const cv::Mat img = readImage(seq.framePath(i));
    const int64_t utime = static_cast<int64_t>(std::llround(seq.timestamp(i) * 1e6));
    expected.push_back(
        encodeMessage(makeImageMessage(img, utime, i, image_t::PIXEL_FORMAT_JPEG, 90)));
  }

  ASSERT_EQ(received.size(), static_cast<size_t>(kFrames))
      << "frames lost on the way to the subscriber";
  for (int i = 0; i < kFrames; ++i)
    ASSERT_EQ(received[i], expected[i]) << "frame " << i << " differs";

  std::vector<LogRecord> logged;
  for (auto& ev : LogReader::readAll(log_path))
    if (ev.channel == "CAMERA") logged.push_back(std::move(ev));
  ASSERT_EQ(logged.size(), static_cast<size_t>(kFrames)) << "frames lost on the way to lcm-logger";
  for (int i = 0; i < kFrames; ++i)
    ASSERT_EQ(logged[i].data, expected[i]) << "logged frame " << i << " differs";
  std::printf("frames sent %d, received by the subscriber %zu, by lcm-logger %zu\n", kFrames,
              received.size(), logged.size());
}
