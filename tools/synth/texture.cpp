#include "tools/synth/texture.h"

#include <stdexcept>

namespace slamaware::synth {

Texture::Texture(const cv::Mat& bgr, bool wrap_u, bool wrap_v) : wrap_u_(wrap_u), wrap_v_(wrap_v) {
  if (bgr.empty() || bgr.type() != CV_8UC3)
    throw std::invalid_argument("Texture: need a non-empty 8-bit BGR image");
  int w = bgr.cols, h = bgr.rows;
  w_.push_back(w);
  h_.push_back(h);
  off_.push_back(0);
  px_.resize(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y) {
    const uint8_t* row = bgr.ptr<uint8_t>(y);
    for (int x = 0; x < w; ++x)
      px_[static_cast<size_t>(y) * w + x] = static_cast<uint32_t>(row[3 * x]) |
                                            (static_cast<uint32_t>(row[3 * x + 1]) << 8) |
                                            (static_cast<uint32_t>(row[3 * x + 2]) << 16);
  }
  // Mip levels: 2x2 box filter (the last row / column repeats for odd sizes).
  while (w > 1 || h > 1) {
    const int pw = w, ph = h;
    const size_t poff = static_cast<size_t>(off_.back());
    w = std::max(1, w / 2);
    h = std::max(1, h / 2);
    const size_t off = px_.size();
    px_.resize(off + static_cast<size_t>(w) * h);
    for (int y = 0; y < h; ++y) {
      const int ya = std::min(2 * y, ph - 1), yb = std::min(2 * y + 1, ph - 1);
      for (int x = 0; x < w; ++x) {
        const int xa = std::min(2 * x, pw - 1), xb = std::min(2 * x + 1, pw - 1);
        const uint32_t q[4] = {px_[poff + static_cast<size_t>(ya) * pw + xa],
                               px_[poff + static_cast<size_t>(ya) * pw + xb],
                               px_[poff + static_cast<size_t>(yb) * pw + xa],
                               px_[poff + static_cast<size_t>(yb) * pw + xb]};
        uint32_t out = 0;
        for (int c = 0; c < 3; ++c) {
          uint32_t s = 2;
          for (uint32_t v : q) s += (v >> (8 * c)) & 0xFFu;
          out |= (s / 4) << (8 * c);
        }
        px_[off + static_cast<size_t>(y) * w + x] = out;
      }
    }
    w_.push_back(w);
    h_.push_back(h);
    off_.push_back(static_cast<int32_t>(off));
  }
}

cv::Mat Texture::image() const {
  cv::Mat out(h_[0], w_[0], CV_8UC3);
  for (int y = 0; y < h_[0]; ++y) {
    uint8_t* row = out.ptr<uint8_t>(y);
    for (int x = 0; x < w_[0]; ++x) {
      const uint32_t v = px_[static_cast<size_t>(y) * w_[0] + x];
      row[3 * x] = v & 0xFF;
      row[3 * x + 1] = (v >> 8) & 0xFF;
      row[3 * x + 2] = (v >> 16) & 0xFF;
    }
  }
  return out;
}

}  // namespace slamaware::synth
