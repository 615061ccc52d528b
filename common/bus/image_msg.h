#pragma once
// image_t <-> cv::Mat (8-bit BGR in memory, as everywhere in OpenCV); camera_info_t -> camera.
#include <opencv2/core/mat.hpp>
#include <string>

#include "common/camera_model.h"
#include "slamaware/camera_info_t.hpp"
#include "slamaware/image_t.hpp"

namespace slamaware {

/// Builds an image message: JPEG at `jpeg_quality`, or raw RGB8 / GRAY8.
image_t makeImageMessage(const cv::Mat& bgr, int64_t utime, int32_t seq, int8_t pixel_format,
                         int jpeg_quality = 90);
/// Decodes an image message into 8-bit BGR (or grey). Throws ImageError naming `what` (e.g. the
/// channel and seq) when the data is corrupt or does not match width/height/format.
cv::Mat decodeImageMessage(const image_t& msg, const std::string& what, bool grey = false);

/// The camera a camera_info_t describes; false (and *why) when it is not a usable camera.
bool cameraFromMessage(const camera_info_t& info, CameraModel* camera, std::string* why);

}  // namespace slamaware
