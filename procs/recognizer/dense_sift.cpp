#include "procs/recognizer/dense_sift.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#ifdef __AVX2__
#include <immintrin.h>
#endif

extern "C" {
#include <vl/dsift.h>
#include <vl/mathop.h>
}

namespace slamaware::recognizer {

namespace {

constexpr int kOrientations = 8;
constexpr int kSiftLength = 128;

// VLFeat's _vl_dsift_get_bin_window_mean: the mean over a bin of a Gaussian window of sigma
// window_size bins centred on the descriptor.
float binWindowMean(int bin, int num_bins, int index, double window_size) {
  const float delta = bin * (index - 0.5F * (num_bins - 1));
  const float sigma = static_cast<float>(bin) * static_cast<float>(window_size);
  float acc = 0.0F;
  for (int x = -bin + 1; x <= bin - 1; ++x) {
    const float z = (x - delta) / sigma;
    acc += std::exp(-0.5F * z * z);
  }
  return acc / static_cast<float>(2 * bin - 1);
}

template <class T>
void growTo(std::vector<T>* v, size_t n) {
  if (v->size() < n) v->resize(n);
}

// A descriptor's sum and sum of squares (its mass and its L2 norm), in a fixed order of partial
// sums (VLFeat adds them one by one; the results differ in rounding only); VLFeat's
// _vl_dsift_normalize_histogram (divide by the L2 norm + epsilon) as a multiplication by the
// reciprocal. With AVX2 the descriptor is held as 16 vectors of 8 elements.
#ifdef __AVX2__
inline float horizontalSum(__m256 v) {
  const __m128 s = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
  const __m128 t = _mm_add_ps(s, _mm_movehl_ps(s, s));
  return _mm_cvtss_f32(_mm_add_ss(t, _mm_shuffle_ps(t, t, 1)));
}

inline float sumOf16(const __m256* v) {
  __m256 a[4];
  for (int q = 0; q < 4; ++q)
    a[q] = _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(v[q], v[4 + q]), v[8 + q]), v[12 + q]);
  return horizontalSum(_mm256_add_ps(_mm256_add_ps(a[0], a[1]), _mm256_add_ps(a[2], a[3])));
}

inline float sumSquaresOf16(const __m256* v) {
  __m256 a[4];
  for (int q = 0; q < 4; ++q) {
    a[q] = _mm256_mul_ps(v[q], v[q]);
    for (int r = 1; r < 4; ++r) a[q] = _mm256_fmadd_ps(v[4 * r + q], v[4 * r + q], a[q]);
  }
  return horizontalSum(_mm256_add_ps(_mm256_add_ps(a[0], a[1]), _mm256_add_ps(a[2], a[3])));
}

inline void scaleByInverseNorm(__m256* v) {
  const __m256 inv = _mm256_set1_ps(1.0F / (vl_fast_sqrt_f(sumSquaresOf16(v)) + VL_EPSILON_F));
  for (int q = 0; q < 16; ++q) v[q] = _mm256_mul_ps(v[q], inv);
}
#else
inline float sum128(const float* h) {
  float acc = 0;
  for (int i = 0; i < kSiftLength; ++i) acc += h[i];
  return acc;
}

// Then (clamp) VLFeat's clamping of the elements at 0.2.
inline void normalizeHistogram(float* h, bool clamp) {
  float ss = 0;
  for (int i = 0; i < kSiftLength; ++i) ss += h[i] * h[i];
  const float inv = 1.0F / (vl_fast_sqrt_f(ss) + VL_EPSILON_F);
  for (int i = 0; i < kSiftLength; ++i) h[i] *= inv;
  if (clamp)
    for (int i = 0; i < kSiftLength; ++i) h[i] = std::min(h[i], 0.2F);
}
#endif

