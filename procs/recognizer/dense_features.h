#pragma once
// Dense SIFT (VLFeat vl_dsift, flat window) at several bin sizes on one common grid, plus the mean
// RGB of each descriptor's support: 131-D raw features (docs/architecture.md §3).
//
// Geometry. The image is divided into pooling cells of pool_cell_px; cell (u, v) covers pixels
// [u*T, (u+1)*T) x [v*T, (v+1)*T). Each cell holds s x s grid points (s = T / step), grid point
// (i, j) of the image has its centre at pixel (step*i + step/2, step*j + step/2), and every grid
// point has one descriptor per bin size, all centred there. Pixels beyond the image (a descriptor's
// support near the border, the last partial cell) are the image mirrored at its border
// (BORDER_REFLECT_101), so a grid point's descriptor does not depend on which region is computed.
#include <algorithm>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "procs/recognizer/encoding_params.h"

namespace slamaware::recognizer {

/// A rectangle of pooling cells, half-open: [u0, u1) x [v0, v1).
struct CellRect {
  int u0 = 0, v0 = 0, u1 = 0, v1 = 0;
  int width() const { return u1 - u0; }
  int height() const { return v1 - v0; }
  bool empty() const { return u1 <= u0 || v1 <= v0; }
  int64_t area() const { return empty() ? 0 : int64_t{width()} * height(); }
  bool contains(const CellRect& o) const {
    return o.u0 >= u0 && o.v0 >= v0 && o.u1 <= u1 && o.v1 <= v1;
  }
  /// The smallest rectangle holding both (an empty one is ignored).
  CellRect united(const CellRect& o) const;
  /// The cells in both (empty when they do not overlap).
  CellRect intersected(const CellRect& o) const {
    return CellRect{std::max(u0, o.u0), std::max(v0, o.v0), std::min(u1, o.u1), std::min(v1, o.v1)};
  }
  bool operator==(const CellRect& o) const {
    return u0 == o.u0 && v0 == o.v0 && u1 == o.u1 && v1 == o.v1;
  }
};

/// Raw features of the grid points of a region of pooling cells.
struct FeatureGrid {
  CellRect region;     ///< pooling cells covered
  int nx = 0, ny = 0;  ///< grid points: region.width() * s by region.height() * s
  int scales = 0;
  /// One row per descriptor: row (t * nx * ny + j * nx + i) for grid point (i, j) of the region
  /// and scale t; columns: 128 SIFT (VLFeat order) then R, G, B.
  ReusableMatrix features;
  /// Per row: 1 when its SIFT part is not all zero (its norm is positive and reached the contrast
  /// threshold); 0: the SIFT part is all zero and only R, G, B describe it.
  std::vector<uint8_t> textured;
  int64_t rowOf(int i, int j, int t) const { return (int64_t{t} * ny + j) * nx + i; }
};

/// Computes raw features of one image, region by region.
class DenseFeatureExtractor {
 public:
  explicit DenseFeatureExtractor(const FeatureParams& params);

  /// Sets the image (8-bit BGR; shared, not copied: it must not change until the last extract()).
  /// Cheap: each extract() converts to grey and float RGB, with the mirrored border, only the
  /// pixels its blocks read.
  void setImage(const cv::Mat& bgr);
  int width() const { return width_; }
  int height() const { return height_; }
  /// Pooling cells covering the image (the last row / column may extend beyond it).
  CellRect imageCells() const;
  /// Features of every grid point in `region` (clipped to imageCells()) into *grid (its memory is
  /// reused). With `only`, just those of the cells of blocks(*only, region); the other rows of the
  /// grid are left undefined.
  void extract(const CellRect& region, FeatureGrid* grid,
               const std::vector<CellRect>* only = nullptr);
  /// The rectangles clipped to `within`, overlapping ones and those whose bounding rectangle costs
  /// no more than the two apart (each block is computed with a margin of filter support around
  /// it) joined: disjoint blocks that hold every cell of the rectangles, top to bottom.
  std::vector<CellRect> blocks(const std::vector<CellRect>& rects, const CellRect& within) const;
  const FeatureParams& params() const { return params_; }

 private:
  /// The block plus its margin of filter support, in padded-image coordinates (the padding is
  /// margin_ on the left and top): what its features read.
  cv::Rect paddedRect(const CellRect& block) const;
  /// Its pixels: what computing the block costs.
  int64_t paddedArea(const CellRect& block) const;
  /// Fills the part of grey_padded_ and rgb_padded_ that `block`'s features read.
  void fillPadded(const CellRect& block);
  /// Features of the grid points of one block (inside grid->region) into their rows of *grid.
  void extractBlock(const CellRect& block, FeatureGrid* grid);

  FeatureParams params_;
  int margin_ = 0;
  int width_ = 0, height_ = 0;
  cv::Mat bgr_;  ///< the image
  /// The image with margin_ px of mirrored border (more at right/bottom), filled only where the
  /// blocks of the last extract() read (fillPadded):
  cv::Mat grey_padded_;                        ///< CV_32F, 0..1
  cv::Mat rgb_padded_;                         ///< CV_32FC3 in R, G, B order, 0..1
  cv::Mat window_, window_grey_, window_rgb_;  ///< scratch: one block's pixels, 8 bits
  cv::Mat smooth_, integral_;                  ///< scratch
  std::vector<float> norms_;                   ///< scratch
  std::vector<float> rgb_;                     ///< scratch: mean R, G, B of one scale's grid points
};

}  // namespace slamaware::recognizer
