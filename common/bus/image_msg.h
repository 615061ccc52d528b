#pragma once
// image_t <-> cv::Mat (8-bit BGR in memory, as everywhere in OpenCV); camera_info_t -> camera.
#include <opencv2/core/mat.hpp>
#include <string>

#include "common/camera_model.h"
#include "common/image_codec.h"
#include "slamaware/camera_info_t.hpp"
#include "slamaware/image_t.hpp"

namespace slamaware {

/// Builds an image message: JPEG at `jpeg_quality`, or raw RGB8 / GRAY8.
image_t makeImageMessage(const cv::Mat& bgr, int64_t utime, int32_t seq, int8_t pixel_format,
                         int jpeg_quality = 90);
/// A message whose image is not of the size the receiver's camera has.
class ImageSizeError : public ImageError {
 public:
  using ImageError::ImageError;
};

/// Decodes an image message into 8-bit BGR (or grey). Throws ImageError naming `what` (e.g. the
/// channel and seq) when the data is corrupt or does not match width/height/format, and
/// ImageSizeError, before anything is decoded, when `camera` is not empty and the message is of
/// another size (a message of a few bytes must not make a receiver decode a large image it would
/// refuse anyway).
cv::Mat decodeImageMessage(const image_t& msg, const std::string& what, bool grey = false,
                           cv::Size camera = cv::Size());

/// The camera a camera_info_t describes; false (and *why) when it is not a usable camera.
bool cameraFromMessage(const camera_info_t& info, CameraModel* camera, std::string* why);

}  // namespace slamaware
