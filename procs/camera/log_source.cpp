#include "procs/camera/log_source.h"

#include "common/bus/frame_stamp.h"
#include "common/bus/image_msg.h"
#include "common/bus/log_reader.h"

namespace slamaware::camera {

namespace {

// An LCM log (lcm-logger format) as a camera: its CAMERA_INFO gives the intrinsics, its CAMERA
// frames are published again with their own utime and seq (JPEG bytes pass through).
class LogSource : public FrameSource {
 public:
  explicit LogSource(const std::string& path) : path_(path) {
    // One pass to find the intrinsics, the frame count and the time span (for --loop).
    int64_t first = -1, last = -1;
    bool have_info = false;
    try {
      LogReader reader(path);
      while (auto ev = reader.next()) {
        if (ev->channel == kInfoChannel && !have_info) {
          camera_info_t info{};
          if (info.decode(ev->data.data(), 0, static_cast<int>(ev->data.size())) !=
              static_cast<int>(ev->data.size()))
            continue;
          std::string why;
          have_info = cameraFromMessage(info, &camera_, &why);
        } else if (ev->channel == kFrameChannel) {
          if (const auto st = peekFrameStamp(ev->data.data(), ev->data.size())) {
            if (first < 0) first = st->utime;
            last = st->utime;
            ++frames_;
          }
        }
      }
    } catch (const LogError& e) {
      if (frames_ == 0) throw SourceError(e.what());
      // The frames before the damage are played; next() reports the damage when it gets there.
    }
    if (frames_ == 0)
      throw SourceError(path + ": no " + std::string(kFrameChannel) + " messages in the log");
    if (!have_info)
      throw SourceError(path + ": no valid " + std::string(kInfoChannel) + " message in the log");
    fps_ = frames_ > 1 && last > first ? (frames_ - 1) * 1e6 / static_cast<double>(last - first)
                                       : 30.0;
    duration_us_ = last - first + static_cast<int64_t>(1e6 / fps_);
    reader_ = std::make_unique<LogReader>(path_);
  }
  const CameraModel& camera() const override { return camera_; }
  double fps() const override { return fps_; }
  int64_t length() const override { return frames_; }
  std::string describe() const override { return path_; }

  bool next(SourceFrame* f) override {
    if (!reader_) return false;
    f->error.clear();
    f->jpeg.clear();
    f->bgr.release();
    try {
      while (auto ev = reader_->next()) {
        if (ev->channel != kFrameChannel) continue;
        image_t msg{};
        const int n = static_cast<int>(ev->data.size());
        if (msg.decode(ev->data.data(), 0, n) != n) {
          f->error = path_ + ": undecodable " + std::string(kFrameChannel) + " message at " +
                     std::to_string(index_);
        } else {
          f->seq = static_cast<int32_t>(msg.seq + loops_ * frames_);
          f->utime = msg.utime + loops_ * duration_us_;
          try {
            f->bgr = decodeImageMessage(msg, path_ + " frame " + std::to_string(msg.seq));
            if (msg.pixel_format == image_t::PIXEL_FORMAT_JPEG) f->jpeg = std::move(msg.data);
          } catch (const std::exception& e) {
            f->error = e.what();
          }
        }
        ++index_;
        return true;
      }
    } catch (const LogError& e) {
      f->error = e.what();
      reader_.reset();
      return true;
    }
    reader_.reset();
    return false;
  }
  bool rewind() override {
    reader_ = std::make_unique<LogReader>(path_);
    ++loops_;
    return true;
  }

 private:
  static constexpr const char* kFrameChannel = "CAMERA";
  static constexpr const char* kInfoChannel = "CAMERA_INFO";
  std::string path_;
  std::unique_ptr<LogReader> reader_;
  CameraModel camera_;
  double fps_ = 30;
  int64_t frames_ = 0, index_ = 0, loops_ = 0, duration_us_ = 0;
};

}  // namespace

void registerLogSource() {
  registerSourceScheme("log",
                       [](const std::string& path) { return std::make_unique<LogSource>(path); });
}

}  // namespace slamaware::camera
