#pragma once
// VLAD with a 1x1 + 2x2 + 4x4 spatial pyramid, and the two box encoders that compute it.
//
// Membership. A descriptor belongs to a box when its pooling cell does (dense_features.h): boxes
// are snapped to the pooling grid (snapBox), and so are their pyramid cells: the 4x4 boundaries
// are u0 + floor(i * width / 4), i = 0..4, the 2x2 ones are the even ones of those, so the
// levels nest exactly. A pyramid cell narrower than one pooling cell is empty (a zero block).
//
// Layout of an encoded box (21 * K * D floats): cell 0 = the whole box, cells 1..4 = the 2x2
// level (row-major), cells 5..20 = the 4x4 level (row-major); each cell holds K blocks of D: the
// sum of (descriptor - codeword) over the cell's descriptors assigned to that codeword. Then the
// signed square root of every element, then L2 normalisation of the whole vector (finishVlad).
//
// Both encoders read the per-cell entries of FrameCodes and produce the same vector up to float
// rounding. DirectEncoder sums the entries of the pooling cells inside each 4x4 cell (cost grows
// with the box's area); FlairEncoder reads the 4x4 cells from
// per-codeword integral tables at the 25 distinct corners (cost independent of the area, plus one
// table build per frame whose cost grows with the area the boxes span).
#include <cstddef>
#include <vector>

#include "procs/recognizer/dense_features.h"
#include "procs/recognizer/pca_vocabulary.h"
#include "procs/recognizer/word_scores.h"

namespace slamaware::recognizer {

/// A box on the pooling grid with the boundaries of its 4x4 pyramid cells (cell (i, j) =
/// [u[i], u[i+1]) x [v[j], v[j+1])).
struct PyramidBox {
  int u[5] = {0, 0, 0, 0, 0};
  int v[5] = {0, 0, 0, 0, 0};
  CellRect cells() const { return CellRect{u[0], v[0], u[4], v[4]}; }
};

/// Snaps the pixel box (x, y = top-left corner, w, h) of an image of width x height to the
/// pooling grid: clipped to the image, each edge moved to the nearest cell boundary; a box
/// narrower than one cell keeps the cell under its centre. Returns false (and leaves *out alone)
/// for a box that is not finite or has no area inside the image.
bool snapBox(double x, double y, double w, double h, int width, int height, int pool_cell_px,
             PyramidBox* out);
/// A pyramid box from cell boundaries [u0, u1) x [v0, v1) (u1 > u0, v1 > v0).
PyramidBox pyramidFromCells(const CellRect& cells);

/// What both box encoders read: for each pooling cell of `region`, the codewords its descriptors
/// were assigned to, each with how many descriptors and the sum of their residuals (projected
/// descriptor - codeword). A box's VLAD is a sum of these entries over its cells, so the encoders
/// add one entry per (cell, codeword) instead of one projected descriptor each.
struct FrameCodes {
  CellRect region;  ///< pooling cells covered
  /// Entries of cell (u, v) are [first[i], first[i + 1]) with i = cellIndex(u, v), by increasing
  /// codeword; a cell that no box reads was not coded and has none.
  std::vector<int32_t> first;
  std::vector<int16_t> words;  ///< per entry: the codeword
  std::vector<float> counts;   ///< per entry: its descriptors in the cell
  ReusableMatrix residuals;    ///< entries x D: sum over them of (projected descriptor - codeword)

  int64_t cellIndex(int u, int v) const {
    return int64_t{v - region.v0} * region.width() + (u - region.u0);
  }
  bool coded(int u, int v) const {
    const int64_t i = cellIndex(u, v);
    return first[static_cast<size_t>(i) + 1] > first[static_cast<size_t>(i)];
  }
  /// Empties the codes and sizes them for `region` (all cells uncoded).
  void reset(const CellRect& cells, int d);
  /// Appends an entry to the cell being filled: cells are filled in index order, each with
  /// endCell() after its entries.
  float* addEntry(int16_t word, float count);
  void endCell() { first.push_back(static_cast<int32_t>(words.size())); }
};

/// Codes the descriptors of a FeatureGrid: each is assigned to its nearest codeword after PCA,
/// and the entries of FrameCodes are formed per pooling cell. PCA is linear, so a cell's sum of
/// projected descriptors of one codeword is the projection of their raw sum: the assignment is one
/// product with (PCA basis x codewords^T) (131 x K) per descriptor, and the projection (131 x D)
/// runs once per (cell, codeword), not per descriptor. Descriptors whose SIFT part is zero
/// (below the contrast threshold; three quarters of a real frame) are assigned from their R, G, B
/// alone. The result equals projecting and assigning every descriptor up to float rounding
/// (ties between two codewords within rounding may go either way).
class FeatureCoder {
 public:
  /// Keeps references: `pca` and `vocabulary` must outlive the coder.
  FeatureCoder(const Pca& pca, const Vocabulary& vocabulary);
  /// Codes the cells of grid.region (reusing out's memory). With `only` (cell rectangles, e.g.
  /// the boxes to encode), just the cells some rectangle covers; the others stay uncoded.
  void code(const FeatureGrid& grid, int steps_per_cell, FrameCodes* out,
            const std::vector<CellRect>* only = nullptr);

