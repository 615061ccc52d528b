#pragma once
// Textures for the rasteriser: 8-bit BGR texels with a mip-map chain, sampled bilinearly within a
// level and between two levels only in the middle half of the way from one to the next
// ("brilinear", which halves the fetches of trilinear filtering), with the level chosen from the
// screen-space derivatives of the texture coordinates. u runs along the columns, v down the
// rows; (0, 0) is the top-left corner of the top-left texel, (1, 1) the bottom-right corner of
// the last one. The arithmetic is integer (8-bit fixed-point weights) after the coordinates, so
// a vectorised sampler can reproduce it bit for bit.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <vector>

namespace slamaware::synth {

/// log2(x) for x > 0, to about 0.01 (enough to pick a mip level); deterministic.
inline float fastLog2(float x) {
  uint32_t i;
  std::memcpy(&i, &x, 4);
  const float e = static_cast<float>(static_cast<int>(i >> 23) - 127);
  i = (i & 0x7FFFFFu) | 0x3F800000u;
  float m;
  std::memcpy(&m, &i, 4);
  return e + (-0.34484843f * m + 2.02466578f) * m - 0.67487759f;
}

/// The mip levels and the blend weight (0-256 towards `second`) for a squared footprint rho2
/// (texels per pixel, squared) in a texture of `levels` levels.
inline void chooseLevels(float rho2, int levels, int* first, int* second, uint32_t* weight) {
  if (!(rho2 > 1.f) || levels == 1) {
    *first = *second = 0;
    *weight = 0;
    return;
  }
  const float lod = 0.5f * fastLog2(rho2);
  const float max_lod = static_cast<float>(levels - 1);
  if (lod >= max_lod) {
    *first = *second = levels - 1;
    *weight = 0;
    return;
  }
  const int l0 = static_cast<int>(lod);
  const float t = (lod - static_cast<float>(l0) - 0.25f) * 2.f;
  *first = l0;
  *second = l0 + 1;
  *weight = t <= 0.f ? 0u : (t >= 1.f ? 256u : static_cast<uint32_t>(t * 256.f));
}

/// (a * (256 - w) + b * w) / 256 for each byte, two bytes at a time in 16-bit lanes.
inline uint32_t lerpTexel(uint32_t a, uint32_t b, uint32_t w) {
  constexpr uint32_t M = 0x00FF00FFu;
  const uint32_t iw = 256u - w;
  const uint32_t rb = (((a & M) * iw + (b & M) * w) >> 8) & M;
  const uint32_t ga = ((((a >> 8) & M) * iw + ((b >> 8) & M) * w)) & ~M;
  return rb | ga;
}

/// Where a texel index lands: wrapped or clamped into [0, n).
inline int fixTexelIndex(int i, int n, bool wrap) {
  if (i < 0) i = wrap ? n - 1 : 0;
  if (i >= n) i = wrap ? 0 : n - 1;
  if (i < 0) i = 0;  // n == 1
  return i;
}

class Texture {
 public:
  /// From an 8-bit BGR image (CV_8UC3). wrap_u / wrap_v: repeat (else clamp to the edge).
  Texture(const cv::Mat& bgr, bool wrap_u, bool wrap_v);

  int width() const { return w_[0]; }
  int height() const { return h_[0]; }
  int levels() const { return static_cast<int>(w_.size()); }
  bool wrapU() const { return wrap_u_; }
  bool wrapV() const { return wrap_v_; }
  size_t bytes() const { return px_.size() * 4; }
  /// The base level as an 8-bit BGR image.
  cv::Mat image() const;
  // The storage, for vectorised samplers: every level's texels (B, G, R, 0 bytes) one after the
  // other; level l starts at offsets()[l] and is widths()[l] x heights()[l].
  const uint32_t* texels() const { return px_.data(); }
  const int32_t* widths() const { return w_.data(); }
  const int32_t* heights() const { return h_.data(); }
  const int32_t* offsets() const { return off_.data(); }

  /// Filtered sample with the level from the uv derivatives per pixel (dudx, dvdx, dudy, dvdy);
  /// returns packed B, G, R bytes.
  uint32_t sample(float u, float v, float dudx, float dvdx, float dudy, float dvdy) const {
    const float ax = dudx * static_cast<float>(w_[0]), ay = dvdx * static_cast<float>(h_[0]);
    const float bx = dudy * static_cast<float>(w_[0]), by = dvdy * static_cast<float>(h_[0]);
    const float rho2 = std::max(ax * ax + ay * ay, bx * bx + by * by);
    int l0, l1;
    uint32_t weight;
    chooseLevels(rho2, levels(), &l0, &l1, &weight);
    if (weight == 0) return fetch(l0, u, v);
    if (weight == 256) return fetch(l1, u, v);
    return lerpTexel(fetch(l0, u, v), fetch(l1, u, v), weight);
  }

