#pragma once
#include <string>

#include "common/frame_source.h"

namespace slamaware::camera {

struct CameraOptions {
  std::string pixel_format = "jpeg";  ///< jpeg or rgb8
  int jpeg_quality = 90;
  bool passthrough_jpeg = true;  ///< publish .jpg files as they are (no second compression)
  double info_rate_hz = 1.0;     ///< CAMERA_INFO rate
  std::string frame_id = "camera";
  SourceOptions source;

  template <class V>
  void visit(V& v) {
    v("pixel_format", pixel_format, "jpeg or rgb8");
    v("jpeg_quality", jpeg_quality, "JPEG quality of published frames, 1-100");
    v("passthrough_jpeg", passthrough_jpeg, "publish .jpg frames of a sequence folder as they are");
    v("info_rate_hz", info_rate_hz, "Hz, CAMERA_INFO rate");
    v("frame_id", frame_id, "name of the camera frame in CAMERA_INFO");
    v.section("source", source,
              "intrinsics for video files and V4L devices (sequence folders carry their own)");
  }
};

}  // namespace slamaware::camera
