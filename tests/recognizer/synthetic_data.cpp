#include "tests/recognizer/synthetic_data.h"

#include <cmath>
#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <random>

#include "common/dataset.h"
#include "common/image_codec.h"

namespace slamaware::test {

namespace fs = std::filesystem;

namespace {

cv::Scalar hueColour(double hue_deg, double sat, double val) {
  cv::Mat hsv(1, 1, CV_8UC3, cv::Scalar(hue_deg / 2.0, sat * 255, val * 255)), bgr;
  cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
  const cv::Vec3b c = bgr.at<cv::Vec3b>(0, 0);
  return cv::Scalar(c[0], c[1], c[2]);
}

}  // namespace

cv::Mat syntheticObjectView(const std::string& category, int instance, int view, int size) {
  std::mt19937 rng(
      static_cast<uint32_t>(1000 * instance + view + (category == "disc" ? 0 : 500000)));
  std::uniform_real_distribution<double> u(0, 1);
  cv::Mat img(size, size, CV_8UC3);
  // A neutral, slightly textured background shared by both categories.
  img.setTo(cv::Scalar(150 + 20 * u(rng), 150 + 20 * u(rng), 150 + 20 * u(rng)));
  cv::Mat noise(size, size, CV_8UC3);
  cv::randn(noise, 0, 6);
  img += noise;
  const cv::Point2d c(size / 2.0 + (u(rng) - 0.5) * size * 0.1,
                      size / 2.0 + (u(rng) - 0.5) * size * 0.1);
  const double scale = size * (0.30 + 0.04 * instance + 0.05 * u(rng));
  if (category == "disc") {
    // Reddish discs with a bright rim and a dark spot: round shapes, warm colours.
    const cv::Scalar colour = hueColour(5 + 12 * instance + 8 * u(rng), 0.8, 0.75);
    cv::circle(img, c, static_cast<int>(scale), colour, cv::FILLED, cv::LINE_AA);
    cv::circle(img, c, static_cast<int>(scale), hueColour(20, 0.3, 0.95), 2, cv::LINE_AA);
    cv::circle(img, c + cv::Point2d(scale * 0.3, -scale * 0.3), static_cast<int>(scale * 0.2),
               hueColour(0, 0.2, 0.25), cv::FILLED, cv::LINE_AA);
  } else {
    // Blue-green bars: straight parallel edges, cold colours.
    const cv::Scalar colour = hueColour(190 + 15 * instance + 10 * u(rng), 0.8, 0.7);
    const double angle = (u(rng) - 0.5) * 0.8 + 0.3 * instance;
    const cv::Point2d d(std::cos(angle), std::sin(angle)), n(-std::sin(angle), std::cos(angle));
    for (int k = -2; k <= 2; ++k) {
      const cv::Point2d o = c + n * (k * scale * 0.35);
      cv::line(img, o - d * scale, o + d * scale, k % 2 ? colour * 0.6 : colour,
               static_cast<int>(scale * 0.18), cv::LINE_AA);
    }
  }
  cv::GaussianBlur(img, img, cv::Size(3, 3), 0.6);
  return img;
}

std::string makeSyntheticObjectSet(const std::string& dir, int instances, int views, int size) {
  for (const std::string category : {"disc", "bar"})
    for (int i = 1; i <= instances; ++i) {
      const std::string inst = category + "_" + std::to_string(i);
      const fs::path folder = fs::path(dir) / category / inst;
      fs::create_directories(folder);
      for (int v = 0; v < views; ++v)
        writeImage((folder / (inst + "_1_" + std::to_string(v) + "_crop.png")).string(),
                   syntheticObjectView(category, i, v, size));
    }
  return dir;
}

cv::Mat texturedFrame(int seed, int width, int height) {
  std::mt19937 rng(static_cast<uint32_t>(seed));
  cv::Mat coarse(height / 16, width / 16, CV_8UC3), img;
  cv::randu(coarse, 0, 255);
  cv::resize(coarse, img, cv::Size(width, height), 0, 0, cv::INTER_CUBIC);
  std::uniform_int_distribution<int> x(0, width - 1), y(0, height - 1), r(5, 60), col(0, 255);
  for (int k = 0; k < 40; ++k)
    cv::rectangle(img, cv::Rect(x(rng), y(rng), r(rng), r(rng)),
                  cv::Scalar(col(rng), col(rng), col(rng)), cv::FILLED);
  for (int k = 0; k < 30; ++k)
    cv::line(img, {x(rng), y(rng)}, {x(rng), y(rng)}, cv::Scalar(col(rng), col(rng), col(rng)), 2,
             cv::LINE_AA);
  cv::Mat noise(height, width, CV_8UC3);
  cv::randn(noise, 0, 8);
  img += noise;
  return img;
}

std::string makeSyntheticScenes(const std::string& dir, int frames) {
  fs::create_directories(fs::path(dir) / "rgb");
  SequenceInfo info;
  info.name = fs::path(dir).filename().string();
  info.source = "synthetic test scenes";
  info.fps = 10;
  info.frames = frames;
  info.camera = CameraModel(320, 240, 300, 300, 159.5, 119.5);
  info.classes = {"disc", "bar"};
  writeSequenceInfo((fs::path(dir) / "sequence.yaml").string(), info);
  std::vector<GroundTruthBox> boxes;
  for (int f = 0; f < frames; ++f) {
    cv::Mat img = texturedFrame(100 + f, 320, 240);
    const std::string category = f % 2 ? "bar" : "disc";
    const cv::Mat obj = syntheticObjectView(category, 1 + f % 3, 50 + f, 72);
    const cv::Rect r(40 + (37 * f) % 200, 30 + (23 * f) % 130, 72, 72);
    obj.copyTo(img(r));
    char name[32];
    std::snprintf(name, sizeof(name), "%06d.png", f);
    writeImage((fs::path(dir) / "rgb" / name).string(), img);
    GroundTruthBox b;
    b.frame = f;
    b.x = r.x;
    b.y = r.y;
    b.w = r.width;
    b.h = r.height;
    b.cls = category;
    b.instance = category + "_1";
    boxes.push_back(b);
  }
  writeBoxes((fs::path(dir) / "boxes.csv").string(), boxes);
  return dir;
}

}  // namespace slamaware::test
