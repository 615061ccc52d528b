#include "procs/recognizer/dense_features.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "procs/recognizer/dense_sift.h"

namespace slamaware::recognizer {

namespace {

double smoothingSigma(int bin, double magnif) {
  const double s = bin / magnif;
  return std::sqrt(std::max(0.0, s * s - 0.25));
}

// Radius of the kernel cv::GaussianBlur uses for a float image at this sigma.
int gaussianRadius(double sigma) {
  if (sigma <= 0) return 0;
  const int ksize = cvRound(sigma * 4 * 2 + 1) | 1;
  return ksize / 2;
}

}  // namespace

void FeatureParams::validate() const {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("feature parameters: " + what);
  };
  // The upper bounds are far beyond any useful value; they keep sizes derived from these (margins,
  // cells, kernels) inside int.
  if (step_px <= 0 || step_px % 2 != 0 || step_px > 256)
    fail("step_px must be an even number in 2..256");
  if (pool_cell_px <= 0 || pool_cell_px % step_px != 0 || pool_cell_px > 1024)
    fail("pool_cell_px must be a multiple of step_px, at most 1024");
  if (bin_sizes_px.empty()) fail("bin_sizes_px is empty");
  for (int b : bin_sizes_px)
    if (b < 2 || b % 2 != 0 || b > 256) fail("every bin size must be an even number in 2..256");
  if (!(smoothing_magnif > 0) || !std::isfinite(smoothing_magnif))
    fail("smoothing_magnif must be positive");
  if (!(contrast_threshold >= 0) || !std::isfinite(contrast_threshold))
    fail("contrast_threshold must be a finite number >= 0");
  if (!(rgb_weight >= 0) || !std::isfinite(rgb_weight))
    fail("rgb_weight must be a finite number >= 0");
}

int FeatureParams::marginPx() const {
  int m = 0;
  for (int b : bin_sizes_px) {
    // Support of a descriptor: its 4 bins +- one bin of triangular interpolation = 2.5 bins from
    // the centre; +1 for the central-difference gradient; + the smoothing kernel.
    const int reach = (5 * b + 1) / 2 + 1 + gaussianRadius(smoothingSigma(b, smoothing_magnif)) + 1;
    m = std::max(m, reach - step_px / 2);
  }
  return (m + 3) / 4 * 4;
}

void EncodingParams::validate() const {
  features.validate();
  if (pca_dims <= 0 || pca_dims > kFeatureDims)
    throw std::invalid_argument("encoding parameters: pca_dims must be in 1.." +
                                std::to_string(kFeatureDims));
  if (vocabulary_size <= 1 || vocabulary_size > 32767)
    throw std::invalid_argument("encoding parameters: vocabulary_size must be in 2..32767");
  if (shape_bins == 1 || shape_bins < 0 || shape_bins > pca_dims)
    throw std::invalid_argument("encoding parameters: shape_bins must be 0 or in 2..pca_dims (" +
                                std::to_string(pca_dims) + ")");
}

CellRect CellRect::united(const CellRect& o) const {
  if (empty()) return o;
  if (o.empty()) return *this;
  return CellRect{std::min(u0, o.u0), std::min(v0, o.v0), std::max(u1, o.u1), std::max(v1, o.v1)};
}

DenseFeatureExtractor::DenseFeatureExtractor(const FeatureParams& params) : params_(params) {
  params_.validate();
  margin_ = params_.marginPx();
}

void DenseFeatureExtractor::setImage(const cv::Mat& bgr) {
  if (bgr.empty() || bgr.type() != CV_8UC3)
    throw std::invalid_argument("setImage: expected an 8-bit BGR image");
  bgr_ = bgr;
  width_ = bgr.cols;
  height_ = bgr.rows;
  // Allocated once per frame size (create() keeps a buffer of the same size and type).
  const cv::Size size = paddedRect(imageCells()).size();
  grey_padded_.create(size, CV_32F);
  rgb_padded_.create(size, CV_32FC3);
}

