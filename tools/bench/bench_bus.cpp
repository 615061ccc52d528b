// slamaware-bench-bus: costs of moving camera frames: JPEG encode/decode of a VGA frame and the
// publish-to-receive time of a VGA frame over the LCM bus (run inside scripts/netns-run).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "common/bus/bus.h"
#include "common/bus/image_msg.h"
#include "common/bus/system_config.h"
#include "common/image_codec.h"

using namespace slamaware;
using Clock = std::chrono::steady_clock;

namespace {
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}
double ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// A textured VGA test frame: smooth colour gradients plus noise at several scales (JPEG cost
// depends on texture; a flat frame would flatter the codec).
cv::Mat testFrame() {
  std::mt19937 rng(7);
  cv::Mat img(480, 640, CV_8UC3);
  cv::Mat noise(60, 80, CV_8UC3);
  cv::randu(noise, 0, 255);
  cv::resize(noise, img, img.size(), 0, 0, cv::INTER_CUBIC);
  cv::Mat fine(480, 640, CV_8UC3);
  cv::randn(fine, 0, 12);
  img += fine;
  return img;
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"slamaware-bench-bus: JPEG and bus costs of VGA frames"};
  std::string out;
  int n = 100;
  app.add_option("--out", out, "JSON file to write")->required();
  app.add_option("--frames", n, "frames per measurement");
  CLI11_PARSE(app, argc, argv);

  const cv::Mat frame = testFrame();
  std::vector<double> enc, dec, bus_ms;
  std::vector<uint8_t> jpeg;
  for (int i = 0; i < n; ++i) {
    auto t0 = Clock::now();
    jpeg = encodeJpeg(frame, 90);
    auto t1 = Clock::now();
    cv::Mat back = decodeImage(jpeg.data(), jpeg.size(), "bench");
    auto t2 = Clock::now();
    enc.push_back(ms(t0, t1));
    dec.push_back(ms(t1, t2));
  }
  nlohmann::json j;
  j["jpeg_encode_ms_vga"] = median(enc);
  j["jpeg_decode_ms_vga"] = median(dec);
  j["jpeg_bytes_vga_q90"] = jpeg.size();
  try {
    Bus bus(BusOptions().url);
    Clock::time_point sent;
    bool got = false;
    bus.subscribe<image_t>(
        "BENCH_CAMERA",
        [&](const image_t&) {
          bus_ms.push_back(ms(sent, Clock::now()));
          got = true;
        },
        16 << 20);
    const image_t msg = makeImageMessage(frame, 0, 0, image_t::PIXEL_FORMAT_JPEG, 90);
    for (int i = 0; i < n; ++i) {
      got = false;
      sent = Clock::now();
      bus.publish("BENCH_CAMERA", msg);
      while (!got && ms(sent, Clock::now()) < 1000) bus.handle(100);
    }
    j["bus_vga_jpeg_publish_to_receive_ms"] = median(bus_ms);
    j["bus_vga_frames_lost"] = n - static_cast<int>(bus_ms.size());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench-bus: no bus (%s); bus keys left out\n", e.what());
  }
  std::ofstream(out) << j.dump(2) << "\n";
  std::printf("%s\n", j.dump().c_str());
  return 0;
}
