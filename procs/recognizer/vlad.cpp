#include "procs/recognizer/vlad.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#ifdef __AVX2__
#include <immintrin.h>
#endif

namespace slamaware::recognizer {

namespace {

constexpr int kLevel1 = 1;  // first 2x2 cell
constexpr int kLevel2 = 5;  // first 4x4 cell

// dst[i] += src[i]
inline void addTo(float* __restrict dst, const float* __restrict src, int n) {
  for (int i = 0; i < n; ++i) dst[i] += src[i];
}

// One pyramid coordinate: [lo, hi) of the image cells, snapped.
bool snapAxis(double lo, double hi, int size, int cell, int cells, int* c0, int* c1) {
  lo = std::max(lo, 0.0);
  hi = std::min(hi, static_cast<double>(size));
  if (!(hi > lo)) return false;
  int a = static_cast<int>(std::floor(lo / cell + 0.5));
  int b = static_cast<int>(std::floor(hi / cell + 0.5));
  a = std::clamp(a, 0, cells);
  b = std::clamp(b, 0, cells);
  if (b <= a) {
    a = std::clamp(static_cast<int>(std::floor(0.5 * (lo + hi) / cell)), 0, cells - 1);
    b = a + 1;
  }
  *c0 = a;
  *c1 = b;
  return true;
}

}  // namespace

bool snapBox(double x, double y, double w, double h, int width, int height, int pool_cell_px,
             PyramidBox* out) {
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(w) || !std::isfinite(h))
    return false;
  if (w <= 0 || h <= 0 || width <= 0 || height <= 0) return false;
  const int cells_x = (width + pool_cell_px - 1) / pool_cell_px;
  const int cells_y = (height + pool_cell_px - 1) / pool_cell_px;
  CellRect r;
  if (!snapAxis(x, x + w, width, pool_cell_px, cells_x, &r.u0, &r.u1)) return false;
  if (!snapAxis(y, y + h, height, pool_cell_px, cells_y, &r.v0, &r.v1)) return false;
  *out = pyramidFromCells(r);
  return true;
}

PyramidBox pyramidFromCells(const CellRect& c) {
  PyramidBox b;
  const int w = c.width(), h = c.height();
  for (int i = 0; i <= 4; ++i) {
    b.u[i] = c.u0 + (i * w) / 4;
    b.v[i] = c.v0 + (i * h) / 4;
  }
  return b;
}

void FrameCodes::reset(const CellRect& cells, int d) {
  region = cells;
  first.assign(1, 0);
  first.reserve(static_cast<size_t>(cells.area()) + 1);
  words.clear();
  counts.clear();
  residuals.resize(0, d);
}

float* FrameCodes::addEntry(int16_t word, float count) {
  const int64_t n = static_cast<int64_t>(words.size());
  words.push_back(word);
  counts.push_back(count);
  residuals.resize(n + 1, residuals.cols());  // keeps the rows written (same columns)
  return residuals.row(n);
}

namespace {

// Rows coded at a time: assigned to codewords, then pooled while they are still in the cache.
constexpr size_t kGroupRows = 2048;

// argmax_k y.c_k - |c_k|^2 / 2 with y = x B - offset  =  argmax_k x (B c_k) - bias_k.
Eigen::RowVectorXf wordBiasOf(const Pca& pca, const Vocabulary& vocabulary) {
  return pca.offset() * vocabulary.centers.transpose() +
         0.5f * vocabulary.centers.rowwise().squaredNorm().transpose();
}

WordScores checkedWordScores(const Pca& pca, const Vocabulary& vocabulary) {
  if (pca.outDims() != vocabulary.dims())
    throw std::invalid_argument("FeatureCoder: PCA and vocabulary dimensions differ");
  if (pca.inDims() != kFeatureDims)
    throw std::invalid_argument("FeatureCoder: PCA is not of " + std::to_string(kFeatureDims) +
                                "-D features");
  return WordScores(pca.basis * vocabulary.centers.transpose(), wordBiasOf(pca, vocabulary));
}

}  // namespace