// Orientation-binned gradient of image row y, columns [x0, x1], into out ((x1 - x0 + 1) x 8,
// zero except the two bins each pixel votes for). VLFeat's formulas, term by term.
void gradientRow(const float* image, int width, int height, int y, int x0, int x1, float* out,
                 int32_t* bins, float* w0s, float* w1s) {
  const int n = x1 - x0 + 1;
  std::memset(out, 0, sizeof(float) * n * kOrientations);
  const float* row = image + int64_t{y} * width;
  const float* up = y > 0 ? row - width : row;
  const float* down = y < height - 1 ? row + width : row;
  const bool one_sided_y = y == 0 || y == height - 1;
  auto scalarPixel = [&](int k) {
    const int x = x0 + k;
    const float gy = one_sided_y ? down[x] - up[x] : 0.5F * (down[x] - up[x]);
    float gx;
    if (x == 0)
      gx = row[x + 1] - row[x];
    else if (x == width - 1)
      gx = row[x] - row[x - 1];
    else
      gx = 0.5F * (row[x + 1] - row[x - 1]);
    const float angle = vl_fast_atan2_f(gy, gx);
    const float mod = vl_fast_sqrt_f(gx * gx + gy * gy);
    const float nt = vl_mod_2pi_f(angle) * (kOrientations / (2 * VL_PI));
    const int bint = static_cast<int>(vl_floor_f(nt));
    const float rbint = nt - bint;
    float* o = out + k * kOrientations;
    o[bint % kOrientations] = (1 - rbint) * mod;
    o[(bint + 1) % kOrientations] = rbint * mod;
  };
  int k = 0;
  for (; k < n && x0 + k < 1; ++k) scalarPixel(k);
#ifdef __AVX2__
  // Interior pixels, 8 at a time.
  const int k_begin = k;
  const __m256 half = _mm256_set1_ps(0.5F);
  const __m256 sign_mask = _mm256_set1_ps(-0.0F);
  const __m256 eps = _mm256_set1_ps(VL_EPSILON_F);
  const __m256 zero = _mm256_setzero_ps();
  const __m256 c3 = _mm256_set1_ps(0.1821F), c1 = _mm256_set1_ps(0.9675F);
  const __m256 pi4 = _mm256_set1_ps(static_cast<float>(VL_PI / 4));
  const __m256 pi34 = _mm256_set1_ps(static_cast<float>(3 * VL_PI / 4));
  const __m256 two_pi = _mm256_set1_ps(static_cast<float>(2 * VL_PI));
  const __m256d to_bins = _mm256_set1_pd(kOrientations / (2 * VL_PI));
  const __m256 one = _mm256_set1_ps(1.0F), three_halves = _mm256_set1_ps(1.5F);
  const __m256 tiny = _mm256_set1_ps(1e-8F);
  const __m256i magic = _mm256_set1_epi32(0x5f3759df);
  for (; k + 8 <= n && x0 + k + 7 <= width - 2; k += 8) {
    const int x = x0 + k;
    const __m256 gx = _mm256_mul_ps(
        half, _mm256_sub_ps(_mm256_loadu_ps(row + x + 1), _mm256_loadu_ps(row + x - 1)));
    __m256 gy = _mm256_sub_ps(_mm256_loadu_ps(down + x), _mm256_loadu_ps(up + x));
    if (!one_sided_y) gy = _mm256_mul_ps(half, gy);
    // vl_fast_atan2_f
    const __m256 abs_y = _mm256_add_ps(_mm256_andnot_ps(sign_mask, gy), eps);
    const __m256 xpos = _mm256_cmp_ps(gx, zero, _CMP_GE_OQ);
    const __m256 r_pos = _mm256_div_ps(_mm256_sub_ps(gx, abs_y), _mm256_add_ps(gx, abs_y));
    const __m256 r_neg = _mm256_div_ps(_mm256_add_ps(gx, abs_y), _mm256_sub_ps(abs_y, gx));
    const __m256 r = _mm256_blendv_ps(r_neg, r_pos, xpos);
    __m256 angle = _mm256_blendv_ps(pi34, pi4, xpos);
    const __m256 poly = _mm256_mul_ps(_mm256_sub_ps(_mm256_mul_ps(_mm256_mul_ps(c3, r), r), c1), r);
    angle = _mm256_add_ps(angle, poly);
    const __m256 yneg = _mm256_cmp_ps(gy, zero, _CMP_LT_OQ);
    angle = _mm256_blendv_ps(angle, _mm256_xor_ps(angle, sign_mask), yneg);
    // vl_mod_2pi_f (the angle is in [-pi, pi] here)
    angle = _mm256_blendv_ps(angle, _mm256_add_ps(angle, two_pi),
                             _mm256_cmp_ps(angle, zero, _CMP_LT_OQ));
    // nt = angle * (8 / (2 pi)) in double, as VLFeat's expression is
    const __m256d lo = _mm256_mul_pd(_mm256_cvtps_pd(_mm256_castps256_ps128(angle)), to_bins);
    const __m256d hi = _mm256_mul_pd(_mm256_cvtps_pd(_mm256_extractf128_ps(angle, 1)), to_bins);
    const __m256 nt =
        _mm256_insertf128_ps(_mm256_castps128_ps256(_mm256_cvtpd_ps(lo)), _mm256_cvtpd_ps(hi), 1);
    const __m256i bint = _mm256_cvttps_epi32(nt);
    const __m256 rbint = _mm256_sub_ps(nt, _mm256_cvtepi32_ps(bint));
    // vl_fast_sqrt_f
    const __m256 s = _mm256_add_ps(_mm256_mul_ps(gx, gx), _mm256_mul_ps(gy, gy));
    const __m256 xhalf = _mm256_mul_ps(half, s);
    __m256 u =
        _mm256_castsi256_ps(_mm256_sub_epi32(magic, _mm256_srli_epi32(_mm256_castps_si256(s), 1)));
    u = _mm256_mul_ps(u, _mm256_sub_ps(three_halves, _mm256_mul_ps(_mm256_mul_ps(xhalf, u), u)));
    u = _mm256_mul_ps(u, _mm256_sub_ps(three_halves, _mm256_mul_ps(_mm256_mul_ps(xhalf, u), u)));
    const __m256 mod = _mm256_andnot_ps(_mm256_cmp_ps(s, tiny, _CMP_LT_OQ), _mm256_mul_ps(s, u));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(bins + k), bint);
    _mm256_storeu_ps(w0s + k, _mm256_mul_ps(_mm256_sub_ps(one, rbint), mod));
    _mm256_storeu_ps(w1s + k, _mm256_mul_ps(rbint, mod));
  }
  for (int q = k_begin; q < k; ++q) {
    float* o = out + q * kOrientations;
    o[bins[q] % kOrientations] = w0s[q];
    o[(bins[q] + 1) % kOrientations] = w1s[q];
  }
