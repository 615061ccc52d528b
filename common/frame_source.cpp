#include "common/frame_source.h"

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "common/dataset.h"
#include "common/image_codec.h"

namespace fs = std::filesystem;

namespace slamaware {

namespace {

CameraModel cameraFromOptions(const SourceOptions& o, int width, int height) {
  const int w = width > 0 ? width : o.width;
  const int h = height > 0 ? height : o.height;
  const double fx = o.fx > 0 ? o.fx : w;
  const double fy = o.fy > 0 ? o.fy : fx;
  const double cx = o.cx > 0 ? o.cx : (w - 1) / 2.0;
  const double cy = o.cy > 0 ? o.cy : (h - 1) / 2.0;
  std::array<double, 5> d{0, 0, 0, 0, 0};
  for (size_t i = 0; i < 5 && i < o.distortion.size(); ++i) d[i] = o.distortion[i];
  return CameraModel(w, h, fx, fy, cx, cy, d);
}

bool hasJpegExtension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (auto& c : ext) c = static_cast<char>(::tolower(c));
  return ext == ".jpg" || ext == ".jpeg";
}

class SequenceSource : public FrameSource {
 public:
  explicit SequenceSource(const std::string& dir) {
    try {
      seq_ = SequenceFolder::open(dir);
    } catch (const DatasetError& e) {
      throw SourceError(e.what());
    }
    duration_us_ = static_cast<int64_t>(std::llround(
        (seq_.timestamp(seq_.size() - 1) - seq_.timestamp(0)) * 1e6 + 1e6 / seq_.info().fps));
  }
  const CameraModel& camera() const override { return seq_.info().camera; }
  double fps() const override { return seq_.info().fps; }
  int64_t length() const override { return static_cast<int64_t>(seq_.size()); }
  std::string describe() const override { return seq_.dir(); }

  bool next(SourceFrame* f) override {
    if (index_ >= seq_.size()) return false;
    const size_t i = index_++;
    f->seq = static_cast<int32_t>(i + loops_ * seq_.size());
    f->utime = static_cast<int64_t>(std::llround(seq_.timestamp(i) * 1e6)) + loops_ * duration_us_;
    f->error.clear();
    f->jpeg.clear();
    const std::string& path = seq_.framePath(i);
    try {
      std::ifstream in(path, std::ios::binary);
      if (!in) throw ImageError(path + ": cannot open frame");
      std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), {});
      f->bgr = decodeImage(bytes.data(), bytes.size(), path);
      if (f->bgr.cols != camera().width() || f->bgr.rows != camera().height())
        throw ImageError(path + ": frame is " + std::to_string(f->bgr.cols) + "x" +
                         std::to_string(f->bgr.rows) + ", sequence.yaml says " +
                         std::to_string(camera().width()) + "x" +
                         std::to_string(camera().height()));
      if (hasJpegExtension(path)) f->jpeg = std::move(bytes);
    } catch (const ImageError& e) {
      f->bgr.release();
      f->error = e.what();
    }
    return true;
  }
  bool rewind() override {
    index_ = 0;
    ++loops_;
    return true;
  }

 private:
  SequenceFolder seq_;
  size_t index_ = 0;
  int64_t loops_ = 0;
  int64_t duration_us_ = 0;
};

class VideoSource : public FrameSource {
 public:
  VideoSource(const std::string& spec, const SourceOptions& options, bool device, int device_index)
      : spec_(spec), device_(device) {
    if (device)
      cap_.open(device_index, cv::CAP_V4L2);
    else
      cap_.open(spec, cv::CAP_FFMPEG);
    if (!cap_.isOpened())
      throw SourceError(spec + ": cannot open " + (device ? "video device" : "video file"));
    if (device) {
      cap_.set(cv::CAP_PROP_FRAME_WIDTH, options.width);
      cap_.set(cv::CAP_PROP_FRAME_HEIGHT, options.height);
    }
    const int w = static_cast<int>(cap_.get(cv::CAP_PROP_FRAME_WIDTH));
    const int h = static_cast<int>(cap_.get(cv::CAP_PROP_FRAME_HEIGHT));
    fps_ = cap_.get(cv::CAP_PROP_FPS);
    if (!(fps_ > 0 && fps_ < 1000)) fps_ = 30.0;
    frames_ = device ? -1 : static_cast<int64_t>(cap_.get(cv::CAP_PROP_FRAME_COUNT));
    camera_ = cameraFromOptions(options, w, h);
  }
  const CameraModel& camera() const override { return camera_; }
  double fps() const override { return fps_; }
  int64_t length() const override { return frames_; }
  bool live() const override { return device_; }
  std::string describe() const override { return spec_; }

