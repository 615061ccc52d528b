#pragma once
// Dense SIFT with a flat window: the computation of VLFeat's vl_dsift_process with
// vl_dsift_set_flat_window(1) (VLFeat 0.9.21), reorganised for speed.
//
// vl_dsift writes each descriptor element in its own pass over all frames (a stride of 512 bytes)
// and filters 8 full-size orientation planes with transposes; at 4 scales of a 640x480 frame it
// costs ~250 ms here. This version keeps the 8 orientations of a pixel together, filters
// row by row, and evaluates the triangular filters only at the bin centres the frames use.
// The formulas are VLFeat's: central-difference gradients, vl_fast_atan2_f / vl_fast_sqrt_f,
// linear interpolation between the 2 nearest of 8 orientation bins, the triangular kernel
// (b - |d|) / b^2 per axis, the flat-window bin weights (mean of a Gaussian window of sigma
// 2 bins over each bin), the "norm" (mean mass), L2 normalisation, clamping at 0.2 and L2
// normalisation again. tests/recognizer/test_dense_sift.cpp compares it with
// vl_dsift itself.
#include <cstddef>

namespace slamaware::recognizer {

/// The frames of one scale: frame (i, j) starts at (min_x + step * i, min_y + step * j) (VLFeat's
/// frame origin: its first bin centre) and has its centre 1.5 bins further.
struct DsiftGeometry {
  int bin = 4;   ///< px, spatial bin size (4 x 4 bins, 8 orientations)
  int step = 4;  ///< px between frames
  int min_x = 0, min_y = 0;
  int nx = 0, ny = 0;
};

/// Where denseSiftFlat writes frame (i, j)'s results.
struct DsiftOutput {
  /// Its 128 floats (VLFeat's element order: orientation fastest, then bin x, then bin y) at
  /// descriptors + (j * row_pitch + i) * stride (row_pitch 0: nx; a larger one writes into a
  /// wider grid).
  float* descriptors = nullptr;
  size_t stride = 128;
  size_t row_pitch = 0;
  /// Its mean gradient mass (VLFeat's keypoint norm) at norms[j * nx + i].
  float* norms = nullptr;
  /// A descriptor whose norm is below this is written as 128 zeros instead (the contrast
  /// threshold; 0: none is).
  float zero_below = 0;
  /// tail_dims floats of tail[(j * nx + i) * tail_dims] written after its 128 elements, in the
  /// same pass (stride >= 128 + tail_dims).
  const float* tail = nullptr;
  int tail_dims = 0;
};

/// Computes nx * ny descriptors of a row-major float image into `out`.
/// Every frame's support (origin - bin + 1 .. origin + 4 bins - 1) must lie inside the image.
/// Throws std::invalid_argument otherwise, or when `out` cannot hold them.
void denseSiftFlat(const float* image, int width, int height, const DsiftGeometry& geometry,
                   const DsiftOutput& out);

/// The same descriptors computed by VLFeat's vl_dsift (for tests and comparisons; slow).
void denseSiftVlfeat(const float* image, int width, int height, const DsiftGeometry& geometry,
                     float* descriptors, size_t stride, float* norms);

}  // namespace slamaware::recognizer