  /// Bilinear sample of one level, as packed B, G, R bytes.
  uint32_t fetch(int level, float u, float v) const {
    const int w = w_[static_cast<size_t>(level)], h = h_[static_cast<size_t>(level)];
    if (wrap_u_) u -= std::floor(u);
    if (wrap_v_) v -= std::floor(v);
    // Fixed point with 8 fractional bits; the offset keeps the conversion a floor.
    constexpr float kOffset = 4096.f;
    const int xi = static_cast<int>((u * static_cast<float>(w) - 0.5f + kOffset) * 256.f) -
                   static_cast<int>(kOffset * 256.f);
    const int yi = static_cast<int>((v * static_cast<float>(h) - 0.5f + kOffset) * 256.f) -
                   static_cast<int>(kOffset * 256.f);
    const uint32_t fx = static_cast<uint32_t>(xi & 255), fy = static_cast<uint32_t>(yi & 255);
    const int x0 = fixTexelIndex(xi >> 8, w, wrap_u_),
              x1 = fixTexelIndex((xi >> 8) + 1, w, wrap_u_);
    const int y0 = fixTexelIndex(yi >> 8, h, wrap_v_),
              y1 = fixTexelIndex((yi >> 8) + 1, h, wrap_v_);
    const uint32_t* base = &px_[static_cast<size_t>(off_[static_cast<size_t>(level)])];
    const uint32_t* r0 = base + static_cast<size_t>(y0) * static_cast<size_t>(w);
    const uint32_t* r1 = base + static_cast<size_t>(y1) * static_cast<size_t>(w);
    return lerpTexel(lerpTexel(r0[x0], r0[x1], fx), lerpTexel(r1[x0], r1[x1], fx), fy);
  }

  /// Bilinear sample of one level (B, G, R in [0, 1]).
  void sampleLevel(int level, float u, float v, float bgr[3]) const {
    const uint32_t t = fetch(level, u, v);
    for (int c = 0; c < 3; ++c) bgr[c] = static_cast<float>((t >> (8 * c)) & 0xFFu) / 255.f;
  }

 private:
  std::vector<uint32_t> px_;
  std::vector<int32_t> w_, h_, off_;
  bool wrap_u_, wrap_v_;
};

using TexturePtr = std::shared_ptr<const Texture>;

/// A single-channel map (shadow and ambient occlusion of a horizontal receiver), sampled
/// bilinearly with clamping; values in [0, 1].
class ScalarMap {
 public:
  ScalarMap() = default;
  ScalarMap(int w, int h) : w_(w), h_(h), v_(static_cast<size_t>(w) * h, 1.f) {}
  int width() const { return w_; }
  int height() const { return h_; }
  const float* data() const { return v_.data(); }
  float& at(int x, int y) { return v_[static_cast<size_t>(y) * w_ + x]; }
  float at(int x, int y) const { return v_[static_cast<size_t>(y) * w_ + x]; }
  /// Bilinear samples of two maps of the same size at (u, v) (one index computation).
  static void sample2(const ScalarMap& a, const ScalarMap& b, float u, float v, float* va,
                      float* vb) {
    float x = u * static_cast<float>(a.w_) - 0.5f, y = v * static_cast<float>(a.h_) - 0.5f;
    x = std::min(std::max(x, 0.f), static_cast<float>(a.w_ - 1));
    y = std::min(std::max(y, 0.f), static_cast<float>(a.h_ - 1));
    const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
    const int x1 = std::min(x0 + 1, a.w_ - 1), y1 = std::min(y0 + 1, a.h_ - 1);
    const float fx = x - static_cast<float>(x0), fy = y - static_cast<float>(y0);
    const size_t i00 = static_cast<size_t>(y0) * a.w_ + x0,
                 i10 = static_cast<size_t>(y0) * a.w_ + x1;
    const size_t i01 = static_cast<size_t>(y1) * a.w_ + x0,
                 i11 = static_cast<size_t>(y1) * a.w_ + x1;
    const float w00 = (1.f - fx) * (1.f - fy), w10 = fx * (1.f - fy), w01 = (1.f - fx) * fy,
                w11 = fx * fy;
    *va = w00 * a.v_[i00] + w10 * a.v_[i10] + w01 * a.v_[i01] + w11 * a.v_[i11];
    *vb = w00 * b.v_[i00] + w10 * b.v_[i10] + w01 * b.v_[i01] + w11 * b.v_[i11];
  }
  /// Bilinear at (u, v) in [0, 1]^2, texel-centred like Texture.
  float sample(float u, float v) const {
    float a, b;
    sample2(*this, *this, u, v, &a, &b);
    return a;
  }

 private:
  int w_ = 0, h_ = 0;
  std::vector<float> v_;
};

}  // namespace slamaware::synth
