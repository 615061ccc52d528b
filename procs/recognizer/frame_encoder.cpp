#include "procs/recognizer/frame_encoder.h"

#include <chrono>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <random>
#include <stdexcept>

namespace slamaware::recognizer {

namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

CellRect spanOf(const std::vector<PyramidBox>& boxes) {
  CellRect r;
  for (const auto& b : boxes) r = r.united(b.cells());
  return r;
}

// One FNV-1a step: the hashes below that seed the trainer's box-shape noise.
uint64_t fnvMix(uint64_t h, uint64_t v) { return (h ^ v) * 1099511628211ull; }

// A hash of an image's size and 64 of its pixels (an 8 x 8 grid): what tells two training crops
// apart, cheaply.
uint64_t contentHash(const cv::Mat& bgr) {
  uint64_t h = fnvMix(fnvMix(1469598103934665603ull, static_cast<uint64_t>(bgr.cols)),
                      static_cast<uint64_t>(bgr.rows));
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 8; ++i) {
      const cv::Vec3b p =
          bgr.at<cv::Vec3b>(bgr.rows * (2 * j + 1) / 16, bgr.cols * (2 * i + 1) / 16);
      h = fnvMix(h, static_cast<uint64_t>(p[0]) | static_cast<uint64_t>(p[1]) << 8 |
                        static_cast<uint64_t>(p[2]) << 16);
    }
  return h;
}

uint64_t hashBox(uint64_t h, const PyramidBox& b) {
  for (int k = 0; k < 5; ++k) h = fnvMix(h, static_cast<uint64_t>(b.u[k] * 65536 + b.v[k]));
  return h;
}