FeatureCoder::FeatureCoder(const Pca& pca, const Vocabulary& vocabulary)
    : pca_(pca),
      vocabulary_(vocabulary),
      words_(checkedWordScores(pca, vocabulary)),
      offset_(pca.offset()) {}

void FeatureCoder::assignRows(const FeatureGrid& grid, size_t begin, size_t end) {
  // Rows with and without gradient apart (the extractor's flags): the latter only from their R,
  // G, B.
  for (auto& list : group_rows_) list.clear();
  for (auto& list : group_at_) list.clear();
  for (size_t i = begin; i < end; ++i) {
    const float* f = grid.features.row(rows_[i]);
    row_textured_[i] = grid.textured[static_cast<size_t>(rows_[i])];
    group_rows_[row_textured_[i]].push_back(f);
    group_at_[row_textured_[i]].push_back(i);
  }
  for (int textured = 0; textured < 2; ++textured) {
    group_words_.resize(group_rows_[textured].size());
    words_.assign(group_rows_[textured].data(), static_cast<int64_t>(group_words_.size()),
                  group_words_.data(), textured ? 0 : kSiftDims);
    for (size_t j = 0; j < group_words_.size(); ++j)
      row_words_[group_at_[textured][j]] = group_words_[j];
  }
}

void FeatureCoder::code(const FeatureGrid& grid, int steps_per_cell, FrameCodes* out,
                        const std::vector<CellRect>* only) {
  if (grid.features.cols() != kFeatureDims)
    throw std::invalid_argument("FeatureCoder: features are not " + std::to_string(kFeatureDims) +
                                "-D");
  if (grid.textured.size() != static_cast<size_t>(grid.features.rows()))
    throw std::invalid_argument("FeatureCoder: the grid has no textured flag per row");
  const CellRect& region = grid.region;
  const int K = vocabulary_.size(), D = pca_.outDims(), s = steps_per_cell;
  const int64_t cells = region.area();
  // 1. The cells to code, and their descriptors' rows, cell by cell.
  std::vector<uint8_t> covered(static_cast<size_t>(cells), only ? 0 : 1);
  if (only)
    for (const CellRect& r : *only) {
      const CellRect c = r.intersected(region);
      for (int v = c.v0; v < c.v1; ++v)
        for (int u = c.u0; u < c.u1; ++u)
          covered[static_cast<size_t>(int64_t{v - region.v0} * region.width() + (u - region.u0))] =
              1;
    }
  rows_.clear();
  for (int v = region.v0; v < region.v1; ++v)
    for (int u = region.u0; u < region.u1; ++u) {
      if (!covered[static_cast<size_t>(int64_t{v - region.v0} * region.width() + (u - region.u0))])
        continue;
      const int gx0 = (u - region.u0) * s, gy0 = (v - region.v0) * s;
      for (int t = 0; t < grid.scales; ++t)
        for (int gy = gy0; gy < gy0 + s; ++gy)
          for (int gx = gx0; gx < gx0 + s; ++gx) rows_.push_back(grid.rowOf(gx, gy, t));
    }
  row_words_.resize(rows_.size());
  row_textured_.resize(rows_.size());
  out->reset(region, D);
  acc_.assign(static_cast<size_t>(K) * kFeatureDims, 0.f);
  acc_n_.assign(static_cast<size_t>(K), 0.f);
  const size_t per_cell = static_cast<size_t>(s) * s * grid.scales;
  size_t next = 0;
  sums_.resize(0, kFeatureDims);
  for (int64_t c = 0; c < cells;) {
    // 2. The codeword of each row of the next group of cells (textured rows by WordScores, flat
    // ones from their R, G, B) ...
    int64_t group_end = c;
    size_t rows_end = next;
    while (group_end < cells && rows_end - next < kGroupRows)
      if (covered[static_cast<size_t>(group_end++)]) rows_end += per_cell;
    assignRows(grid, next, rows_end);
    // 3. ... then per cell and codeword, the count and the raw sum of its descriptors.
    for (; c < group_end; ++c) {
      if (covered[static_cast<size_t>(c)]) {
        for (size_t i = 0; i < per_cell; ++i, ++next) {
          const int k = row_words_[next];
          float* __restrict a = acc_.data() + int64_t{k} * kFeatureDims;
          const float* __restrict f = grid.features.row(rows_[next]);
          if (row_textured_[next]) {
            for (int e = 0; e < kFeatureDims; ++e) a[e] += f[e];
          } else {  // the SIFT part is zero: adding it would change no sum
            for (int e = kSiftDims; e < kFeatureDims; ++e) a[e] += f[e];
          }
          acc_n_[static_cast<size_t>(k)] += 1.f;
        }
        for (int k = 0; k < K; ++k) {
          if (acc_n_[static_cast<size_t>(k)] == 0.f) continue;
          const int64_t e = static_cast<int64_t>(out->words.size());
          out->addEntry(static_cast<int16_t>(k), acc_n_[static_cast<size_t>(k)]);
          sums_.resize(e + 1, kFeatureDims);
          float* a = acc_.data() + int64_t{k} * kFeatureDims;
          std::memcpy(sums_.row(e), a, sizeof(float) * kFeatureDims);
          std::fill(a, a + kFeatureDims, 0.f);
          acc_n_[static_cast<size_t>(k)] = 0.f;
        }
      }
      out->endCell();
    }
  }
  // 4. Residual sums: (sum x) B - n (offset + c_k), one product for all entries.
  const int64_t n = static_cast<int64_t>(out->words.size());
  if (n == 0) return;
  auto residuals = out->residuals.map();
  residuals.noalias() = Eigen::Map<const MatrixRM>(sums_.data(), n, kFeatureDims) * pca_.basis;
  for (int64_t e = 0; e < n; ++e) {
    const float cnt = out->counts[static_cast<size_t>(e)];
    const float* ck = vocabulary_.centers.row(out->words[static_cast<size_t>(e)]).data();
    float* r = residuals.row(e).data();
    for (int d = 0; d < D; ++d) r[d] -= cnt * (offset_[d] + ck[d]);
  }
}