 private:
  /// The codewords of rows_[begin, end) into row_words_ (and row_textured_).
  void assignRows(const FeatureGrid& grid, size_t begin, size_t end);

  const Pca& pca_;
  const Vocabulary& vocabulary_;
  WordScores words_;           ///< the codeword of a row
  Eigen::RowVectorXf offset_;  ///< mean x basis
  // Scratch, reused across frames.
  std::vector<int64_t> rows_;  ///< grid rows to code, cell by cell
  std::vector<int16_t> row_words_;
  std::vector<uint8_t> row_textured_;  ///< per entry of rows_: its SIFT part is not all zero
  /// Of the group of rows being assigned, without and with gradient: the rows, their positions
  /// in rows_, their words.
  std::vector<const float*> group_rows_[2];
  std::vector<size_t> group_at_[2];
  std::vector<int16_t> group_words_;
  ReusableMatrix sums_;     ///< entries x 131: raw sums
  std::vector<float> acc_;  ///< K x 131 sums of the cell being pooled
  std::vector<float> acc_n_;
};

/// Normalises the 21 * K * D raw residual sums in place: blocks whose count is zero are set to
/// exactly zero (FLAIR's table differences leave rounding noise there), then each element
/// becomes sign(v) sqrt(|v|) (alpha = 0.5), then the vector is scaled to unit L2 norm (left at
/// zero when it is all zero). `counts` holds 21 * K descriptor counts.
void finishVlad(float* v, const float* counts, int K, int D);

/// The shape block of a box (EncodingParams::shapeDims() floats): its log aspect ratio
/// a = ln(width / height), clamped to [-kShapeLogAspectMax, kShapeLogAspectMax], spread over
/// `bins` evenly spaced centres by linear interpolation between the two nearest (two values
/// summing to 1, the rest of the block zero). The VLAD vector describes what a box holds but not
/// its outline, since every box is pooled into the same 4x4 grid; a soda can, a mug and a bowl
/// differ in aspect first. The classifiers learn what each aspect means for each class; with
/// values summing to 1 each bin acts as a bias of its own, on the footing of the unit-norm VLAD
/// vector. `log_aspect_offset` is added to a before binning (the trainer's box-shape noise).
void encodeBoxShape(const PyramidBox& box, int bins, int block_dims, float* out,
                    double log_aspect_offset = 0);

/// Sums the 4x4 cells (5..20) into the 2x2 cells (1..4) and the whole box (0), for sums (K * D
/// per cell) and counts (K per cell).
void sumPyramidLevels(float* v, float* counts, int K, int D);

/// Encodes boxes by summing the entries of the pooling cells inside each 4x4 pyramid cell, then
/// the 4x4 cells into the 2x2 cells and the whole box. Shares the frame's codes with FLAIR (a
/// strong baseline, not a per-box recomputation); its cost grows with the box's area.
class DirectEncoder {
 public:
  DirectEncoder(const FrameCodes& codes, const Vocabulary& vocabulary)
      : codes_(codes), vocabulary_(vocabulary) {}
  /// Writes the normalised 21 * K * D vector of `box` (inside codes.region) to out.
  void encode(const PyramidBox& box, float* out);

 private:
  const FrameCodes& codes_;
  const Vocabulary& vocabulary_;
  std::vector<float> counts_;
};

/// FLAIR (Van de Sande et al., CVPR 2014): per-codeword integral tables of residual sums and
/// counts over the pooling grid, so that any box and its 21 pyramid cells cost 25 corner lookups
/// whatever its area. Tables are float, one entry of K * (D + 1) floats per cell corner, over the
/// region the boxes span only; the residual (descriptor - codeword) is integrated rather than the
/// descriptor, which keeps the table values small and their rounding error low.
class FlairEncoder {
 public:
  /// Builds the tables over `region` (within codes.region). Reuses its memory across frames.
  void build(const FrameCodes& codes, const Vocabulary& vocabulary, const CellRect& region);
  /// Writes the normalised vector of `box` (inside the built region) to out.
  void encode(const PyramidBox& box, float* out);
  const CellRect& region() const { return region_; }
  /// Bytes of the tables for the region built last.
  size_t tableBytes() const { return tableBytesFor(region_, K_, D_); }
  /// Bytes the tables need for a region.
  static size_t tableBytesFor(const CellRect& region, int K, int D);

 private:
  const float* sumsAt(int a, int b) const {
    return sums_.data() + (int64_t{b} * (region_.width() + 1) + a) * K_ * D_;
  }
  const float* countsAt(int a, int b) const {
    return counts_.data() + (int64_t{b} * (region_.width() + 1) + a) * K_;
  }
  CellRect region_;
  int K_ = 0, D_ = 0;
  std::vector<float> sums_;    ///< corners x K x D
  std::vector<float> counts_;  ///< corners x K
  std::vector<float> box_counts_;
  std::vector<float> row_sums_, row_counts_;
};

}  // namespace slamaware::recognizer