void DenseFeatureExtractor::fillPadded(const CellRect& block) {
  // The block and its margin, in image coordinates; what of it lies beyond the image is the image
  // mirrored at its border (reflect-101), exactly as if the whole image had been padded: the
  // pixels copied include those that the mirrored border repeats.
  const cv::Rect padded = paddedRect(block);
  const cv::Rect want = padded - cv::Point(margin_, margin_);
  const int left = std::max(0, -want.x), top = std::max(0, -want.y);
  const int right = std::max(0, want.br().x - width_), bottom = std::max(0, want.br().y - height_);
  const int x0 = std::min(std::max(0, want.x), std::max(0, width_ - 1 - right));
  const int x1 = std::max(std::min(width_, want.br().x), std::min(width_, left + 1));
  const int y0 = std::min(std::max(0, want.y), std::max(0, height_ - 1 - bottom));
  const int y1 = std::max(std::min(height_, want.br().y), std::min(height_, top + 1));
  cv::copyMakeBorder(bgr_(cv::Rect(x0, y0, x1 - x0, y1 - y0)), window_, top, bottom, left, right,
                     cv::BORDER_REFLECT_101 | cv::BORDER_ISOLATED);
  // window_'s pixel (0, 0) is the image's (x0 - left, y0 - top).
  const cv::Mat pixels =
      window_(cv::Rect(want.x - (x0 - left), want.y - (y0 - top), want.width, want.height));
  cv::Mat grey = grey_padded_(padded), rgb = rgb_padded_(padded);
  cv::cvtColor(pixels, window_grey_, cv::COLOR_BGR2GRAY);
  window_grey_.convertTo(grey, CV_32F, 1.0 / 255.0);
  cv::cvtColor(pixels, window_rgb_, cv::COLOR_BGR2RGB);
  window_rgb_.convertTo(rgb, CV_32FC3, 1.0 / 255.0);
}

cv::Rect DenseFeatureExtractor::paddedRect(const CellRect& block) const {
  const int T = params_.pool_cell_px;
  return cv::Rect(block.u0 * T, block.v0 * T, block.width() * T + 2 * margin_,
                  block.height() * T + 2 * margin_);
}

int64_t DenseFeatureExtractor::paddedArea(const CellRect& block) const {
  const cv::Rect r = paddedRect(block);
  return int64_t{r.width} * r.height;
}

CellRect DenseFeatureExtractor::imageCells() const {
  const int T = params_.pool_cell_px;
  return CellRect{0, 0, (width_ + T - 1) / T, (height_ + T - 1) / T};
}

std::vector<CellRect> DenseFeatureExtractor::blocks(const std::vector<CellRect>& rects,
                                                    const CellRect& within) const {
  // Each block costs its pixels plus margin_ on every side (blur, gradients, filtering): two
  // blocks become their bounding rectangle when that costs no more than the two apart.
  std::vector<CellRect> out;
  for (const CellRect& r : rects) {
    const CellRect c = r.intersected(within);
    if (!c.empty()) out.push_back(c);
  }
  for (bool merged = true; merged;) {
    merged = false;
    for (size_t i = 0; i < out.size() && !merged; ++i)
      for (size_t j = i + 1; j < out.size() && !merged; ++j) {
        const CellRect u = out[i].united(out[j]);
        if (!out[i].intersected(out[j]).empty() ||
            paddedArea(u) <= paddedArea(out[i]) + paddedArea(out[j])) {
          out[i] = u;
          out.erase(out.begin() + static_cast<long>(j));
          merged = true;
        }
      }
  }
  std::sort(out.begin(), out.end(), [](const CellRect& a, const CellRect& b) {
    return std::tie(a.v0, a.u0) < std::tie(b.v0, b.u0);
  });
  return out;
}

void DenseFeatureExtractor::extract(const CellRect& requested, FeatureGrid* out,
                                    const std::vector<CellRect>* only) {
  const CellRect region = requested.intersected(imageCells());
  FeatureGrid& grid = *out;
  grid.scales = params_.scales();
  if (region.empty() || grey_padded_.empty()) {
    grid.region = CellRect{};
    grid.nx = grid.ny = 0;
    grid.features.resize(0, kFeatureDims);
    grid.textured.clear();
    return;
  }
  grid.region = region;
  const int s = params_.stepsPerCell();
  grid.nx = region.width() * s;
  grid.ny = region.height() * s;
  grid.features.resize(int64_t{grid.nx} * grid.ny * grid.scales, kFeatureDims);
  grid.textured.resize(static_cast<size_t>(grid.features.rows()));
  // Each block's pixels with their margin, or the region's once when the blocks' margins would
  // convert more pixels than that.
  const std::vector<CellRect> parts = only ? blocks(*only, region) : std::vector<CellRect>{region};
  int64_t area = 0;
  for (const CellRect& b : parts) area += paddedArea(b);
  const bool once = area >= paddedArea(region);
  if (once) fillPadded(region);
  for (const CellRect& b : parts) {
    if (!once) fillPadded(b);
    extractBlock(b, &grid);
  }
}

