#include "procs/recognizer/vlad.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <stdexcept>

#ifdef __AVX2__
#include <immintrin.h>
#endif

namespace slamaware {

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

void codeFeatures(const FeatureGrid& grid, int steps_per_cell, const Pca& pca,
                  const Vocabulary& vocabulary, FrameCodes* out, const std::vector<CellRect>* only) {
  if (pca.outDims() != vocabulary.dims())
    throw std::invalid_argument("codeFeatures: PCA and vocabulary dimensions differ");
  out->region = grid.region;
  out->nx = grid.nx;
  out->ny = grid.ny;
  out->scales = grid.scales;
  out->steps_per_cell = steps_per_cell;
  out->projected.resize(grid.features.rows(), pca.outDims());
  if (!only) {
    pca.project(grid.features.map(), out->projected.map());
    vocabulary.assign(out->projected.map(), &out->words);
    return;
  }
  out->words.assign(static_cast<size_t>(grid.features.rows()), FrameCodes::kNotCoded);
  const Eigen::RowVectorXf offset = pca.offset();
  const Vocabulary::Lookup lookup = vocabulary.lookup();
  const CellRect& region = grid.region;
  const int W = region.width(), s = steps_per_cell;
  std::vector<uint8_t> covered(static_cast<size_t>(std::max(0, W)));
  std::vector<std::pair<int, int>> runs;  // of covered cells [a, b) on a row of cells
  for (int v = region.v0; v < region.v1; ++v) {
    std::fill(covered.begin(), covered.end(), 0);
    for (const CellRect& r : *only) {
      const CellRect c = r.intersected(region);
      if (v >= c.v0 && v < c.v1)
        for (int u = c.u0; u < c.u1; ++u) covered[u - region.u0] = 1;
    }
    runs.clear();
    for (int a = 0; a < W; ++a) {
      if (!covered[a]) continue;
      int b = a;
      while (b < W && covered[b]) ++b;
      runs.emplace_back(a, b);
      a = b;
    }
    for (int t = 0; t < grid.scales; ++t)
      for (int gy = (v - region.v0) * s; gy < (v - region.v0 + 1) * s; ++gy)
        for (const auto& [a, b] : runs) {
          const int64_t first = grid.rowOf(a * s, gy, t), n = int64_t{b - a} * s;
          pca.project(grid.features.map().middleRows(first, n), out->projected.map().middleRows(first, n), offset);
          vocabulary.assign(out->projected.map().middleRows(first, n), out->words.data() + first, lookup);
        }
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
  const int K = vocabulary_.size(), D = vocabulary_.dims(), KD = K * D, s = c.steps_per_cell;
  if (!c.region.contains(box.cells()))
    throw std::invalid_argument("DirectEncoder: box outside the coded region");
  std::memset(out, 0, sizeof(float) * kPyramidCells * KD);
  counts_.assign(static_cast<size_t>(kPyramidCells) * K, 0.f);
  const int16_t* words = c.words.data();
  const float* y = c.projected.data();
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) {
      const int cell = kLevel2 + 4 * j + i;
      float* dst = out + int64_t{cell} * KD;
      float* dst_c = counts_.data() + int64_t{cell} * K;
      // Grid points of the pooling cells [u[i], u[i+1]) x [v[j], v[j+1]).
      const int gx0 = (box.u[i] - c.region.u0) * s, gx1 = (box.u[i + 1] - c.region.u0) * s;
      const int gy0 = (box.v[j] - c.region.v0) * s, gy1 = (box.v[j + 1] - c.region.v0) * s;
      for (int t = 0; t < c.scales; ++t)
        for (int gy = gy0; gy < gy1; ++gy) {
          const int64_t base = c.rowOf(0, gy, t);
          for (int64_t r = base + gx0; r < base + gx1; ++r) {
            const int k = words[r];
            addTo(dst + int64_t{k} * D, y + r * D, D);
            dst_c[k] += 1.f;
          }
        }
      // Sum of residuals = sum of descriptors - count * codeword.
      for (int k = 0; k < K; ++k)
        if (dst_c[k] > 0.f) {
          const float n = dst_c[k];
          const float* ck = vocabulary_.centers.row(k).data();
          float* d = dst + int64_t{k} * D;
          for (int e = 0; e < D; ++e) d[e] -= n * ck[e];
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
  const int KD = K_ * D_, s = codes.steps_per_cell;
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
  const int16_t* words = codes.words.data();
  const float* y = codes.projected.data();
  for (int b = 1; b <= H; ++b) {
    std::fill(row_sums_.begin(), row_sums_.end(), 0.f);
    std::fill(row_counts_.begin(), row_counts_.end(), 0.f);
    std::memset(sums_.data() + int64_t{b} * (W + 1) * KD, 0, sizeof(float) * KD);
    std::memset(counts_.data() + int64_t{b} * (W + 1) * K_, 0, sizeof(float) * K_);
    const int gy0 = (region.v0 + b - 1 - codes.region.v0) * s;
    for (int a = 1; a <= W; ++a) {
      // The descriptors of cell (region.u0 + a - 1, region.v0 + b - 1).
      const int gx0 = (region.u0 + a - 1 - codes.region.u0) * s;
      for (int t = 0; t < codes.scales; ++t)
        for (int gy = gy0; gy < gy0 + s; ++gy)
          for (int gx = gx0; gx < gx0 + s; ++gx) {
            const int64_t r = codes.rowOf(gx, gy, t);
            const int k = words[r];
            if (k < 0) continue;  // no box reads this cell
            float* __restrict acc = row_sums_.data() + int64_t{k} * D_;
            const float* __restrict x = y + r * D_;
            const float* __restrict ck = vocabulary.centers.row(k).data();
            for (int e = 0; e < D_; ++e) acc[e] += x[e] - ck[e];
            row_counts_[k] += 1.f;
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

}  // namespace slamaware