#else
  (void)bins;
  (void)w0s;
  (void)w1s;
#endif
  for (; k < n; ++k) scalarPixel(k);
}

// Triangular filter of 8-lane pixels (the 8 orientations): for q = 0 .. n - 1,
// out[q * 8 + c] = sum_d (b - |d|) * in[q * in_step + d * in_stride + c], d = -(b-1) .. b-1.
void triangleFilter(const float* in, int64_t in_step, int64_t in_stride, int b, int n, float* out) {
#ifdef __AVX2__
  __m256 w[64];
  const int taps = 2 * b - 1;
  if (taps > 64) throw std::invalid_argument("denseSiftFlat: bin size over 32");
  for (int d = 0; d < taps; ++d)
    w[d] = _mm256_set1_ps(static_cast<float>(b - std::abs(d - (b - 1))));
  int q = 0;
  // Four outputs at a time: independent accumulators hide the FMA latency.
  for (; q + 4 <= n; q += 4) {
    const float* p = in + q * in_step - (b - 1) * in_stride;
    __m256 a0 = _mm256_setzero_ps(), a1 = _mm256_setzero_ps(), a2 = _mm256_setzero_ps(),
           a3 = _mm256_setzero_ps();
    for (int d = 0; d < taps; ++d, p += in_stride) {
      a0 = _mm256_fmadd_ps(w[d], _mm256_loadu_ps(p), a0);
      a1 = _mm256_fmadd_ps(w[d], _mm256_loadu_ps(p + in_step), a1);
      a2 = _mm256_fmadd_ps(w[d], _mm256_loadu_ps(p + 2 * in_step), a2);
      a3 = _mm256_fmadd_ps(w[d], _mm256_loadu_ps(p + 3 * in_step), a3);
    }
    _mm256_storeu_ps(out + q * kOrientations, a0);
    _mm256_storeu_ps(out + (q + 1) * kOrientations, a1);
    _mm256_storeu_ps(out + (q + 2) * kOrientations, a2);
    _mm256_storeu_ps(out + (q + 3) * kOrientations, a3);
  }
  for (; q < n; ++q) {
    const float* p = in + q * in_step - (b - 1) * in_stride;
    __m256 a = _mm256_setzero_ps();
    for (int d = 0; d < taps; ++d, p += in_stride) a = _mm256_fmadd_ps(w[d], _mm256_loadu_ps(p), a);
    _mm256_storeu_ps(out + q * kOrientations, a);
  }
#else
  for (int q = 0; q < n; ++q) {
    float acc[kOrientations] = {0, 0, 0, 0, 0, 0, 0, 0};
    for (int d = -(b - 1); d <= b - 1; ++d) {
      const float wd = static_cast<float>(b - std::abs(d));
      const float* p = in + q * in_step + d * in_stride;
      for (int c = 0; c < kOrientations; ++c) acc[c] += wd * p[c];
    }
    std::memcpy(out + q * kOrientations, acc, sizeof(acc));
  }
#endif
}

}  // namespace

