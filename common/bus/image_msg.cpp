#include "common/bus/image_msg.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "common/image_codec.h"

namespace slamaware {

image_t makeImageMessage(const cv::Mat& bgr, int64_t utime, int32_t seq, int8_t pixel_format,
                         int jpeg_quality) {
  image_t msg{};
  msg.utime = utime;
  msg.seq = seq;
  msg.width = bgr.cols;
  msg.height = bgr.rows;
  msg.pixel_format = pixel_format;
  if (pixel_format == image_t::PIXEL_FORMAT_JPEG) {
    msg.data = encodeJpeg(bgr, jpeg_quality);
  } else if (pixel_format == image_t::PIXEL_FORMAT_RGB8) {
    cv::Mat rgb;
    cv::cvtColor(bgr, rgb, bgr.channels() == 1 ? cv::COLOR_GRAY2RGB : cv::COLOR_BGR2RGB);
    msg.data.assign(rgb.data, rgb.data + rgb.total() * 3);
  } else if (pixel_format == image_t::PIXEL_FORMAT_GRAY8) {
    cv::Mat grey = bgr;
    if (bgr.channels() == 3) cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
    if (!grey.isContinuous()) grey = grey.clone();
    msg.data.assign(grey.data, grey.data + grey.total());
  } else {
    throw ImageError("makeImageMessage: unknown pixel format " + std::to_string(pixel_format));
  }
  msg.size = static_cast<int32_t>(msg.data.size());
  return msg;
}

cv::Mat decodeImageMessage(const image_t& msg, const std::string& what, bool grey,
                           cv::Size camera) {
  if (msg.width <= 0 || msg.height <= 0 || msg.width > 16384 || msg.height > 16384)
    throw ImageError(what + ": bad image size " + std::to_string(msg.width) + "x" +
                     std::to_string(msg.height));
  if (!camera.empty() && (msg.width != camera.width || msg.height != camera.height))
    throw ImageSizeError(what + ": frame is " + std::to_string(msg.width) + "x" +
                         std::to_string(msg.height) + " but the camera is " +
                         std::to_string(camera.width) + "x" + std::to_string(camera.height));
  cv::Mat out;
  switch (msg.pixel_format) {
    case image_t::PIXEL_FORMAT_JPEG: {
      // The header must agree with the message before anything is decoded (a small message must
      // not make the decoder allocate for another size); the decoder gives the header's size.
      return decodeImage(msg.data.data(), msg.data.size(), what, grey,
                         cv::Size(msg.width, msg.height));
    }
    case image_t::PIXEL_FORMAT_RGB8: {
      if (msg.data.size() != static_cast<size_t>(msg.width) * msg.height * 3)
        throw ImageError(what + ": RGB8 data has " + std::to_string(msg.data.size()) +
                         " bytes, expected " +
                         std::to_string(static_cast<size_t>(msg.width) * msg.height * 3));
      cv::Mat rgb(msg.height, msg.width, CV_8UC3, const_cast<uint8_t*>(msg.data.data()));
      cv::cvtColor(rgb, out, grey ? cv::COLOR_RGB2GRAY : cv::COLOR_RGB2BGR);
      return out;
    }
    case image_t::PIXEL_FORMAT_GRAY8: {
      if (msg.data.size() != static_cast<size_t>(msg.width) * msg.height)
        throw ImageError(what + ": GRAY8 data has " + std::to_string(msg.data.size()) +
                         " bytes, expected " +
                         std::to_string(static_cast<size_t>(msg.width) * msg.height));
      cv::Mat g(msg.height, msg.width, CV_8UC1, const_cast<uint8_t*>(msg.data.data()));
      if (grey) return g.clone();
      cv::cvtColor(g, out, cv::COLOR_GRAY2BGR);
      return out;
    }
    default:
      throw ImageError(what + ": unknown pixel format " + std::to_string(msg.pixel_format));
  }
}

bool cameraFromMessage(const camera_info_t& info, CameraModel* camera, std::string* why) {
  const bool finite = std::isfinite(info.fx) && std::isfinite(info.fy) && std::isfinite(info.cx) &&
                      std::isfinite(info.cy);
  bool dist_finite = true;
  for (double d : info.distortion) dist_finite = dist_finite && std::isfinite(d);
  if (info.width < 64 || info.height < 64 || info.width > 8192 || info.height > 8192 || !finite ||
      !dist_finite || info.fx <= 0 || info.fy <= 0) {
    *why = "camera_info " + std::to_string(info.width) + "x" + std::to_string(info.height) +
           " fx " + std::to_string(info.fx) + " fy " + std::to_string(info.fy) +
           " is not a usable camera";
    return false;
  }
  *camera = CameraModel(info.width, info.height, info.fx, info.fy, info.cx, info.cy,
                        {info.distortion[0], info.distortion[1], info.distortion[2],
                         info.distortion[3], info.distortion[4]});
  return true;
}

}  // namespace slamaware
