#pragma once
// The "log" camera source: an LCM log (lcm-logger format) played as a camera. Its CAMERA_INFO
// gives the intrinsics; its CAMERA frames keep their utime and seq (+ loops x length when looping)
// and their JPEG bytes.
//   log:PATH, or any PATH ending in .lcm
#include "common/frame_source.h"

namespace slamaware::camera {

/// Registers the "log" scheme with the source registry (common/frame_source.h).
void registerLogSource();

}  // namespace slamaware::camera