void denseSiftFlat(const float* image, int width, int height, const DsiftGeometry& g,
                   const DsiftOutput& out) {
  const int b = g.bin;
  if (b < 1 || g.step < 1 || g.nx < 1 || g.ny < 1 ||
      (out.row_pitch != 0 && out.row_pitch < static_cast<size_t>(g.nx)))
    throw std::invalid_argument("denseSiftFlat: bad geometry");
  if (!out.descriptors || !out.norms || out.tail_dims < 0 || (out.tail_dims > 0 && !out.tail) ||
      out.stride < static_cast<size_t>(kSiftLength + out.tail_dims))
    throw std::invalid_argument("denseSiftFlat: bad output");
  const size_t pitch_out = out.row_pitch ? out.row_pitch : static_cast<size_t>(g.nx);
  const int span_x = g.step * (g.nx - 1) + 3 * b, span_y = g.step * (g.ny - 1) + 3 * b;
  // Pixels the frames read: their bin centres +- (b - 1).
  const int x0 = g.min_x - (b - 1), x1 = g.min_x + span_x + (b - 1);
  const int y0 = g.min_y - (b - 1), y1 = g.min_y + span_y + (b - 1);
  if (x0 < 0 || y0 < 0 || x1 > width - 1 || y1 > height - 1)
    throw std::invalid_argument("denseSiftFlat: frames reach beyond the " + std::to_string(width) +
                                "x" + std::to_string(height) + " image");
  // Bin centres lie on a grid of pitch gcd(step, bin) from (min_x, min_y).
  const int pitch = std::gcd(g.step, b);
  const int cols = span_x / pitch + 1, rows = span_y / pitch + 1;
  const int n_in = x1 - x0 + 1;

  // Horizontal pass: every input row, filtered at the bin-centre columns.
  const int in_rows = y1 - y0 + 1;
  // Scratch memory, kept per thread across calls (a frame would otherwise page-fault it in anew).
  thread_local std::vector<float> horizontal, grad, w0, w1, filtered;
  thread_local std::vector<int32_t> bins;
  growTo(&horizontal, static_cast<size_t>(in_rows) * cols * kOrientations);
  growTo(&grad, static_cast<size_t>(n_in) * kOrientations);
  growTo(&bins, static_cast<size_t>(n_in) + 8);
  growTo(&w0, static_cast<size_t>(n_in) + 8);
  growTo(&w1, static_cast<size_t>(n_in) + 8);
  for (int y = y0; y <= y1; ++y) {
    gradientRow(image, width, height, y, x0, x1, grad.data(), bins.data(), w0.data(), w1.data());
    float* out = horizontal.data() + static_cast<size_t>(y - y0) * cols * kOrientations;
    triangleFilter(grad.data() + static_cast<size_t>(g.min_x - x0) * kOrientations,
                   int64_t{pitch} * kOrientations, kOrientations, b, cols, out);
  }
  // Vertical pass at the bin-centre rows.
  growTo(&filtered, static_cast<size_t>(rows) * cols * kOrientations);
  const int64_t row_stride = int64_t{cols} * kOrientations;
  for (int r = 0; r < rows; ++r) {
    const int local = g.min_y + pitch * r - y0;
    const float* in = horizontal.data() + local * row_stride;
    float* out = filtered.data() + r * row_stride;
    triangleFilter(in, kOrientations, row_stride, b, cols, out);
  }

  // Bin weights: VLFeat's flat-window weight (the mean of the Gaussian window over the bin) times
  // the triangular kernels' 1 / b^2 per axis (as the installed VLFeat 0.9.21 computes it: the
  // descriptor is normalised anyway, but the mass that the contrast threshold reads is not).
  float weight[4][4];
  for (int by = 0; by < 4; ++by)
    for (int bx = 0; bx < 4; ++bx) {
      const float wy = binWindowMean(b, 4, by, 2.0);
      const float wx = binWindowMean(b, 4, bx, 2.0);
      weight[by][bx] = (wx * wy) / (static_cast<float>(b) * b * b * b);
    }
  const float frame_size = static_cast<float>(3 * b + 1);
  const float norm_constant = frame_size * frame_size / (static_cast<float>(b) * b);
  const int step_cols = g.step / pitch, bin_cols = b / pitch;
  // Each descriptor is assembled, measured and normalised in registers and written once (the
  // output grid is far larger than the cache).
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) {
      const size_t frame = static_cast<size_t>(j) * g.nx + i;
      float* d = out.descriptors + (static_cast<size_t>(j) * pitch_out + i) * out.stride;
      float& norm = out.norms[frame];
      if (out.tail_dims > 0)
        std::memcpy(d + kSiftLength, out.tail + frame * out.tail_dims,
                    sizeof(float) * out.tail_dims);
#ifdef __AVX2__
      __m256 v[16];
      for (int by = 0; by < 4; ++by) {
        const float* src_row = filtered.data() + (j * step_cols + by * bin_cols) * row_stride;
        for (int bx = 0; bx < 4; ++bx)
          v[by * 4 + bx] = _mm256_mul_ps(
              _mm256_set1_ps(weight[by][bx]),
              _mm256_loadu_ps(src_row + (i * step_cols + bx * bin_cols) * kOrientations));
      }
      norm = sumOf16(v) / norm_constant;
      if (norm < out.zero_below) {
        for (int q = 0; q < 16; ++q) _mm256_storeu_ps(d + 8 * q, _mm256_setzero_ps());
        continue;
      }
      scaleByInverseNorm(v);
      const __m256 clamp = _mm256_set1_ps(0.2F);
      for (int q = 0; q < 16; ++q) v[q] = _mm256_min_ps(v[q], clamp);
      scaleByInverseNorm(v);
      for (int q = 0; q < 16; ++q) _mm256_storeu_ps(d + 8 * q, v[q]);
#else
      for (int by = 0; by < 4; ++by) {
        const float* src_row = filtered.data() + (j * step_cols + by * bin_cols) * row_stride;
        for (int bx = 0; bx < 4; ++bx) {
          const float* src = src_row + (i * step_cols + bx * bin_cols) * kOrientations;
          float* dst = d + (by * 4 + bx) * kOrientations;
          for (int c = 0; c < kOrientations; ++c) dst[c] = weight[by][bx] * src[c];
        }
      }
      norm = sum128(d) / norm_constant;
      if (norm < out.zero_below) {
        std::memset(d, 0, sizeof(float) * kSiftLength);
        continue;
      }
      normalizeHistogram(d, true);
      normalizeHistogram(d, false);
#endif
    }
}