void sumPyramidLevels(float* v, float* counts, int K, int D) {
  const int KD = K * D;
  for (int J = 0; J < 2; ++J)
    for (int I = 0; I < 2; ++I) {
      const int dst = kLevel1 + 2 * J + I;
      float* out = v + int64_t{dst} * KD;
      float* out_c = counts + int64_t{dst} * K;
      std::memset(out, 0, sizeof(float) * KD);
      std::memset(out_c, 0, sizeof(float) * K);
      for (int dj = 0; dj < 2; ++dj)
        for (int di = 0; di < 2; ++di) {
          const int src = kLevel2 + 4 * (2 * J + dj) + (2 * I + di);
          addTo(out, v + int64_t{src} * KD, KD);
          addTo(out_c, counts + int64_t{src} * K, K);
        }
    }
  std::memset(v, 0, sizeof(float) * KD);
  std::memset(counts, 0, sizeof(float) * K);
  for (int c = kLevel1; c < kLevel2; ++c) {
    addTo(v, v + int64_t{c} * KD, KD);
    addTo(counts, counts + int64_t{c} * K, K);
  }
}

void encodeBoxShape(const PyramidBox& box, int bins, int block_dims, float* out,
                    double log_aspect_offset) {
  std::fill(out, out + block_dims, 0.f);
  if (bins < 2) return;
  const int w = box.u[4] - box.u[0], h = box.v[4] - box.v[0];
  if (w <= 0 || h <= 0) return;
  const double a = std::clamp(std::log(static_cast<double>(w) / h) + log_aspect_offset,
                              -kShapeLogAspectMax, kShapeLogAspectMax);
  const double at = (a + kShapeLogAspectMax) / (2 * kShapeLogAspectMax) * (bins - 1);
  const int lo = std::min(static_cast<int>(at), bins - 2);
  const double f = at - lo;
  out[lo] = static_cast<float>(1.0 - f);
  out[lo + 1] = static_cast<float>(f);
}

