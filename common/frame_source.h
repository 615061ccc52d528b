#pragma once
// Where camera frames come from: a sequence folder (DATASETS.md §1), a video file, a V4L
// device, or a registered scheme: an LCM log (registered by the camera, "log:PATH" or any
// *.lcm path) or a rendered scene (registered by the synthetic generator, "synth:CONFIG"). The
// camera node paces and publishes what a FrameSource yields; this library knows nothing of LCM.
#include <functional>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <stdexcept>
#include <string>

#include "common/camera_model.h"

namespace slamaware {

struct SourceFrame {
  int64_t utime = 0;          ///< µs, capture time (sequence time; wall time for live devices)
  int32_t seq = 0;            ///< frame index in the source (+ loops * length when looping)
  cv::Mat bgr;                ///< 8-bit BGR; empty when the frame could not be read
  std::vector<uint8_t> jpeg;  ///< the original JPEG bytes when the source file was a JPEG
  std::string error;          ///< why the frame could not be read ("" if it could)
};

class SourceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  /// Intrinsics of the frames.
  virtual const CameraModel& camera() const = 0;
  /// Nominal frame rate (Hz).
  virtual double fps() const = 0;
  /// Frames in one pass, or -1 for a live or endless source.
  virtual int64_t length() const = 0;
  /// True for devices: frames come at the device's rate, pacing is the device's.
  virtual bool live() const { return false; }
  /// Reads the next frame; false at the end. A frame that cannot be read is returned with
  /// `error` set and an empty image (the caller reports and skips it).
  virtual bool next(SourceFrame* frame) = 0;
  /// Starts again from the first frame (for --loop); false if the source cannot.
  virtual bool rewind() = 0;
  /// A description for logs and camera_info_t.source.
  virtual std::string describe() const = 0;
};

struct SourceOptions {
  /// Intrinsics for video files and devices (sequence folders carry their own).
  int width = 640, height = 480;
  double fx = 0, fy = 0, cx = 0, cy = 0;  ///< 0: guessed (fx = fy = width, centre of the image)
  std::vector<double> distortion = {0, 0, 0, 0, 0};

  template <class V>
  void visit(V& v) {
    v("width", width, "px, frame width for video files and devices");
    v("height", height, "px, frame height for video files and devices");
    v("fx", fx, "px, focal length for video files and devices (0: width, a ~53 deg field of view)");
    v("fy", fy, "px (0: same as fx)");
    v("cx", cx, "px (0: image centre)");
    v("cy", cy, "px (0: image centre)");
    v("distortion", distortion, "k1 k2 p1 p2 k3 for video files and devices");
  }
};

/// Makes a source from a --source argument: a sequence folder, a video file, "v4l:N",
/// "<scheme>:ARG" for a registered scheme, or a *.lcm path (the "log" scheme). Throws SourceError
/// naming the argument.
std::unique_ptr<FrameSource> openSource(const std::string& spec, const SourceOptions& options);

/// Lets another part add a source scheme (e.g. the synthetic generator: "synth:CONFIG").
using SourceFactory = std::function<std::unique_ptr<FrameSource>(const std::string& arg)>;
void registerSourceScheme(const std::string& scheme, SourceFactory factory);

}  // namespace slamaware