void denseSiftVlfeat(const float* image, int width, int height, const DsiftGeometry& g,
                     float* descriptors, size_t stride, float* norms) {
  std::unique_ptr<VlDsiftFilter, void (*)(VlDsiftFilter*)> f(vl_dsift_new(width, height),
                                                             vl_dsift_delete);
  VlDsiftDescriptorGeometry geom;
  geom.numBinT = kOrientations;
  geom.numBinX = 4;
  geom.numBinY = 4;
  geom.binSizeX = g.bin;
  geom.binSizeY = g.bin;
  vl_dsift_set_geometry(f.get(), &geom);
  vl_dsift_set_steps(f.get(), g.step, g.step);
  vl_dsift_set_flat_window(f.get(), 1);
  vl_dsift_set_bounds(f.get(), g.min_x, g.min_y, g.min_x + g.step * (g.nx - 1) + 3 * g.bin,
                      g.min_y + g.step * (g.ny - 1) + 3 * g.bin);
  vl_dsift_process(f.get(), image);
  if (vl_dsift_get_keypoint_num(f.get()) != g.nx * g.ny)
    throw std::logic_error("vl_dsift returned " +
                           std::to_string(vl_dsift_get_keypoint_num(f.get())) + " frames");
  const float* d = vl_dsift_get_descriptors(f.get());
  const VlDsiftKeypoint* kp = vl_dsift_get_keypoints(f.get());
  for (int p = 0; p < g.nx * g.ny; ++p) {
    std::memcpy(descriptors + static_cast<size_t>(p) * stride,
                d + static_cast<size_t>(p) * kSiftLength, sizeof(float) * kSiftLength);
    norms[p] = static_cast<float>(kp[p].norm);
  }
}

}  // namespace slamaware::recognizer
