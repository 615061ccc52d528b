#pragma once
// Parameters of the image encoding (docs/architecture.md §3): dense SIFT + mean RGB, PCA,
// vocabulary, VLAD with a 1x1 + 2x2 + 4x4 spatial pyramid, then the box's shape (its aspect
// ratio, soft-binned). They are fixed when a model is trained and stored in the model file; the
// recognizer always encodes with the parameters of its model.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace slamaware::recognizer {

/// Row-major float matrix: one descriptor (or encoded box) per row.
using MatrixRM = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// A row-major float matrix that keeps its memory when resized to a size it has held before:
/// per-frame buffers of tens of MB would otherwise be mapped and page-faulted in anew each frame.
class ReusableMatrix {
 public:
  void resize(int64_t rows, int64_t cols) {
    const size_t n = static_cast<size_t>(rows * cols);
    if (data_.size() < n) data_.resize(n);
    rows_ = rows;
    cols_ = cols;
  }
  int64_t rows() const { return rows_; }
  int64_t cols() const { return cols_; }
  float* data() { return data_.data(); }
  const float* data() const { return data_.data(); }
  float* row(int64_t r) { return data_.data() + r * cols_; }
  const float* row(int64_t r) const { return data_.data() + r * cols_; }
  Eigen::Map<MatrixRM> map() { return Eigen::Map<MatrixRM>(data_.data(), rows_, cols_); }
  Eigen::Map<const MatrixRM> map() const {
    return Eigen::Map<const MatrixRM>(data_.data(), rows_, cols_);
  }

 private:
  std::vector<float> data_;
  int64_t rows_ = 0, cols_ = 0;
};

constexpr int kSiftDims = 128;               ///< 4 x 4 spatial bins x 8 orientations
constexpr int kFeatureDims = kSiftDims + 3;  ///< + mean R, G, B of the patch's support
constexpr int kPyramidCells = 1 + 4 + 16;    ///< 1x1, 2x2, 4x4 cells

struct FeatureParams {
  /// Grid step of the descriptor centres; every grid point holds one descriptor per bin size.
  int step_px = 4;
  /// SIFT spatial bin sizes (a descriptor spans 4 bins): ~sqrt(2) apart, rounded to even sizes so
  /// that every centre (frame + 1.5 bins) falls on the same integer grid.
  std::vector<int> bin_sizes_px = {4, 6, 8, 12};
  /// Each scale is computed on the grey image smoothed with sigma = sqrt((bin / magnif)^2 - 1/4)
  /// (as VLFeat's vl_phow does).
  double smoothing_magnif = 6.0;
  /// Descriptors whose mean gradient magnitude (VLFeat's keypoint norm, image in 0..1) is below
  /// this have their SIFT part set to zero (vl_phow's contrast threshold).
  double contrast_threshold = 0.005;
  /// The mean R, G, B (0..1) of the descriptor's 4x4-bin support are multiplied by this.
  double rgb_weight = 1.0;
  /// Pooling cell: descriptors are pooled per cell of this size (a multiple of step_px); boxes
  /// and their pyramid cells are snapped to this grid, and FLAIR's integral tables have one entry
  /// per cell corner. 8 px = 2 x 2 grid points = 16 descriptors per cell at 4 scales.
  int pool_cell_px = 8;

  template <class V>
  void visit(V& v) {
    v("step_px", step_px, "px, dense grid step");
    v("bin_sizes_px", bin_sizes_px, "px, SIFT bin size of each scale (even)");
    v("smoothing_magnif", smoothing_magnif, "smoothing sigma = sqrt((bin/magnif)^2 - 0.25)");
    v("contrast_threshold", contrast_threshold, "SIFT part zeroed below this mean gradient");
    v("rgb_weight", rgb_weight, "weight of the mean RGB (0..1) appended to SIFT");
    v("pool_cell_px", pool_cell_px, "px, pooling / FLAIR table cell (multiple of step_px)");
  }
  /// Throws std::invalid_argument when the parameters cannot work together.
  void validate() const;
  int stepsPerCell() const { return pool_cell_px / step_px; }
  int scales() const { return static_cast<int>(bin_sizes_px.size()); }
  /// Descriptors per pooling cell.
  int descriptorsPerCell() const { return stepsPerCell() * stepsPerCell() * scales(); }
  /// px of image needed around a region so that its descriptors do not see the region's edge.
  int marginPx() const;
};

/// The box-shape block covers log aspect ratios ln(width / height) in [-kShapeLogAspectMax,
/// kShapeLogAspectMax] (aspect 0.22 to 4.5); a box beyond counts as the end bin.
constexpr double kShapeLogAspectMax = 1.5;

struct EncodingParams {
  FeatureParams features;
  int pca_dims = 80;         ///< D: descriptors are projected to this many dimensions
  int vocabulary_size = 64;  ///< K: k-means codewords
  /// Bins of the box's log aspect ratio appended to its VLAD vector (vlad.h, encodeBoxShape);
  /// 0: no shape block (models made before it existed).
  int shape_bins = 13;

  template <class V>
  void visit(V& v) {
    v.section("features", features);
    v("pca_dims", pca_dims, "dimensions kept by PCA");
    v("vocabulary_size", vocabulary_size, "k-means codewords");
    v("shape_bins", shape_bins, "bins of the box's log aspect ratio (0: none)");
  }
  void validate() const;
  /// Length of a box's VLAD vector: 21 pyramid cells x K x D.
  int64_t vladDims() const { return int64_t{kPyramidCells} * vocabulary_size * pca_dims; }
  /// Length of the shape block: one block of D values (the first shape_bins used), so that an
  /// encoded box is still a whole number of D-blocks; 0 without shape bins.
  int64_t shapeDims() const { return shape_bins > 0 ? pca_dims : 0; }
  /// Length of an encoded box: its VLAD vector, then its shape block.
  int64_t encodedDims() const { return vladDims() + shapeDims(); }
};

}  // namespace slamaware::recognizer