void finishVlad(float* v, const float* counts, int K, int D) {
  const int64_t n = int64_t{kPyramidCells} * K * D;
  for (int64_t b = 0; b < int64_t{kPyramidCells} * K; ++b)
    if (counts[b] == 0.f) std::memset(v + b * D, 0, sizeof(float) * D);
  // sign(v) sqrt(|v|); the squared norm of the result is sum |v|.
  double l1 = 0;
  int64_t i = 0;
#ifdef __AVX2__
  const __m256 sign_mask = _mm256_set1_ps(-0.f);
  __m256 acc = _mm256_setzero_ps();
  for (; i + 8 <= n; i += 8) {
    const __m256 x = _mm256_loadu_ps(v + i);
    const __m256 sign = _mm256_and_ps(x, sign_mask);
    const __m256 a = _mm256_andnot_ps(sign_mask, x);
    acc = _mm256_add_ps(acc, a);
    _mm256_storeu_ps(v + i, _mm256_or_ps(_mm256_sqrt_ps(a), sign));
  }
  alignas(32) float lanes[8];
  _mm256_store_ps(lanes, acc);
  for (float l : lanes) l1 += l;
#endif
  for (; i < n; ++i) {
    const float a = std::fabs(v[i]);
    l1 += a;
    v[i] = std::copysign(std::sqrt(a), v[i]);
  }
  if (l1 <= 0) return;
  const float scale = static_cast<float>(1.0 / std::sqrt(l1));
  for (int64_t j = 0; j < n; ++j) v[j] *= scale;
}

void DirectEncoder::encode(const PyramidBox& box, float* out) {
  const FrameCodes& c = codes_;
  const int K = vocabulary_.size(), D = vocabulary_.dims(), KD = K * D;
  if (!c.region.contains(box.cells()))
    throw std::invalid_argument("DirectEncoder: box outside the coded region");
  std::memset(out, 0, sizeof(float) * kPyramidCells * KD);
  counts_.assign(static_cast<size_t>(kPyramidCells) * K, 0.f);
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) {
      const int cell = kLevel2 + 4 * j + i;
      float* dst = out + int64_t{cell} * KD;
      float* dst_c = counts_.data() + int64_t{cell} * K;
      // The entries of the pooling cells [u[i], u[i+1]) x [v[j], v[j+1]).
      for (int v = box.v[j]; v < box.v[j + 1]; ++v)
        for (int u = box.u[i]; u < box.u[i + 1]; ++u) {
          const size_t ci = static_cast<size_t>(c.cellIndex(u, v));
          for (int32_t e = c.first[ci]; e < c.first[ci + 1]; ++e) {
            const int k = c.words[static_cast<size_t>(e)];
            addTo(dst + int64_t{k} * D, c.residuals.row(e), D);
            dst_c[k] += c.counts[static_cast<size_t>(e)];
          }
        }
    }
  sumPyramidLevels(out, counts_.data(), K, D);
  finishVlad(out, counts_.data(), K, D);
}

size_t FlairEncoder::tableBytesFor(const CellRect& region, int K, int D) {
  if (region.empty()) return 0;
  const size_t corners =
      static_cast<size_t>(region.width() + 1) * static_cast<size_t>(region.height() + 1);
  return corners * static_cast<size_t>(K) * static_cast<size_t>(D + 1) * sizeof(float);
}

