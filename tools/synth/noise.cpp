#include "tools/synth/noise.h"

#include <cmath>

namespace slamaware::synth {

namespace {

inline int wrapIndex(int i, int period) {
  if (period <= 0) return i;
  const int m = i % period;
  return m < 0 ? m + period : m;
}

inline float fade(float t) { return t * t * t * (t * (t * 6.f - 15.f) + 10.f); }

// One of 16 unit gradients on the circle.
inline float grad(uint32_t h, float dx, float dy) {
  static const float kCos[16] = {
      1.f,  0.9238795f,  0.7071068f,  0.3826834f,  0.f, -0.3826834f, -0.7071068f, -0.9238795f,
      -1.f, -0.9238795f, -0.7071068f, -0.3826834f, 0.f, 0.3826834f,  0.7071068f,  0.9238795f};
  const uint32_t k = h & 15u;
  return kCos[k] * dx + kCos[(k + 4u) & 15u] * dy;
}

}  // namespace

uint32_t hash32(int x, int y, uint32_t seed) {
  uint32_t h = seed * 0x9E3779B1u;
  h ^= static_cast<uint32_t>(x) * 0x85EBCA6Bu;
  h = (h << 13) | (h >> 19);
  h ^= static_cast<uint32_t>(y) * 0xC2B2AE35u;
  h ^= h >> 16;
  h *= 0x7FEB352Du;
  h ^= h >> 15;
  h *= 0x846CA68Bu;
  h ^= h >> 16;
  return h;
}

float hash01(int x, int y, uint32_t seed) {
  return static_cast<float>(hash32(x, y, seed) >> 8) * (1.f / 16777216.f);
}

namespace {
// A cheap lattice hash: only a few bits pick a gradient.
inline uint32_t latticeHash(int x, int y, uint32_t s) {
  uint32_t h = static_cast<uint32_t>(x) * 0x8DA6B343u ^ static_cast<uint32_t>(y) * 0xD8163841u ^ s;
  h ^= h >> 15;
  h *= 0x2C1B3C6Du;
  return h ^ (h >> 13);
}
}  // namespace

float gradientNoise(float x, float y, uint32_t seed, int period_x) {
  const float fx = std::floor(x), fy = std::floor(y);
  const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
  const float dx = x - fx, dy = y - fy;
  const int x0 = period_x > 0 ? wrapIndex(ix, period_x) : ix,
            x1 = period_x > 0 ? wrapIndex(ix + 1, period_x) : ix + 1;
  const uint32_t s = seed * 0xCB1AB31Fu;
  const float n00 = grad(latticeHash(x0, iy, s), dx, dy);
  const float n10 = grad(latticeHash(x1, iy, s), dx - 1.f, dy);
  const float n01 = grad(latticeHash(x0, iy + 1, s), dx, dy - 1.f);
  const float n11 = grad(latticeHash(x1, iy + 1, s), dx - 1.f, dy - 1.f);
  const float u = fade(dx), v = fade(dy);
  const float a = n00 + u * (n10 - n00);
  const float b = n01 + u * (n11 - n01);
  return 1.4142135f * (a + v * (b - a));
}

float fbm(float x, float y, uint32_t seed, int octaves, float gain, int period_x) {
  float sum = 0.f, amp = 1.f, norm = 0.f, f = 1.f;
  int period = period_x;
  for (int o = 0; o < octaves; ++o) {
    sum += amp * gradientNoise(x * f, y * f, seed + 1013u * static_cast<uint32_t>(o), period);
    norm += amp;
    amp *= gain;
    f *= 2.f;
    if (period > 0) period *= 2;
  }
  return sum / norm;
}

float ridged(float x, float y, uint32_t seed, int octaves, int period_x) {
  float sum = 0.f, amp = 1.f, norm = 0.f, f = 1.f;
  int period = period_x;
  for (int o = 0; o < octaves; ++o) {
    const float n = 1.f - std::fabs(gradientNoise(x * f, y * f,
                                                  seed + 7919u * static_cast<uint32_t>(o), period));
    sum += amp * n * n;
    norm += amp;
    amp *= 0.5f;
    f *= 2.f;
    if (period > 0) period *= 2;
  }
  return sum / norm;
}

Cell worley(float x, float y, uint32_t seed, int period_x) {
  const int ix = static_cast<int>(std::floor(x)), iy = static_cast<int>(std::floor(y));
  Cell c;
  c.f1 = c.f2 = 1e9f;
  for (int j = -1; j <= 1; ++j) {
    for (int i = -1; i <= 1; ++i) {
      const int cx = ix + i, cy = iy + j;
      const uint32_t h = hash32(wrapIndex(cx, period_x), cy, seed);
      const float px = static_cast<float>(cx) + static_cast<float>(h & 0xFFFF) * (1.f / 65536.f);
      const float py = static_cast<float>(cy) + static_cast<float>(h >> 16) * (1.f / 65536.f);
      const float d = std::sqrt((px - x) * (px - x) + (py - y) * (py - y));
      if (d < c.f1) {
        c.f2 = c.f1;
        c.f1 = d;
        c.id = h;
      } else if (d < c.f2) {
        c.f2 = d;
      }
    }
  }
  return c;
}

}  // namespace slamaware::synth