// A standard normal deviate by Box-Muller from the generator's raw output (std::normal_distribution
// is implementation-defined).
double standardNormal(std::mt19937_64& rng) {
  const double u1 = (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53;
  const double u2 = static_cast<double>(rng() >> 11) * 0x1.0p-53;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

}  // namespace

EncoderKind parseEncoderKind(const std::string& name) {
  if (name == "auto") return EncoderKind::kAuto;
  if (name == "direct") return EncoderKind::kDirect;
  if (name == "flair") return EncoderKind::kFlair;
  throw std::invalid_argument("encoder must be auto, direct or flair, not '" + name + "'");
}

const char* encoderName(EncoderKind kind) {
  switch (kind) {
    case EncoderKind::kAuto:
      return "auto";
    case EncoderKind::kDirect:
      return "direct";
    case EncoderKind::kFlair:
      return "flair";
  }
  return "?";
}

FrameEncoder::FrameEncoder(const EncodingParams& params, const Pca& pca,
                           const Vocabulary& vocabulary, EncoderCostModel cost)
    : params_(params),
      pca_(pca),
      vocabulary_(vocabulary),
      cost_(cost),
      extractor_(params.features),
      coder_(pca, vocabulary) {
  params_.validate();
  if (pca.inDims() != kFeatureDims || pca.outDims() != params.pca_dims ||
      vocabulary.dims() != params.pca_dims || vocabulary.size() != params.vocabulary_size)
    throw std::invalid_argument(
        "FrameEncoder: PCA / vocabulary do not match the encoding parameters");
}

bool FrameEncoder::snap(double x, double y, double w, double h, int width, int height,
                        PyramidBox* out) const {
  return snapBox(x, y, w, h, width, height, params_.features.pool_cell_px, out);
}

double FrameEncoder::estimateMs(const std::vector<PyramidBox>& boxes, EncoderKind kind) const {
  if (boxes.empty()) return 0;
  if (kind == EncoderKind::kFlair) {
    const CellRect r = spanOf(boxes);
    const double corners = static_cast<double>(r.width() + 1) * (r.height() + 1);
    return (corners * cost_.flair_ns_per_corner * 1e-3 + boxes.size() * cost_.flair_us_per_box) *
           1e-3;
  }
  const double per_cell = params_.features.descriptorsPerCell();
  double descriptors = 0;
  for (const auto& b : boxes) descriptors += static_cast<double>(b.cells().area()) * per_cell;
  return (boxes.size() * cost_.direct_us_per_box +
          descriptors * cost_.direct_ns_per_descriptor * 1e-3) *
         1e-3;
}

EncoderKind FrameEncoder::choose(const std::vector<PyramidBox>& boxes) const {
  const CellRect r = spanOf(boxes);
  const double table_mb =
      FlairEncoder::tableBytesFor(r, params_.vocabulary_size, params_.pca_dims) / 1e6;
  if (table_mb > cost_.flair_max_table_mb) return EncoderKind::kDirect;
  return estimateMs(boxes, EncoderKind::kFlair) < estimateMs(boxes, EncoderKind::kDirect)
             ? EncoderKind::kFlair
             : EncoderKind::kDirect;
}

void FrameEncoder::encode(const cv::Mat& bgr, const std::vector<PyramidBox>& boxes,
                          EncoderKind kind, ReusableMatrix* out, Stats* stats) {
  prepare(bgr, boxes, kind, stats);
  encodeRows(boxes, 0, boxes.size(), out, stats);
}

void FrameEncoder::prepare(const cv::Mat& bgr, const std::vector<PyramidBox>& boxes,
                           EncoderKind kind, Stats* stats) {
  Stats local;
  Stats& st = stats ? *stats : local;
  st = Stats();
  if (boxes.empty()) return;
  auto t0 = Clock::now();
  extractor_.setImage(bgr);
  const CellRect image_cells = extractor_.imageCells();
  const CellRect region = spanOf(boxes);
  if (!image_cells.contains(region))
    throw std::invalid_argument("FrameEncoder: box outside the image");
  // Features and codes only where some box is: a few boxes spread over the frame cover about
  // half of their span.
  box_cells_.clear();
  for (const auto& b : boxes) box_cells_.push_back(b.cells());
  extractor_.extract(region, &grid_, &box_cells_);
  st.features_ms = msSince(t0);
  st.region = region;

  t0 = Clock::now();
  coder_.code(grid_, params_.features.stepsPerCell(), &codes_, &box_cells_);
  st.coding_ms = msSince(t0);

  t0 = Clock::now();
  if (kind == EncoderKind::kAuto) kind = choose(boxes);
  st.used = prepared_kind_ = kind;
  if (kind == EncoderKind::kFlair) {
    flair_.build(codes_, vocabulary_, region);
    st.table_bytes = flair_.tableBytes();
  }
  image_hash_ = shape_noise_ > 0 ? contentHash(bgr) : 0;
  st.encode_ms = msSince(t0);
}

void FrameEncoder::encodeRows(const std::vector<PyramidBox>& boxes, size_t first, size_t count,
                              ReusableMatrix* out, Stats* stats) {
  if (first > boxes.size() || count > boxes.size() - first)
    throw std::invalid_argument("FrameEncoder::encodeRows: boxes out of range");
  const auto t0 = Clock::now();
  out->resize(static_cast<int64_t>(count), params_.encodedDims());
  DirectEncoder direct(codes_, vocabulary_);
  for (size_t r = 0; r < count; ++r) {
    const PyramidBox& box = boxes[first + r];
    float* row = out->row(static_cast<int64_t>(r));
    if (prepared_kind_ == EncoderKind::kFlair)
      flair_.encode(box, row);
    else
      direct.encode(box, row);
    if (params_.shapeDims() > 0) {
      double offset = 0;
      if (shape_noise_ > 0) {
        std::mt19937_64 rng(hashBox(image_hash_, box));
        offset = shape_noise_ * standardNormal(rng);
      }
      encodeBoxShape(box, params_.shape_bins, static_cast<int>(params_.shapeDims()),
                     row + params_.vladDims(), offset);
    }
  }
  if (stats) stats->encode_ms += msSince(t0);
}

double FrameEncoder::warmUp(int width, int height, EncoderKind kind) {
  const auto t0 = Clock::now();
  PyramidBox whole;
  if (width <= 0 || height <= 0 || !snap(0, 0, width, height, width, height, &whole)) return 0;
  cv::Mat noise(height, width, CV_8UC3);
  cv::RNG(1).fill(noise, cv::RNG::UNIFORM, 0, 256);
  const std::vector<PyramidBox> boxes{whole};
  ReusableMatrix out;
  encode(noise, boxes, EncoderKind::kDirect, &out);
  const double table_mb =
      FlairEncoder::tableBytesFor(whole.cells(), params_.vocabulary_size, params_.pca_dims) / 1e6;
  if (kind != EncoderKind::kDirect && table_mb <= cost_.flair_max_table_mb)
    encode(noise, boxes, EncoderKind::kFlair, &out);
  return msSince(t0);
}

}  // namespace slamaware::recognizer
