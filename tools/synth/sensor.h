#pragma once
// The camera between the rendered radiance and the 8-bit image: motion blur over the shutter
// time (from the depth and the camera motion, exact for a static scene), the lens' blur,
// vignetting, gain and a soft shoulder, signal-dependent noise, quantisation.
#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core/mat.hpp>

#include "tools/synth/rasterizer.h"

namespace slamaware::synth {

struct SensorOptions {
  double gain = 1.0;           ///< multiplies the rendered radiance
  double read_noise = 1.5;     ///< DN (8-bit units), noise floor sigma
  double shot_noise = 0.05;    ///< DN: sigma^2 = read^2 + shot * signal(DN)
  double psf_sigma_px = 0.55;  ///< px, Gaussian blur of the optics
  double vignetting = 0.22;    ///< relative darkening in the image corners
  double shutter_s = 0.0;      ///< s, exposure time for motion blur (0: none)
  int jpeg_quality = 92;       ///< quality of the written / streamed JPEG frames

  template <class V>
  void visit(V& v) {
    v("gain", gain, "multiplies the rendered radiance");
    v("read_noise", read_noise, "DN, sigma of the noise floor (8-bit units)");
    v("shot_noise", shot_noise, "DN, signal-dependent noise: sigma^2 = read^2 + shot * signal");
    v("psf_sigma_px", psf_sigma_px, "px, Gaussian blur of the lens (0: none)");
    v("vignetting", vignetting, "relative darkening in the corners (0: none)");
    v("shutter_s", shutter_s, "s, shutter time for motion blur (0: none)");
    v("jpeg_quality", jpeg_quality, "quality of the JPEG frames, 1-100");
  }
};

/// For motion blur: where the camera was when the shutter opened.
struct ShutterMotion {
  bool enabled = false;
  Eigen::Isometry3d T_world_camera_open = Eigen::Isometry3d::Identity();
};

/// Turns a full-image render into an 8-bit BGR image. `noise_seed` fixes the noise (a function
/// of the scene seed and the frame index, so a frame is the same however it is reached).
cv::Mat applySensor(const FrameBuffers& fb, const Intrinsics& K,
                    const Eigen::Isometry3d& T_world_camera, const SensorOptions& options,
                    const ShutterMotion& motion, uint64_t noise_seed);

}  // namespace slamaware::synth
