#include "tools/train/object_box.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>

namespace slamaware::recognizer {

cv::Rect objectBoxInCrop(const cv::Mat& crop) {
  const cv::Rect whole(0, 0, crop.cols, crop.rows);
  if (crop.empty() || crop.type() != CV_8UC3 || std::min(crop.cols, crop.rows) < 16) return whole;
  const int band = std::max(1, static_cast<int>(0.06 * std::min(crop.cols, crop.rows) + 0.5));
  cv::Mat mask(crop.size(), CV_8UC1, cv::Scalar(cv::GC_BGD));
  const cv::Rect inner(band, band, crop.cols - 2 * band, crop.rows - 2 * band);
  mask(inner).setTo(cv::GC_PR_FGD);
  cv::Mat bgd, fgd;
  const uint64 state = cv::theRNG().state;
  cv::theRNG().state = 0x5eed;
  cv::grabCut(crop, mask, cv::Rect(), bgd, fgd, 4, cv::GC_INIT_WITH_MASK);
  cv::theRNG().state = state;
  cv::Mat fg = (mask == cv::GC_FGD) | (mask == cv::GC_PR_FGD);
  // Specks of a pixel or two are not the object.
  cv::morphologyEx(fg, fg, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_RECT, {3, 3}));
  const cv::Rect fgBox = cv::boundingRect(fg);
  if (fgBox.area() == 0) return whole;
  // An object that reaches the band touches the crop's border: the crop is framed by it (tight),
  // and the band hid part of it from the cut.
  if (fgBox.x <= inner.x || fgBox.y <= inner.y || fgBox.br().x >= inner.br().x ||
      fgBox.br().y >= inner.br().y)
    return whole;
  return fgBox;
}

}  // namespace slamaware::recognizer