void DenseFeatureExtractor::extractBlock(const CellRect& block, FeatureGrid* out) {
  FeatureGrid& grid = *out;
  const int step = params_.step_px, s = params_.stepsPerCell();
  const int M = margin_;
  const int nx = block.width() * s, ny = block.height() * s;
  const int64_t points = int64_t{nx} * ny;
  // Grid point (i, j) of the block is point (gx + i, gy + j) of the grid.
  const int gx = (block.u0 - grid.region.u0) * s, gy = (block.v0 - grid.region.v0) * s;

  const cv::Rect sub = paddedRect(block);
  const cv::Mat grey_sub = grey_padded_(sub);
  const int c0 = M + step / 2;  // centre of grid point 0 inside `sub`
  std::vector<float>& norms = norms_;

  // Mean R, G, B over each descriptor's support (the 4 x 4 bins around its centre), from an
  // integral image, written with the descriptor.
  cv::Mat& integral = integral_;
  cv::integral(rgb_padded_(sub), integral, CV_64F);
  const float w = static_cast<float>(params_.rgb_weight);
  rgb_.resize(static_cast<size_t>(points) * 3);

  for (int t = 0; t < grid.scales; ++t) {
    const int b = params_.bin_sizes_px[t];
    const int half = 2 * b;
    const double inv_area = 1.0 / (4.0 * half * half);
    for (int j = 0; j < ny; ++j) {
      const int y0 = c0 + step * j - half, y1 = c0 + step * j + half;
      const cv::Vec3d* top = integral.ptr<cv::Vec3d>(y0);
      const cv::Vec3d* bottom = integral.ptr<cv::Vec3d>(y1);
      float* rgb = rgb_.data() + static_cast<size_t>(j) * nx * 3;
      for (int i = 0; i < nx; ++i) {
        const int x0 = c0 + step * i - half, x1 = c0 + step * i + half;
        const cv::Vec3d sum = bottom[x1] - bottom[x0] - top[x1] + top[x0];
        for (int c = 0; c < 3; ++c) rgb[3 * i + c] = w * static_cast<float>(sum[c] * inv_area);
      }
    }

    const double sigma = smoothingSigma(b, params_.smoothing_magnif);
    cv::Mat& smooth = smooth_;
    if (sigma > 0)
      cv::GaussianBlur(grey_sub, smooth, cv::Size(0, 0), sigma, sigma, cv::BORDER_REFLECT_101);
    else
      grey_sub.copyTo(smooth);
    if (!smooth.isContinuous()) smooth = smooth.clone();

    // A frame starting at x has its centre at x + 1.5 bins.
    DsiftGeometry geometry;
    geometry.bin = b;
    geometry.step = step;
    geometry.min_x = c0 - 3 * b / 2;
    geometry.min_y = c0 - 3 * b / 2;
    geometry.nx = nx;
    geometry.ny = ny;
    norms.resize(static_cast<size_t>(points));
    const float threshold = static_cast<float>(params_.contrast_threshold);
    DsiftOutput out_sift;
    out_sift.descriptors = grid.features.row(grid.rowOf(gx, gy, t));
    out_sift.stride = kFeatureDims;
    out_sift.row_pitch = static_cast<size_t>(grid.nx);
    out_sift.norms = norms.data();
    out_sift.zero_below = threshold;
    out_sift.tail = rgb_.data();
    out_sift.tail_dims = 3;
    denseSiftFlat(smooth.ptr<float>(), smooth.cols, smooth.rows, geometry, out_sift);
    // A positive mass leaves a non-zero normalised descriptor; a zero one (possible with a
    // threshold of 0) an all-zero one.
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const float norm = norms[static_cast<size_t>(j) * nx + i];
        grid.textured[static_cast<size_t>(grid.rowOf(gx + i, gy + j, t))] =
            norm >= threshold && norm > 0;
      }
  }
}

}  // namespace slamaware::recognizer
