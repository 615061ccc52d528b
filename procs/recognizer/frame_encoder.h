#pragma once
// Encodes the boxes of one frame: raw features over the cells the boxes span only, codeword
// assignment and PCA as matrix products (FeatureCoder), then one VLAD vector per box by the
// direct encoder or FLAIR, whichever the cost model expects to be cheaper for this set of boxes.
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "procs/recognizer/vlad.h"

namespace slamaware::recognizer {

enum class EncoderKind { kAuto, kDirect, kFlair };
/// "auto", "direct", "flair"; throws std::invalid_argument otherwise.
EncoderKind parseEncoderKind(const std::string& name);
const char* encoderName(EncoderKind kind);

/// Time model of the two encoders (defaults: the medians of slamaware-bench-recognizer on
/// 640x480 frames, 2-core reference machine, 2026-12-03; see README). Direct: per box a fixed
/// part plus a part per descriptor inside the box. FLAIR: a table build per corner of the region
/// the boxes span, plus a fixed time per box whatever its size.
struct EncoderCostModel {
  double direct_us_per_box = 130.0;
  double direct_ns_per_descriptor = 2.7;
  double flair_ns_per_corner = 4300.0;
  double flair_us_per_box = 150.0;
  /// FLAIR is not used when its tables would need more memory than this (the direct encoder then
  /// handles the frame).
  double flair_max_table_mb = 200.0;

  template <class V>
  void visit(V& v) {
    v("direct_us_per_box", direct_us_per_box, "us, direct encoder: fixed cost per box");
    v("direct_ns_per_descriptor", direct_ns_per_descriptor,
      "ns, direct encoder: cost per descriptor in a box");
    v("flair_ns_per_corner", flair_ns_per_corner, "ns, FLAIR: table build per pooling-cell corner");
    v("flair_us_per_box", flair_us_per_box, "us, FLAIR: cost per box (any size)");
    v("flair_max_table_mb", flair_max_table_mb, "MB, FLAIR is not used above this table size");
  }
};

class FrameEncoder {
 public:
  struct Stats {
    double features_ms = 0;  ///< dense SIFT + RGB
    double coding_ms = 0;    ///< PCA + assignment
    double encode_ms = 0;    ///< table build (FLAIR) + per-box VLAD
    EncoderKind used = EncoderKind::kDirect;
    size_t table_bytes = 0;  ///< FLAIR tables of this frame (0 with the direct encoder)
    CellRect region;         ///< cells whose features were computed
  };

  /// Keeps references: the parameters, PCA and vocabulary must outlive the encoder.
  FrameEncoder(const EncodingParams& params, const Pca& pca, const Vocabulary& vocabulary,
               EncoderCostModel cost = EncoderCostModel());

  /// Snaps a pixel box to this image's pooling grid (see snapBox).
  bool snap(double x, double y, double w, double h, int width, int height, PyramidBox* out) const;
  /// The encoder the cost model picks for these boxes.
  EncoderKind choose(const std::vector<PyramidBox>& boxes) const;
  /// Estimated ms of each encoder for these boxes (excluding features and coding).
  double estimateMs(const std::vector<PyramidBox>& boxes, EncoderKind kind) const;

  /// Encodes `boxes` of the 8-bit BGR image into the rows of *out (boxes.size() x encodedDims:
  /// each box's VLAD vector, then its shape block): prepare(), then encodeRows() of every box.
  void encode(const cv::Mat& bgr, const std::vector<PyramidBox>& boxes, EncoderKind kind,
              ReusableMatrix* out, Stats* stats = nullptr);

  /// What the boxes of a frame share: the features and codes where they are and, with FLAIR
  /// (`kind`, or the cost model's choice for kAuto), the tables. Sets *stats (encode_ms: the
  /// tables).
  void prepare(const cv::Mat& bgr, const std::vector<PyramidBox>& boxes, EncoderKind kind,
               Stats* stats = nullptr);
  /// Encodes boxes[first, first + count) of the frame prepare() was given into the rows of *out
  /// (count x encodedDims), in as many passes as suit the caller: a caller that encodes a few
  /// boxes at a time needs memory for a few rows (430 KB each), whatever the number of boxes.
  /// Adds its time to stats->encode_ms.
  void encodeRows(const std::vector<PyramidBox>& boxes, size_t first, size_t count,
                  ReusableMatrix* out, Stats* stats = nullptr);

  /// Encodes one box over a whole `width` x `height` frame of noise with the direct encoder and,
  /// unless `kind` is kDirect or the tables would exceed flair_max_table_mb, with FLAIR, so that
  /// the memory of the features, codes and tables of any frame of that size exists before the
  /// first real frame: the buffers grow to a frame's span and stay, and growing them is most of a
  /// cold frame's time (a whole VGA frame: about 540 ms the first time, 70 ms after). Later
  /// results do not depend on it. Returns the ms spent.
  double warmUp(int width, int height, EncoderKind kind);

  /// Training only: the log aspect ratio each box's shape block is made from is moved by a
  /// Gaussian of this standard deviation (TrainOptions::shape_noise), drawn from the box and the
  /// image's content, so that the same box of the same image gets the same offset whichever
  /// thread encodes it. 0 (the default): the box's own aspect.
  void setShapeNoise(double sigma) { shape_noise_ = sigma; }

  /// The last frame's codes (for benchmarks and tests).
  const FrameCodes& codes() const { return codes_; }
  const EncodingParams& params() const { return params_; }

 private:
  const EncodingParams& params_;
  const Pca& pca_;
  const Vocabulary& vocabulary_;
  EncoderCostModel cost_;
  DenseFeatureExtractor extractor_;
  FeatureGrid grid_;
  FeatureCoder coder_;
  FrameCodes codes_;
  std::vector<CellRect> box_cells_;
  FlairEncoder flair_;
  EncoderKind prepared_kind_ = EncoderKind::kDirect;  ///< the encoder of the prepared frame
  uint64_t image_hash_ = 0;                           ///< of the prepared frame (shape noise)
  double shape_noise_ = 0;
};

}  // namespace slamaware::recognizer