  bool next(SourceFrame* f) override {
    cv::Mat img;
    if (!cap_.read(img) || img.empty()) {
      if (device_) {
        f->error = spec_ + ": device returned no frame";
        f->bgr.release();
        f->seq = static_cast<int32_t>(index_++);
        return ++device_failures_ < 100;  // give up after 100 failures in a row
      }
      return false;
    }
    device_failures_ = 0;
    if (img.channels() == 1) cv::cvtColor(img, img, cv::COLOR_GRAY2BGR);
    f->error.clear();
    f->jpeg.clear();
    f->bgr = img;
    f->seq = static_cast<int32_t>(index_);
    if (device_) {
      f->utime = std::chrono::duration_cast<std::chrono::microseconds>(
                     std::chrono::system_clock::now().time_since_epoch())
                     .count();
    } else {
      f->utime = static_cast<int64_t>(std::llround(index_ * 1e6 / fps_));
    }
    ++index_;
    return true;
  }
  bool rewind() override {
    if (device_) return false;
    return cap_.set(cv::CAP_PROP_POS_FRAMES, 0);  // seq and utime keep increasing
  }

 private:
  std::string spec_;
  bool device_;
  cv::VideoCapture cap_;
  CameraModel camera_;
  double fps_ = 30;
  int64_t frames_ = -1;
  int64_t index_ = 0;
  int device_failures_ = 0;
};

std::mutex g_schemes_mutex;
std::map<std::string, SourceFactory>& schemes() {
  static std::map<std::string, SourceFactory> m;
  return m;
}

}  // namespace

void registerSourceScheme(const std::string& scheme, SourceFactory factory) {
  std::lock_guard<std::mutex> lock(g_schemes_mutex);
  schemes()[scheme] = std::move(factory);
}

namespace {

// The registered source of `scheme` opened on `arg`; SourceError naming `spec` if none is.
std::unique_ptr<FrameSource> openScheme(const std::string& spec, const std::string& scheme,
                                        const std::string& arg) {
  std::lock_guard<std::mutex> lock(g_schemes_mutex);
  auto it = schemes().find(scheme);
  if (it == schemes().end())
    throw SourceError(spec + (scheme == "log" ? ": LCM logs are not a source in this program"
                                              : ": unknown source scheme '" + scheme + ":'"));
  return it->second(arg);
}

}  // namespace

std::unique_ptr<FrameSource> openSource(const std::string& spec, const SourceOptions& options) {
  if (spec.empty()) throw SourceError("no --source given");
  if (spec.rfind("v4l:", 0) == 0) {
    int index = -1;
    try {
      index = std::stoi(spec.substr(4));
    } catch (const std::exception&) {
      throw SourceError(spec + ": expected v4l:N with N the device number (/dev/videoN)");
    }
    return std::make_unique<VideoSource>(spec, options, true, index);
  }
  const size_t colon = spec.find(':');
  if (colon != std::string::npos && colon > 1 && !fs::exists(spec))
    return openScheme(spec, spec.substr(0, colon), spec.substr(colon + 1));
  if (fs::is_directory(spec)) return std::make_unique<SequenceSource>(spec);
  // Logs are read by the bus layer: the camera registers the "log" scheme.
  if (fs::path(spec).extension() == ".lcm") return openScheme(spec, "log", spec);
  if (fs::is_regular_file(spec)) return std::make_unique<VideoSource>(spec, options, false, -1);
  throw SourceError(spec + ": no such sequence folder or video file");
}

}  // namespace slamaware
