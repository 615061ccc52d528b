#include "procs/recognizer/word_scores.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define SLAMAWARE_HAVE_AVX512_KERNEL 1
#endif

namespace slamaware::recognizer {

namespace {

constexpr int kBlock = 64;  // scores held at once per row

// acc + x * w, fused where the build has FMA (as every vector kernel does).
inline float multiplyAdd(float x, float w, float acc) {
#ifdef __FMA__
  return std::fma(x, w, acc);
#else
  return acc + x * w;
#endif
}

void assignPortable(const float* const* rows, int64_t n, int first, const float* w,
                    const float* bias, int padded, int16_t* words) {
  alignas(64) float acc[kBlock];
  for (int64_t i = 0; i < n; ++i) {
    const float* x = rows[i];
    float best = -std::numeric_limits<float>::infinity();
    int best_k = 0;
    for (int kb = 0; kb < padded; kb += kBlock) {
      const int width = std::min(kBlock, padded - kb);
      std::fill(acc, acc + width, 0.0F);
      for (int d = first; d < kFeatureDims; ++d) {
        const float xd = x[d];
        const float* wd = w + int64_t{d} * padded + kb;
        for (int k = 0; k < width; ++k) acc[k] = multiplyAdd(xd, wd[k], acc[k]);
      }
      for (int k = 0; k < width; ++k) {
        const float s = acc[k] - bias[kb + k];
        if (s > best) {
          best = s;
          best_k = kb + k;
        }
      }
    }
    words[i] = static_cast<int16_t>(best_k);
  }
}

#ifdef SLAMAWARE_HAVE_AVX512_KERNEL
// GCC 12's AVX-512 intrinsics pass an undefined vector to the masked builtins they wrap, which
// -Wuninitialized reports at every use.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#ifndef __clang__
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
// R rows at a time, Q registers of 16 scores per row (a block of 16 Q codewords).
template <int R, int Q>
__attribute__((target("avx512f"))) void blockAvx512(const float* const* x, int first,
                                                    const float* w, const float* bias, int padded,
                                                    int kb, float* best, int* best_k) {
  __m512 acc[R][Q];
  for (int r = 0; r < R; ++r)
    for (int q = 0; q < Q; ++q) acc[r][q] = _mm512_setzero_ps();
  for (int d = first; d < kFeatureDims; ++d) {
    const float* wd = w + int64_t{d} * padded + kb;
    __m512 wv[Q];
    for (int q = 0; q < Q; ++q) wv[q] = _mm512_loadu_ps(wd + 16 * q);
    for (int r = 0; r < R; ++r) {
      const __m512 xd = _mm512_set1_ps(x[r][d]);
      for (int q = 0; q < Q; ++q) acc[r][q] = _mm512_fmadd_ps(xd, wv[q], acc[r][q]);
    }
  }
  for (int r = 0; r < R; ++r) {
    __m512 m = _mm512_set1_ps(-std::numeric_limits<float>::infinity());
    for (int q = 0; q < Q; ++q) {
      acc[r][q] = _mm512_sub_ps(acc[r][q], _mm512_loadu_ps(bias + kb + 16 * q));
      m = _mm512_max_ps(m, acc[r][q]);
    }
    alignas(64) float lanes[16];
    _mm512_store_ps(lanes, m);
    const float block_best = *std::max_element(lanes, lanes + 16);
    if (!(block_best > best[r])) continue;  // ties keep the lower codeword of an earlier block
    const __m512 bv = _mm512_set1_ps(block_best);
    for (int q = 0; q < Q; ++q) {
      const __mmask16 hit = _mm512_cmp_ps_mask(acc[r][q], bv, _CMP_EQ_OQ);
      if (hit) {
        best[r] = block_best;
        best_k[r] = kb + 16 * q + __builtin_ctz(hit);
        break;
      }
    }
  }
}

template <int R>
__attribute__((target("avx512f"))) void rowsAvx512(const float* const* x, int first, const float* w,
                                                   const float* bias, int padded, int16_t* words) {
  float best[R];
  int best_k[R];
  for (int r = 0; r < R; ++r) {
    best[r] = -std::numeric_limits<float>::infinity();
    best_k[r] = 0;
  }
  for (int kb = 0; kb < padded; kb += kBlock) {
    switch (std::min(kBlock, padded - kb) / 16) {
      case 1:
        blockAvx512<R, 1>(x, first, w, bias, padded, kb, best, best_k);
        break;
      case 2:
        blockAvx512<R, 2>(x, first, w, bias, padded, kb, best, best_k);
        break;
      case 3:
        blockAvx512<R, 3>(x, first, w, bias, padded, kb, best, best_k);
        break;
      default:
        blockAvx512<R, 4>(x, first, w, bias, padded, kb, best, best_k);
        break;
    }
  }
  for (int r = 0; r < R; ++r) words[r] = static_cast<int16_t>(best_k[r]);
}

__attribute__((target("avx512f"))) void assignAvx512(const float* const* rows, int64_t n, int first,
                                                     const float* w, const float* bias, int padded,
                                                     int16_t* words) {
  int64_t i = 0;
  for (; i + 4 <= n; i += 4) rowsAvx512<4>(rows + i, first, w, bias, padded, words + i);
  for (; i < n; ++i) rowsAvx512<1>(rows + i, first, w, bias, padded, words + i);
}
#pragma GCC diagnostic pop
#endif

}  // namespace

WordScores::WordScores(const Eigen::MatrixXf& scores, const Eigen::RowVectorXf& bias) {
  if (scores.rows() != kFeatureDims || scores.cols() != bias.size() || scores.cols() < 1 ||
      scores.cols() > 32767)
    throw std::invalid_argument("WordScores: expected " + std::to_string(kFeatureDims) +
                                " x K scores and K biases");
  const int k = static_cast<int>(scores.cols());
  padded_ = (k + 15) / 16 * 16;
  w_.assign(static_cast<size_t>(kFeatureDims) * padded_, 0.0F);
  bias_.assign(static_cast<size_t>(padded_), std::numeric_limits<float>::infinity());
  for (int d = 0; d < kFeatureDims; ++d)
    for (int c = 0; c < k; ++c) w_[static_cast<size_t>(d) * padded_ + c] = scores(d, c);
  for (int c = 0; c < k; ++c) bias_[static_cast<size_t>(c)] = bias[c];
}

bool WordScores::available(Kernel kernel) {
  switch (kernel) {
    case Kernel::kAuto:
    case Kernel::kPortable:
      return true;
    case Kernel::kAvx512:
#ifdef SLAMAWARE_HAVE_AVX512_KERNEL
      return __builtin_cpu_supports("avx512f");
#else
      return false;
#endif
  }
  return false;
}

WordScores::Kernel WordScores::best() {
  return available(Kernel::kAvx512) ? Kernel::kAvx512 : Kernel::kPortable;
}

void WordScores::assign(const float* const* rows, int64_t n, int16_t* words, int first,
                        Kernel kernel) const {
  if (kernel == Kernel::kAuto) kernel = best();
  if (!available(kernel)) throw std::invalid_argument("WordScores: kernel not available here");
  if (first < 0 || first >= kFeatureDims)
    throw std::invalid_argument("WordScores: first element out of range");
#ifdef SLAMAWARE_HAVE_AVX512_KERNEL
  if (kernel == Kernel::kAvx512) {
    assignAvx512(rows, n, first, w_.data(), bias_.data(), padded_, words);
    return;
  }
#endif
  assignPortable(rows, n, first, w_.data(), bias_.data(), padded_, words);
}

}  // namespace slamaware::recognizer