void FlairEncoder::build(const FrameCodes& codes, const Vocabulary& vocabulary,
                         const CellRect& region) {
  if (!codes.region.contains(region) || region.empty())
    throw std::invalid_argument("FlairEncoder: table region outside the coded region");
  region_ = region;
  K_ = vocabulary.size();
  D_ = vocabulary.dims();
  const int KD = K_ * D_;
  const int W = region.width(), H = region.height();
  const size_t corners = static_cast<size_t>(W + 1) * static_cast<size_t>(H + 1);
  if (sums_.size() < corners * KD) sums_.resize(corners * KD);
  if (counts_.size() < corners * K_) counts_.resize(corners * K_);
  // Row 0 and column 0 are zero; corner (a, b) = corner (a, b - 1) + the running sum of cell
  // row b - 1 up to column a - 1.
  std::memset(sums_.data(), 0, sizeof(float) * (W + 1) * KD);
  std::memset(counts_.data(), 0, sizeof(float) * (W + 1) * K_);
  row_sums_.resize(KD);
  row_counts_.resize(K_);
  for (int b = 1; b <= H; ++b) {
    std::fill(row_sums_.begin(), row_sums_.end(), 0.f);
    std::fill(row_counts_.begin(), row_counts_.end(), 0.f);
    std::memset(sums_.data() + int64_t{b} * (W + 1) * KD, 0, sizeof(float) * KD);
    std::memset(counts_.data() + int64_t{b} * (W + 1) * K_, 0, sizeof(float) * K_);
    for (int a = 1; a <= W; ++a) {
      // The entries of cell (region.u0 + a - 1, region.v0 + b - 1); none where no box reads it.
      const size_t ci = static_cast<size_t>(codes.cellIndex(region.u0 + a - 1, region.v0 + b - 1));
      for (int32_t e = codes.first[ci]; e < codes.first[ci + 1]; ++e) {
        const int k = codes.words[static_cast<size_t>(e)];
        addTo(row_sums_.data() + int64_t{k} * D_, codes.residuals.row(e), D_);
        row_counts_[k] += codes.counts[static_cast<size_t>(e)];
      }
      float* __restrict dst = sums_.data() + (int64_t{b} * (W + 1) + a) * KD;
      const float* __restrict up = sums_.data() + (int64_t{b - 1} * (W + 1) + a) * KD;
      const float* __restrict acc = row_sums_.data();
      for (int i = 0; i < KD; ++i) dst[i] = up[i] + acc[i];
      float* __restrict dst_c = counts_.data() + (int64_t{b} * (W + 1) + a) * K_;
      const float* __restrict up_c = counts_.data() + (int64_t{b - 1} * (W + 1) + a) * K_;
      for (int k = 0; k < K_; ++k) dst_c[k] = up_c[k] + row_counts_[k];
    }
  }
}

void FlairEncoder::encode(const PyramidBox& box, float* out) {
  if (!region_.contains(box.cells()))
    throw std::invalid_argument("FlairEncoder: box outside the table region");
  const int K = K_, D = D_, KD = K * D;
  box_counts_.resize(static_cast<size_t>(kPyramidCells) * K);
  int a[5], b[5];
  for (int i = 0; i < 5; ++i) {
    a[i] = box.u[i] - region_.u0;
    b[i] = box.v[i] - region_.v0;
  }
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) {
      const int cell = kLevel2 + 4 * j + i;
      float* __restrict dst = out + int64_t{cell} * KD;
      const float* __restrict p11 = sumsAt(a[i + 1], b[j + 1]);
      const float* __restrict p01 = sumsAt(a[i], b[j + 1]);
      const float* __restrict p10 = sumsAt(a[i + 1], b[j]);
      const float* __restrict p00 = sumsAt(a[i], b[j]);
      for (int x = 0; x < KD; ++x) dst[x] = (p11[x] - p01[x]) - (p10[x] - p00[x]);
      float* dst_c = box_counts_.data() + int64_t{cell} * K;
      const float* c11 = countsAt(a[i + 1], b[j + 1]);
      const float* c01 = countsAt(a[i], b[j + 1]);
      const float* c10 = countsAt(a[i + 1], b[j]);
      const float* c00 = countsAt(a[i], b[j]);
      for (int k = 0; k < K; ++k) dst_c[k] = (c11[k] - c01[k]) - (c10[k] - c00[k]);
    }
  // Rounding noise in blocks of codewords absent from a 4x4 cell must not reach the coarser
  // levels: zero them before summing up.
  for (int cell = kLevel2; cell < kPyramidCells; ++cell)
    for (int k = 0; k < K; ++k)
      if (box_counts_[static_cast<size_t>(cell) * K + k] == 0.f)
        std::memset(out + int64_t{cell} * KD + int64_t{k} * D, 0, sizeof(float) * D);
  sumPyramidLevels(out, box_counts_.data(), K, D);
  finishVlad(out, box_counts_.data(), K, D);
}

}  // namespace slamaware::recognizer
