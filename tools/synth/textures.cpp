#include "tools/synth/textures.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "tools/synth/noise.h"

namespace slamaware::synth {

namespace {

constexpr int kMaxTextureSide = 4096;

float clamp01(float x) { return x < 0.f ? 0.f : (x > 1.f ? 1.f : x); }
float smoothstep(float e0, float e1, float x) {
  const float t = clamp01((x - e0) / (e1 - e0));
  return t * t * (3.f - 2.f * t);
}
cv::Vec3f mix(const cv::Vec3f& a, const cv::Vec3f& b, float t) { return a + (b - a) * t; }
cv::Vec3f scale(const cv::Vec3f& a, float s) { return a * s; }
cv::Scalar toScalar(const cv::Vec3f& c) {
  return cv::Scalar(255.f * c[0], 255.f * c[1], 255.f * c[2]);
}
// The colour a little lighter or darker, and (hue_share of that) a little shifted in hue.
cv::Vec3f jitter(Rng& rng, const cv::Vec3f& c, float amount, float hue_share = 0.4f) {
  cv::Vec3f out;
  const float common = rng.uniformf(-amount, amount);
  for (int k = 0; k < 3; ++k)
    out[k] = clamp01(c[k] * (1.f + common + rng.uniformf(-amount, amount) * hue_share));
  return out;
}
uint32_t seed32(Rng& rng) { return static_cast<uint32_t>(rng.next() >> 32); }

int sidePx(float metres, float texel) {
  return std::clamp(static_cast<int>(std::lround(metres / texel)), 4, kMaxTextureSide);
}

// Rounds a value in [0, 255] (already clamped) to a byte.
inline uint8_t toByte(float v) { return static_cast<uint8_t>(static_cast<int>(v + 0.5f)); }

// Fills a w x h image from fn(x, y) -> BGR in [0, 1], with x, y the texel centre in the units
// given by `unit` per texel.
template <class Fn>
cv::Mat generate(int w, int h, float unit, Fn fn) {
  cv::Mat img(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y) {
    uint8_t* row = img.ptr<uint8_t>(y);
    const float fy = (static_cast<float>(y) + 0.5f) * unit;
    for (int x = 0; x < w; ++x) {
      const cv::Vec3f c = fn((static_cast<float>(x) + 0.5f) * unit, fy);
      for (int k = 0; k < 3; ++k) row[3 * x + k] = toByte(255.f * clamp01(c[k]));
    }
  }
  return img;
}

// As generate(), fn(x, y, ix, iy) also gets the texel indices (for CoarseField lookups).
template <class Fn>
cv::Mat generateIdx(int w, int h, float unit, Fn fn) {
  cv::Mat img(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y) {
    uint8_t* row = img.ptr<uint8_t>(y);
    const float fy = (static_cast<float>(y) + 0.5f) * unit;
    for (int x = 0; x < w; ++x) {
      const cv::Vec3f c = fn((static_cast<float>(x) + 0.5f) * unit, fy, x, y);
      for (int k = 0; k < 3; ++k) row[3 * x + k] = toByte(255.f * clamp01(c[k]));
    }
  }
  return img;
}

// A smooth field evaluated every `step` texels and interpolated bilinearly in between: low
// frequencies cost a fraction of a per-texel evaluation.
class CoarseField {
 public:
  template <class Fn>
  CoarseField(int w, int h, int step, Fn fn)
      : step_(step), gw_(w / step + 2), gh_(h / step + 2), v_(static_cast<size_t>(gw_) * gh_) {
    for (int j = 0; j < gh_; ++j)
      for (int i = 0; i < gw_; ++i)
        v_[static_cast<size_t>(j) * gw_ + i] =
            fn(static_cast<float>(i * step), static_cast<float>(j * step));
  }
  float at(int x, int y) const {
    const int i = x / step_, j = y / step_;
    const float fx = static_cast<float>(x - i * step_) / static_cast<float>(step_);
    const float fy = static_cast<float>(y - j * step_) / static_cast<float>(step_);
    const float* r0 = &v_[static_cast<size_t>(j) * gw_ + i];
    const float* r1 = r0 + gw_;
    const float a = r0[0] + fx * (r0[1] - r0[0]), b = r1[0] + fx * (r1[1] - r1[0]);
    return a + fy * (b - a);
  }

 private:
  int step_, gw_, gh_;
  std::vector<float> v_;
};

// Multiplies every texel by (1 + noise): per-texel noise of amplitude `fine` plus gradient
// noise of amplitude `mid` with cells of `mid_cells` texels: the grain every real surface has.
void addGrain(cv::Mat& img, uint32_t seed, float fine, float mid, float mid_cells) {
  const CoarseField field(
      img.cols, img.rows, std::max(1, static_cast<int>(mid_cells / 3.f)), [&](float x, float y) {
        return mid > 0.f ? mid * gradientNoise(x / mid_cells, y / mid_cells, seed + 1) : 0.f;
      });
  for (int y = 0; y < img.rows; ++y) {
    uint8_t* row = img.ptr<uint8_t>(y);
    for (int x = 0; x < img.cols; ++x) {
      const float n = fine * (2.f * hash01(x, y, seed) - 1.f) + field.at(x, y);
      for (int k = 0; k < 3; ++k)
        row[3 * x + k] = toByte(std::min(255.f, std::max(0.f, row[3 * x + k] * (1.f + n))));
    }
  }
}

// Large-scale lighting and dirt variation (a wall is never evenly lit or evenly clean).
void addMottle(cv::Mat& img, uint32_t seed, float amount, float cells) {
  const CoarseField field(
      img.cols, img.rows, std::max(1, static_cast<int>(cells / 16.f)),
      [&](float x, float y) { return amount * fbm(x / cells, y / cells, seed, 4); });
  for (int y = 0; y < img.rows; ++y) {
    uint8_t* row = img.ptr<uint8_t>(y);
    for (int x = 0; x < img.cols; ++x) {
      const float n = field.at(x, y);
      for (int k = 0; k < 3; ++k)
        row[3 * x + k] = toByte(std::min(255.f, std::max(0.f, row[3 * x + k] * (1.f + n))));
    }
  }
}

// ---- Wood --------------------------------------------------------------------------------------

struct Wood {
  cv::Vec3f light, dark;
  float ring_freq = 120.f;  // rings per metre of radius
  float axis_y = 0.f, axis_z = 0.05f, slope = 0.01f;
  uint32_t seed = 1;
  float figure = 0.5f;  // contrast of the ring pattern
};

Wood randomWood(Rng& rng, const cv::Vec3f& light, const cv::Vec3f& dark) {
  Wood w;
  w.light = jitter(rng, light, 0.08f, 0.15f);
  w.dark = jitter(rng, dark, 0.08f, 0.15f);
  w.ring_freq = rng.uniformf(70.f, 220.f);
  w.axis_y = rng.uniformf(-0.3f, 0.3f);
  w.axis_z = rng.uniformf(0.01f, 0.12f);
  w.slope = rng.uniformf(-0.03f, 0.03f);
  w.seed = seed32(rng);
  w.figure = rng.uniformf(0.35f, 0.75f);
  return w;
}

// Wood at (x, y) metres, grain along x.
cv::Vec3f woodAt(const Wood& p, float x, float y) {
  const float warp = 0.015f * fbm(x * 1.2f, y * 5.f, p.seed, 2);
  const float dy = y - p.axis_y + warp + 0.003f * gradientNoise(x * 9.f, y * 40.f, p.seed + 5);
  float ring = (std::sqrt(dy * dy + p.axis_z * p.axis_z) + p.slope * x) * p.ring_freq;
  ring -= std::floor(ring);
  const float late = smoothstep(0.5f, 0.88f, ring) * (1.f - smoothstep(0.93f, 1.f, ring));
  const float streak = 0.5f + 0.5f * fbm(x * 5.f, y * 450.f, p.seed + 11, 2);
  const float broad = 0.5f + 0.5f * gradientNoise(x * 0.9f, y * 3.f, p.seed + 17);
  float t = p.figure * late + 0.25f * streak + 0.3f * broad - 0.1f;
  // Pores: short dark dashes along the grain.
  if (hash01(static_cast<int>(std::floor(x / 0.004f)), static_cast<int>(std::floor(y / 0.0008f)),
             p.seed + 23) > 0.985f)
    t += 0.25f;
  return mix(p.light, p.dark, clamp01(t));
}

// B, G, R of early (light) and late (dark) wood.
const cv::Vec3f kWoodTones[][2] = {
    {{0.42f, 0.64f, 0.82f}, {0.20f, 0.38f, 0.58f}},  // oak
    {{0.52f, 0.74f, 0.90f}, {0.28f, 0.50f, 0.72f}},  // pine / birch
    {{0.22f, 0.34f, 0.50f}, {0.09f, 0.16f, 0.28f}},  // walnut
    {{0.24f, 0.38f, 0.64f}, {0.10f, 0.18f, 0.38f}},  // cherry
    {{0.34f, 0.52f, 0.70f}, {0.15f, 0.28f, 0.44f}},  // teak
    {{0.62f, 0.70f, 0.76f}, {0.40f, 0.48f, 0.56f}},  // white-washed
};

void pickWoodTone(Rng& rng, cv::Vec3f* light, cv::Vec3f* dark) {
  const int k = rng.range(0, 5);
  *light = kWoodTones[k][0];
  *dark = kWoodTones[k][1];
}

// Planks of width `pw`, each row of planks with its own length and offset; every plank its own
// wood.
cv::Mat planks(Rng& rng, float width_m, float height_m, float texel, float pw, float len_lo,
               float len_hi, const cv::Vec3f& light, const cv::Vec3f& dark, float gap_m) {
  const int w = sidePx(width_m, texel), h = sidePx(height_m, texel);
  const float unit = width_m / static_cast<float>(w);
  const uint32_t seed = seed32(rng);
  const int rows = static_cast<int>(std::ceil(height_m / pw)) + 1;
  std::vector<float> row_len(rows), row_off(rows);
  for (int r = 0; r < rows; ++r) {
    row_len[r] = rng.uniformf(len_lo, len_hi);
    row_off[r] = rng.uniformf(0.f, row_len[r]);
  }
  // Plank woods are made on demand from a hash of (row, index), cached while a row is scanned.
  int cached_r = -1, cached_k = 0;
  Wood wood;
  return generate(w, h, unit, [&](float x, float y) {
    const int r = std::min(rows - 1, static_cast<int>(y / pw));
    const float xs = x + row_off[r];
    const int k = static_cast<int>(std::floor(xs / row_len[r]));
    if (r != cached_r || k != cached_k) {
      Rng prng(hashCombine(
          seed, static_cast<uint64_t>(r) * 1000003ull + static_cast<uint64_t>(k + 100000)));
      wood = randomWood(prng, light, dark);
      cached_r = r;
      cached_k = k;
    }
    const float lx = xs - static_cast<float>(k) * row_len[r], ly = y - static_cast<float>(r) * pw;
    cv::Vec3f c = woodAt(wood, lx + 3.f * static_cast<float>(k), ly - pw / 2);
    // Gaps and a slight bevel.
    const float ex = std::min(lx, row_len[r] - lx), ey = std::min(ly, pw - ly);
    const float e = std::min(ex, ey);
    if (e < gap_m)
      c = scale(c, 0.35f);
    else if (e < gap_m + 0.003f)
      c = scale(c, 0.8f + 0.2f * (e - gap_m) / 0.003f);
    return c;
  });
}

cv::Vec3f marbleAt(float x, float y, uint32_t seed, const cv::Vec3f& base, const cv::Vec3f& vein,
                   float scale_m) {
  const float warp = fbm(x / scale_m, y / scale_m, seed, 5);
  const float v = std::fabs(std::sin((x + y * 0.6f) / scale_m * 3.f + warp * 6.f));
  const float veins = std::pow(1.f - v, 6.f);
  const float cloud = 0.5f + 0.5f * fbm(x / (0.3f * scale_m), y / (0.3f * scale_m), seed + 3, 4);
  cv::Vec3f c = mix(base, scale(base, 0.88f), cloud);
  return mix(c, vein, clamp01(veins * 1.2f));
}

}  // namespace

cv::Vec3f hsvColor(float hue_deg, float sat, float val) {
  float h = std::fmod(hue_deg, 360.f);
  if (h < 0) h += 360.f;
  const float c = val * sat, x = c * (1.f - std::fabs(std::fmod(h / 60.f, 2.f) - 1.f)), m = val - c;
  float r = 0, g = 0, b = 0;
  if (h < 60)
    r = c, g = x;
  else if (h < 120)
    r = x, g = c;
  else if (h < 180)
    g = c, b = x;
  else if (h < 240)
    g = x, b = c;
  else if (h < 300)
    r = x, b = c;
  else
    r = c, b = x;
  return {b + m, g + m, r + m};
}

std::string pseudoWord(Rng& rng, int syllables, bool upper) {
  static const char* kOnsets[] = {"b",  "c",  "d",  "f",  "g",  "k",  "l",  "m",  "n",
                                  "p",  "r",  "s",  "t",  "v",  "z",  "br", "cr", "fl",
                                  "gr", "pl", "st", "tr", "sh", "ch", "qu"};
  static const char* kVowels[] = {"a", "e", "i", "o", "u", "ea", "oo", "io", "ai", "y"};
  static const char* kCodas[] = {"", "", "", "n", "s", "x", "r", "l", "m", "t", "ck"};
  std::string s;
  for (int i = 0; i < syllables; ++i) {
    s += kOnsets[rng.range(0, 24)];
    s += kVowels[rng.range(0, 9)];
    if (i + 1 == syllables || rng.chance(0.3)) s += kCodas[rng.range(0, 10)];
  }
  for (auto& ch : s) ch = upper ? static_cast<char>(::toupper(ch)) : ch;
  if (!upper && !s.empty()) s[0] = static_cast<char>(::toupper(s[0]));
  return s;
}

// ---- Room surfaces ------------------------------------------------------------------------------

cv::Mat floorTexture(Rng& rng, const std::string& style, float width_m, float height_m,
                     float texel) {
  const int w = sidePx(width_m, texel), h = sidePx(height_m, texel);
  const float unit = width_m / static_cast<float>(w);
  const uint32_t seed = seed32(rng);
  cv::Mat img;
  if (style == "wood") {
    cv::Vec3f light, dark;
    pickWoodTone(rng, &light, &dark);
    img = planks(rng, width_m, height_m, texel, rng.uniformf(0.09f, 0.2f), 0.7f, 1.8f, light, dark,
                 0.0012f);
  } else if (style == "parquet") {
    cv::Vec3f light, dark;
    pickWoodTone(rng, &light, &dark);
    const float block = rng.uniformf(0.25f, 0.4f);
    const int strips = rng.range(3, 5);
    img = generate(w, h, unit, [&](float x, float y) {
      const int bx = static_cast<int>(std::floor(x / block)),
                by = static_cast<int>(std::floor(y / block));
      const bool horizontal = ((bx + by) & 1) == 0;
      const float lx = x - static_cast<float>(bx) * block, ly = y - static_cast<float>(by) * block;
      const float across = horizontal ? ly : lx, along = horizontal ? lx : ly;
      const int s =
          std::min(strips - 1, static_cast<int>(across / (block / static_cast<float>(strips))));
      Rng prng(hashCombine(seed, (static_cast<uint64_t>(bx + 5000) << 24) ^
                                     (static_cast<uint64_t>(by + 5000) << 4) ^
                                     static_cast<uint64_t>(s)));
      const Wood wood = randomWood(prng, light, dark);
      const float sw = block / static_cast<float>(strips);
      const float la = across - static_cast<float>(s) * sw;
      cv::Vec3f c = woodAt(wood, along, la - sw / 2);
      const float e = std::min({la, sw - la, along, block - along});
      if (e < 0.001f) c = scale(c, 0.45f);
      return c;
    });
  } else if (style == "tiles") {
    const float size = rng.uniformf(0.25f, 0.6f), grout = rng.uniformf(0.003f, 0.007f);
    const float hue = rng.uniformf(0.f, 360.f);
    const int kind = rng.range(0, 2);  // 0 marble, 1 speckled stone, 2 terracotta
    cv::Vec3f base = kind == 2
                         ? cv::Vec3f(0.32f, 0.45f, 0.68f)
                         : hsvColor(hue, rng.uniformf(0.02f, 0.18f), rng.uniformf(0.6f, 0.9f));
    const cv::Vec3f grout_c = jitter(rng, cv::Vec3f(0.55f, 0.57f, 0.58f), 0.2f);
    img = generate(w, h, unit, [&](float x, float y) {
      // Irregular grid: each line wanders by a couple of millimetres.
      const int ix = static_cast<int>(std::floor(x / size)),
                iy = static_cast<int>(std::floor(y / size));
      const float x0 = static_cast<float>(ix) * size + 0.002f * (2.f * hash01(ix, 0, seed) - 1.f);
      const float x1 =
          static_cast<float>(ix + 1) * size + 0.002f * (2.f * hash01(ix + 1, 0, seed) - 1.f);
      const float y0 =
          static_cast<float>(iy) * size + 0.002f * (2.f * hash01(0, iy, seed + 1) - 1.f);
      const float y1 =
          static_cast<float>(iy + 1) * size + 0.002f * (2.f * hash01(0, iy + 1, seed + 1) - 1.f);
      const int tx = x < x0 ? ix - 1 : (x > x1 ? ix + 1 : ix),
                ty = y < y0 ? iy - 1 : (y > y1 ? iy + 1 : iy);
      const float e =
          std::min({std::fabs(x - x0), std::fabs(x1 - x), std::fabs(y - y0), std::fabs(y1 - y)});
      if (e < grout / 2)
        return mix(grout_c, scale(grout_c, 0.7f),
                   0.5f + 0.5f * gradientNoise(x * 300, y * 300, seed + 2));
      const uint32_t tid = hash32(tx, ty, seed + 3);
      const float tb = 0.9f + 0.2f * static_cast<float>(tid & 255) / 255.f;
      cv::Vec3f c;
      if (kind == 0) {
        c = marbleAt(x + static_cast<float>(tid & 1023), y, seed + tid % 97, base,
                     scale(base, 0.55f), 0.25f);
      } else if (kind == 1) {
        const float n = fbm(x * 40.f, y * 40.f, seed + 5 + tid % 31, 4);
        const Cell cell = worley(x * 300.f, y * 300.f, seed + 7);
        c = scale(base, 0.9f + 0.15f * n);
        if ((cell.id & 7) == 0 && cell.f1 < 0.35f) c = scale(c, 0.6f);
        if ((cell.id & 15) == 1 && cell.f1 < 0.3f) c = mix(c, cv::Vec3f(0.9f, 0.9f, 0.9f), 0.6f);
      } else {
        const float n = fbm(x * 12.f, y * 12.f, seed + 9 + tid % 13, 5);
        c = scale(base, 0.85f + 0.25f * n);
      }
      // A soft darkening towards the edges (the glaze pools), and now and then a chip.
      c = scale(c, tb * (0.92f + 0.08f * smoothstep(0.f, 0.012f, e - grout / 2)));
      if ((tid >> 8) % 23 == 0 && e < 0.02f &&
          hash01(static_cast<int>(x * 200), static_cast<int>(y * 200), tid) > 0.6f)
        c = scale(c, 0.7f);
      return c;
    });
  } else if (style == "carpet") {
    const cv::Vec3f base =
        hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.1f, 0.5f), rng.uniformf(0.35f, 0.7f));
    const cv::Vec3f alt =
        hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.2f, 0.6f), rng.uniformf(0.3f, 0.7f));
    const float motif = rng.uniformf(0.15f, 0.35f);
    const bool pattern = rng.chance(0.6);
    const CoarseField big(w, h, 16, [&](float ix, float iy) {
      return fbm(ix * unit * 2.f, iy * unit * 2.f, seed, 4);
    });
    const CoarseField warp_x(w, h, 8, [&](float ix, float iy) {
      return fbm(ix * unit * 3.f, iy * unit * 3.f, seed + 2, 2);
    });
    const CoarseField warp_y(w, h, 8, [&](float ix, float iy) {
      return fbm(iy * unit * 3.f, ix * unit * 3.f, seed + 3, 2);
    });
    img = generateIdx(w, h, unit, [&](float x, float y, int ix, int iy) {
      float t = 0.5f + 0.5f * big.at(ix, iy);
      cv::Vec3f c = scale(base, 0.85f + 0.3f * t);
      if (pattern) {
        // Irregular blots and rings on a grid that drifts (a printed rug, never exactly repeating).
        const float wx = x + 0.04f * warp_x.at(ix, iy), wy = y + 0.04f * warp_y.at(ix, iy);
        const Cell cell = worley(wx / motif, wy / motif, seed + 4);
        const float ring = std::fabs(cell.f1 - 0.3f - 0.1f * static_cast<float>(cell.id & 3));
        if (ring < 0.06f) c = mix(c, alt, 0.8f);
        if (cell.f2 - cell.f1 < 0.05f) c = mix(c, scale(alt, 0.6f), 0.6f);
      }
      const float loops = 2.f * hash01(ix, iy, seed + 5) - 1.f;
      return scale(c, 0.92f + 0.1f * loops);
    });
    addGrain(img, seed + 6, 0.12f, 0.f, 1.f);
    return img;
  } else if (style == "concrete") {
    const float v = rng.uniformf(0.45f, 0.7f);
    const cv::Vec3f base = hsvColor(rng.uniformf(20.f, 50.f), rng.uniformf(0.02f, 0.1f), v);
    const CoarseField big(w, h, 16, [&](float ix, float iy) {
      return fbm(ix * unit * 0.8f, iy * unit * 0.8f, seed, 4);
    });
    const CoarseField mid(w, h, 3, [&](float ix, float iy) {
      return fbm(ix * unit * 9.f, iy * unit * 9.f, seed + 1, 4);
    });
    const CoarseField cracks(w, h, 2, [&](float ix, float iy) {
      return ridged(ix * unit * 1.5f, iy * unit * 1.5f, seed + 3, 5);
    });
    img = generateIdx(w, h, unit, [&](float x, float y, int ix, int iy) {
      cv::Vec3f c = scale(base, 0.9f + 0.12f * big.at(ix, iy) + 0.1f * mid.at(ix, iy));
      const Cell cell = worley(x * 150.f, y * 150.f, seed + 2);
      if ((cell.id & 3) == 0 && cell.f1 < 0.3f) c = scale(c, 0.75f);
      if ((cell.id & 7) == 1 && cell.f1 < 0.25f) c = scale(c, 1.2f);
      const float crack = cracks.at(ix, iy);
      if (crack > 0.93f) c = scale(c, 0.6f);
      return c;
    });
  } else if (style == "linoleum") {
    const cv::Vec3f base =
        hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.05f, 0.3f), rng.uniformf(0.5f, 0.8f));
    std::vector<cv::Vec3f> chips;
    for (int i = 0; i < 6; ++i)
      chips.push_back(
          hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.f, 0.5f), rng.uniformf(0.2f, 0.95f)));
    const float chip = rng.uniformf(0.006f, 0.015f);
    img = generate(w, h, unit, [&](float x, float y) {
      const Cell cell = worley(x / chip, y / chip, seed);
      cv::Vec3f c = scale(base, 0.95f + 0.1f * fbm(x * 3.f, y * 3.f, seed + 1, 3));
      if ((cell.id >> 4) % 3 == 0 && cell.f2 - cell.f1 > 0.12f) c = chips[cell.id % chips.size()];
      return c;
    });
  } else {
    throw std::invalid_argument("unknown floor style '" + style + "'");
  }
  addMottle(img, seed + 101, 0.08f, static_cast<float>(w) / 6.f);
  addGrain(img, seed + 102, 0.05f, 0.04f, 6.f);
  return img;
}

cv::Mat wallTexture(Rng& rng, const std::string& style, float width_m, float height_m,
                    float texel) {
  const int w = sidePx(width_m, texel), h = sidePx(height_m, texel);
  const float unit = width_m / static_cast<float>(w);
  const uint32_t seed = seed32(rng);
  const float ppm = static_cast<float>(w) / width_m;  // pixels per metre
  cv::Mat img;
  if (style == "plaster" || style == "wallpaper" || style == "stripes") {
    const cv::Vec3f base =
        hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.03f, 0.25f), rng.uniformf(0.7f, 0.92f));
    const CoarseField f(w, h, 2, [&](float ix, float iy) {
      return 0.05f * fbm(ix * unit * 4.f, iy * unit * 4.f, seed, 4) +
             0.03f * gradientNoise(ix * unit * 60.f, iy * unit * 60.f, seed + 1);
    });
    img = generateIdx(w, h, unit, [&](float, float, int ix, int iy) {
      return scale(base, 0.95f + f.at(ix, iy));
    });
    if (style == "wallpaper") {
      // Motifs on a loose grid: each one drawn with its own jitter, colour and shape.
      const float cell = rng.uniformf(0.07f, 0.16f);
      const cv::Vec3f ink =
          hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.2f, 0.6f), rng.uniformf(0.3f, 0.7f));
      const cv::Vec3f ink2 =
          hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.2f, 0.6f), rng.uniformf(0.4f, 0.8f));
      const int shape = rng.range(0, 3);
      Rng mrng = rng.fork(7);
      for (float cy = cell / 2; cy < height_m + cell; cy += cell) {
        const float row_shift = (static_cast<int>(cy / cell) & 1) ? cell / 2 : 0.f;
        for (float cx = row_shift; cx < width_m + cell; cx += cell) {
          const float jx = cx + mrng.uniformf(-0.12f, 0.12f) * cell,
                      jy = cy + mrng.uniformf(-0.12f, 0.12f) * cell;
          const cv::Point p(static_cast<int>(jx * ppm), static_cast<int>(jy * ppm));
          const float s = cell * ppm * mrng.uniformf(0.18f, 0.32f);
          const cv::Vec3f col =
              mrng.chance(0.7) ? jitter(mrng, ink, 0.15f) : jitter(mrng, ink2, 0.15f);
          const double ang = mrng.uniform(0, 180);
          switch (shape) {
            case 0:  // flower: petals around a dot
              for (int k = 0; k < 5; ++k) {
                const double a = ang + k * 72.0;
                const cv::Point q(p.x + static_cast<int>(s * 0.7 * std::cos(a * CV_PI / 180)),
                                  p.y + static_cast<int>(s * 0.7 * std::sin(a * CV_PI / 180)));
                cv::ellipse(img, q,
                            cv::Size(std::max(1, static_cast<int>(s * 0.5)),
                                     std::max(1, static_cast<int>(s * 0.25))),
                            a, 0, 360, toScalar(col), -1, cv::LINE_AA);
              }
              cv::circle(img, p, std::max(1, static_cast<int>(s * 0.25)), toScalar(ink2), -1,
                         cv::LINE_AA);
              break;
            case 1:  // diamond
            {
              std::vector<cv::Point> d{{p.x, p.y - static_cast<int>(s)},
                                       {p.x + static_cast<int>(s * 0.6), p.y},
                                       {p.x, p.y + static_cast<int>(s)},
                                       {p.x - static_cast<int>(s * 0.6), p.y}};
              cv::fillConvexPoly(img, d, toScalar(col), cv::LINE_AA);
            } break;
            case 2:  // leaf sprig
              cv::ellipse(img, p,
                          cv::Size(std::max(1, static_cast<int>(s)),
                                   std::max(1, static_cast<int>(s * 0.35))),
                          ang, 0, 360, toScalar(col), -1, cv::LINE_AA);
              cv::line(img, p,
                       cv::Point(p.x + static_cast<int>(s * 1.2 * std::cos(ang * CV_PI / 180)),
                                 p.y + static_cast<int>(s * 1.2 * std::sin(ang * CV_PI / 180))),
                       toScalar(scale(col, 0.6f)), std::max(1, static_cast<int>(s * 0.1)),
                       cv::LINE_AA);
              break;
            default:  // rings
              cv::circle(img, p, std::max(2, static_cast<int>(s)), toScalar(col),
                         std::max(1, static_cast<int>(s * 0.25)), cv::LINE_AA);
              break;
          }
        }
      }
    } else if (style == "stripes") {
      // Stripes of irregular widths and two or three colours (never one period).
      std::vector<cv::Vec3f> cols;
      for (int i = 0; i < 3; ++i)
        cols.push_back(hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.1f, 0.45f),
                                rng.uniformf(0.45f, 0.9f)));
      float x = 0;
      while (x < width_m) {
        const float sw = rng.uniformf(0.01f, 0.09f);
        if (rng.chance(0.55)) {
          const cv::Vec3f c = cols[static_cast<size_t>(rng.range(0, 2))];
          cv::rectangle(img, cv::Point(static_cast<int>(x * ppm), 0),
                        cv::Point(static_cast<int>((x + sw) * ppm), h), toScalar(c), -1);
        }
        x += sw + rng.uniformf(0.005f, 0.05f);
      }
    }
  } else if (style == "brick") {
    const bool painted = rng.chance(0.3);
    const cv::Vec3f brick = painted ? hsvColor(rng.uniformf(0.f, 360.f), 0.05f, 0.85f)
                                    : hsvColor(rng.uniformf(5.f, 25.f), rng.uniformf(0.45f, 0.7f),
                                               rng.uniformf(0.4f, 0.65f));
    const cv::Vec3f mortar = painted ? scale(brick, 0.9f) : cv::Vec3f(0.62f, 0.66f, 0.68f);
    const float bh = 0.065f, bl = 0.215f, m = 0.01f;
    img = generate(w, h, unit, [&](float x, float y) {
      const int row = static_cast<int>(std::floor(y / (bh + m)));
      const float xs = x + ((row & 1) ? (bl + m) / 2 : 0.f) + 0.01f * hash01(row, 0, seed);
      const int col = static_cast<int>(std::floor(xs / (bl + m)));
      const float lx = xs - static_cast<float>(col) * (bl + m),
                  ly = y - static_cast<float>(row) * (bh + m);
      if (lx > bl || ly > bh)
        return scale(mortar, 0.9f + 0.15f * gradientNoise(x * 400, y * 400, seed + 1));
      const uint32_t id = hash32(col, row, seed + 2);
      const float v = 0.8f + 0.35f * static_cast<float>(id & 255) / 255.f;
      cv::Vec3f c = scale(brick, v * (0.9f + 0.15f * fbm(x * 30.f, y * 30.f, seed + id % 101, 4)));
      const float e = std::min({lx, bl - lx, ly, bh - ly});
      if (e < 0.004f) c = scale(c, 0.85f + 0.15f * e / 0.004f);
      return c;
    });
  } else if (style == "panels") {
    cv::Vec3f light, dark;
    pickWoodTone(rng, &light, &dark);
    // Vertical boards: build horizontal planks and rotate.
    cv::Mat p = planks(rng, height_m, width_m, texel, rng.uniformf(0.08f, 0.18f), height_m * 0.9f,
                       height_m * 2.f, light, dark, 0.0015f);
    cv::rotate(p, img, cv::ROTATE_90_CLOCKWISE);
    cv::resize(img, img, cv::Size(w, h), 0, 0, cv::INTER_NEAREST);
  } else if (style == "tiles") {
    const float size = rng.uniformf(0.08f, 0.16f);
    const cv::Vec3f base =
        hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.05f, 0.5f), rng.uniformf(0.55f, 0.95f));
    const cv::Vec3f accent =
        hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.3f, 0.7f), rng.uniformf(0.4f, 0.8f));
    img = generate(w, h, unit, [&](float x, float y) {
      const int ix = static_cast<int>(std::floor(x / size)),
                iy = static_cast<int>(std::floor(y / size));
      const float lx = x - static_cast<float>(ix) * size, ly = y - static_cast<float>(iy) * size;
      const float e = std::min({lx, size - lx, ly, size - ly});
      if (e < 0.0015f) return cv::Vec3f(0.7f, 0.72f, 0.72f);
      const uint32_t id = hash32(ix, iy, seed);
      cv::Vec3f c = (id % 9 == 0) ? accent : base;
      c = scale(c, 0.9f + 0.12f * static_cast<float>((id >> 8) & 255) / 255.f +
                       0.05f * fbm(x * 20.f, y * 20.f, seed + id % 51, 3));
      return c;
    });
  } else {
    throw std::invalid_argument("unknown wall style '" + style + "'");
  }
  addMottle(img, seed + 201, 0.07f, static_cast<float>(w) / 5.f);
  addGrain(img, seed + 202, 0.035f, 0.03f, 5.f);
  return img;
}

cv::Mat woodTexture(Rng& rng, float width_m, float height_m, float texel, cv::Vec3f light,
                    cv::Vec3f dark) {
  const int w = sidePx(width_m, texel), h = sidePx(height_m, texel);
  const Wood wood = randomWood(rng, light, dark);
  cv::Mat img = generate(w, h, width_m / static_cast<float>(w),
                         [&](float x, float y) { return woodAt(wood, x, y - height_m / 2); });
  addGrain(img, seed32(rng), 0.04f, 0.f, 1.f);
  return img;
}

cv::Mat tableTexture(Rng& rng, const std::string& style, float width_m, float height_m,
                     float texel) {
  const int w = sidePx(width_m, texel), h = sidePx(height_m, texel);
  const float unit = width_m / static_cast<float>(w);
  const uint32_t seed = seed32(rng);
  cv::Mat img;
  if (style == "wood") {
    cv::Vec3f light, dark;
    pickWoodTone(rng, &light, &dark);
    img = planks(rng, width_m, height_m, texel, rng.uniformf(0.06f, 0.16f), width_m * 1.05f,
                 width_m * 1.6f, light, dark, rng.chance(0.5) ? 0.0008f : 0.f);
  } else if (style == "laminate") {
    const cv::Vec3f base =
        hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.0f, 0.25f), rng.uniformf(0.55f, 0.9f));
    img = generate(w, h, unit, [&](float x, float y) {
      cv::Vec3f c = scale(base, 0.93f + 0.07f * fbm(x * 6.f, y * 6.f, seed, 4));
      const Cell cell = worley(x * 400.f, y * 400.f, seed + 1);
      if ((cell.id & 3) == 0 && cell.f1 < 0.3f) c = scale(c, 0.8f);
      if ((cell.id & 7) == 1 && cell.f1 < 0.3f) c = scale(c, 1.12f);
      return c;
    });
    // Wear, rings from cups, scratches.
    Rng srng = rng.fork(3);
    const float ppm = static_cast<float>(w) / width_m;
    for (int i = 0; i < 12; ++i) {
      const cv::Point a(srng.range(0, w - 1), srng.range(0, h - 1));
      const cv::Point b(a.x + static_cast<int>(srng.uniformf(-0.15f, 0.15f) * ppm),
                        a.y + static_cast<int>(srng.uniformf(-0.05f, 0.05f) * ppm));
      cv::line(img, a, b, toScalar(scale(base, srng.uniformf(0.75f, 1.1f))), 1, cv::LINE_AA);
    }
    for (int i = 0; i < 4; ++i)
      cv::circle(img, cv::Point(srng.range(0, w - 1), srng.range(0, h - 1)),
                 static_cast<int>(srng.uniformf(0.03f, 0.045f) * ppm), toScalar(scale(base, 0.85f)),
                 std::max(1, static_cast<int>(0.003f * ppm)), cv::LINE_AA);
  } else if (style == "cloth" || style == "checker") {
    const cv::Vec3f a =
        hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.3f, 0.8f), rng.uniformf(0.45f, 0.85f));
    const cv::Vec3f b = style == "checker"
                            ? hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.0f, 0.3f),
                                       rng.uniformf(0.8f, 0.97f))
                            : cv::Vec3f(0.93f, 0.94f, 0.95f);
    const float check =
        style == "checker" ? rng.uniformf(0.04f, 0.09f) : rng.uniformf(0.015f, 0.04f);
    const int pattern = style == "checker" ? 0 : rng.range(0, 2);  // 0 gingham, 1 stripes, 2 floral
    const cv::Vec3f flower =
        hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.3f, 0.6f), rng.uniformf(0.5f, 0.85f));
    const cv::Vec3f leaf = hsvColor(rng.uniformf(90.f, 140.f), 0.4f, 0.5f);
    img = generate(w, h, unit, [&](float x, float y) {
      // Folds and creases bend the pattern a little.
      const float fx = x + 0.01f * fbm(x * 4.f, y * 4.f, seed + 1, 3),
                  fy = y + 0.01f * fbm(y * 4.f, x * 4.f, seed + 2, 3);
      cv::Vec3f c = b;
      if (pattern == 0) {
        const int i = static_cast<int>(std::floor(fx / check)),
                  j = static_cast<int>(std::floor(fy / check));
        const float t = (i & 1 ? 0.5f : 0.f) + (j & 1 ? 0.5f : 0.f);
        c = mix(b, a, t);
      } else if (pattern == 1) {
        const float s = std::sin(fx / check * 3.14159f);
        c = mix(b, a, smoothstep(0.2f, 0.5f, s) * 0.9f);
      } else {
        // Small flowers in two colours on a plain ground, a leaf now and then.
        const Cell cell = worley(fx / (check * 1.5f), fy / (check * 1.5f), seed + 3);
        if (cell.id % 3 == 0 && cell.f1 < 0.16f)
          c = mix(b, (cell.id >> 4) & 1 ? a : flower, 0.85f);
        else if (cell.id % 3 == 0 && cell.f1 < 0.22f)
          c = mix(b, scale(a, 0.6f), 0.5f);
        else if (cell.id % 7 == 1 && cell.f1 < 0.12f)
          c = mix(b, leaf, 0.7f);
      }
      // Weave.
      const float weave = std::sin(x / 0.0012f) * std::sin(y / 0.0012f);
      const float fold = fbm(x * 3.f, y * 3.f, seed + 4, 3);
      return scale(c, 0.93f + 0.05f * weave + 0.1f * fold);
    });
  } else if (style == "marble") {
    const cv::Vec3f base =
        hsvColor(rng.uniformf(0.f, 60.f), rng.uniformf(0.f, 0.1f), rng.uniformf(0.75f, 0.92f));
    // Grey or brownish veins.
    const cv::Vec3f vein = rng.chance(0.5) ? cv::Vec3f(0.35f, 0.36f, 0.38f)
                                           : hsvColor(rng.uniformf(15.f, 35.f), 0.25f, 0.45f);
    const float vein_scale = rng.uniformf(0.1f, 0.25f);
    img = generate(w, h, unit,
                   [&](float x, float y) { return marbleAt(x, y, seed, base, vein, vein_scale); });
  } else if (style == "stone") {
    const cv::Vec3f base =
        hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.f, 0.15f), rng.uniformf(0.25f, 0.6f));
    img = generate(w, h, unit, [&](float x, float y) {
      const Cell c1 = worley(x * 250.f, y * 250.f, seed), c2 = worley(x * 90.f, y * 90.f, seed + 1);
      cv::Vec3f c = scale(base, 0.9f + 0.1f * fbm(x * 5.f, y * 5.f, seed + 2, 3));
      if ((c1.id & 3) == 0)
        c = scale(c, 0.55f);
      else if ((c1.id & 3) == 1)
        c = scale(c, 1.35f);
      if ((c2.id & 7) == 0) c = mix(c, cv::Vec3f(0.85f, 0.85f, 0.88f), 0.5f);
      return c;
    });
  } else {
    throw std::invalid_argument("unknown table style '" + style + "'");
  }
  addMottle(img, seed + 301, 0.05f, static_cast<float>(w) / 4.f);
  addGrain(img, seed + 302, 0.04f, 0.03f, 4.f);
  return img;
}

cv::Mat ceilingTexture(Rng& rng, float width_m, float height_m, float texel) {
  const int w = sidePx(width_m, texel), h = sidePx(height_m, texel);
  const uint32_t seed = seed32(rng);
  const bool tiles = rng.chance(0.5);
  const cv::Vec3f base = hsvColor(rng.uniformf(0.f, 60.f), 0.04f, 0.88f);
  return generate(w, h, width_m / static_cast<float>(w), [&](float x, float y) {
    cv::Vec3f c =
        scale(base, 0.95f + 0.05f * fbm(x * 3.f, y * 3.f, seed, 3) +
                        0.04f * hash01(static_cast<int>(x * 300), static_cast<int>(y * 300), seed));
    if (tiles) {
      const float lx = std::fmod(x, 0.6f), ly = std::fmod(y, 0.6f);
      if (std::min({lx, 0.6f - lx, ly, 0.6f - ly}) < 0.01f) c = scale(c, 0.75f);
    }
    return c;
  });
}

// ---- Decorations
// ---------------------------------------------------------------------------------

cv::Mat posterTexture(Rng& rng, int w, int h) {
  const uint32_t seed = seed32(rng);
  const int kind = rng.range(0, 4);
  const cv::Vec3f c0 =
      hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.3f, 0.9f), rng.uniformf(0.3f, 0.95f));
  const cv::Vec3f c1 =
      hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.3f, 0.9f), rng.uniformf(0.3f, 0.95f));
  cv::Mat img;
  if (kind == 0) {  // landscape painting
    const float horizon = rng.uniformf(0.35f, 0.65f);
    const cv::Vec3f sky_top =
        hsvColor(rng.uniformf(190.f, 240.f), rng.uniformf(0.3f, 0.7f), rng.uniformf(0.6f, 0.95f));
    const cv::Vec3f sky_low = hsvColor(rng.uniformf(20.f, 60.f), rng.uniformf(0.1f, 0.5f), 0.95f);
    const cv::Vec3f hill =
        hsvColor(rng.uniformf(80.f, 150.f), rng.uniformf(0.3f, 0.7f), rng.uniformf(0.25f, 0.6f));
    img = generate(w, h, 1.f / static_cast<float>(h), [&](float x, float y) {
      const float ridge = horizon + 0.12f * fbm(x * 3.f, 0.5f, seed, 5);
      const float ridge2 = horizon + 0.08f + 0.08f * fbm(x * 5.f, 2.5f, seed + 1, 5);
      if (y < ridge) {
        cv::Vec3f c = mix(sky_top, sky_low, y / horizon);
        const float cloud = fbm(x * 4.f, y * 9.f, seed + 2, 5);
        return mix(c, cv::Vec3f(0.97f, 0.97f, 0.97f), smoothstep(0.1f, 0.5f, cloud));
      }
      const cv::Vec3f hc = y < ridge2 ? scale(hill, 0.7f) : hill;
      return scale(hc, 0.75f + 0.35f * fbm(x * 20.f, y * 20.f, seed + 3, 4));
    });
  } else if (kind == 1) {  // abstract shapes
    img = cv::Mat(h, w, CV_8UC3, toScalar(c0));
    for (int i = 0; i < rng.range(6, 16); ++i) {
      const cv::Vec3f c =
          hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.2f, 1.f), rng.uniformf(0.2f, 1.f));
      const cv::Point p(rng.range(0, w), rng.range(0, h));
      const int r = rng.range(std::max(2, w / 20), std::max(3, w / 3));
      switch (rng.range(0, 2)) {
        case 0:
          cv::circle(img, p, r, toScalar(c), rng.chance(0.5) ? -1 : std::max(1, r / 6),
                     cv::LINE_AA);
          break;
        case 1:
          cv::rectangle(img, p, cv::Point(p.x + rng.range(-r, r), p.y + rng.range(-r, r)),
                        toScalar(c), -1, cv::LINE_AA);
          break;
        default: {
          std::vector<cv::Point> tri{p,
                                     {p.x + rng.range(-r, r), p.y + rng.range(-r, r)},
                                     {p.x + rng.range(-r, r), p.y + rng.range(-r, r)}};
          cv::fillConvexPoly(img, tri, toScalar(c), cv::LINE_AA);
        }
      }
    }
  } else if (kind == 2) {  // typographic poster / calendar
    img = cv::Mat(h, w, CV_8UC3, toScalar(mix(c0, cv::Vec3f(1, 1, 1), 0.6f)));
    const std::string title = pseudoWord(rng, rng.range(2, 3), true);
    const double fs = std::max(0.3, w / 230.0);
    cv::putText(img, title, cv::Point(w / 12, h / 5), cv::FONT_HERSHEY_DUPLEX, fs, toScalar(c1),
                std::max(1, static_cast<int>(fs * 2)), cv::LINE_AA);
    // A grid (calendar days) or lines of text.
    if (rng.chance(0.5)) {
      const int cols = 7, rows = 5;
      const int gx = w / 12, gy = h / 3, cw = (w - 2 * gx) / cols, ch = (h - gy - h / 10) / rows;
      for (int r = 0; r < rows; ++r)
        for (int c = 0; c < cols; ++c) {
          cv::rectangle(img, cv::Point(gx + c * cw, gy + r * ch),
                        cv::Point(gx + (c + 1) * cw, gy + (r + 1) * ch), toScalar(scale(c1, 0.6f)),
                        1);
          cv::putText(img, std::to_string(r * cols + c + 1),
                      cv::Point(gx + c * cw + 2, gy + r * ch + ch / 2), cv::FONT_HERSHEY_SIMPLEX,
                      std::max(0.2, cw / 60.0), toScalar(cv::Vec3f(0.1f, 0.1f, 0.1f)), 1,
                      cv::LINE_AA);
        }
    } else {
      for (int y = h / 3; y < h - h / 10; y += std::max(6, h / 22)) {
        std::string line;
        for (int k = 0; k < rng.range(2, 5); ++k)
          line += pseudoWord(rng, rng.range(1, 3), false) + " ";
        cv::putText(img, line, cv::Point(w / 12, y), cv::FONT_HERSHEY_SIMPLEX, fs * 0.35,
                    toScalar(cv::Vec3f(0.15f, 0.15f, 0.15f)), 1, cv::LINE_AA);
      }
    }
  } else if (kind == 3) {  // photo-like: colourful fractal
    img = generate(w, h, 1.f / static_cast<float>(h), [&](float x, float y) {
      const float a = fbm(x * 3.f, y * 3.f, seed, 6), b = fbm(x * 5.f + 3.f, y * 5.f, seed + 1, 6);
      return mix(mix(c0, c1, 0.5f + 0.5f * a), cv::Vec3f(0.95f, 0.95f, 0.9f),
                 smoothstep(0.2f, 0.7f, b));
    });
  } else {  // chart / map
    img = cv::Mat(h, w, CV_8UC3, toScalar(cv::Vec3f(0.93f, 0.94f, 0.92f)));
    for (int x = 0; x < w; x += std::max(4, w / 16))
      cv::line(img, cv::Point(x, 0), cv::Point(x, h), toScalar(cv::Vec3f(0.8f, 0.8f, 0.78f)), 1);
    for (int y = 0; y < h; y += std::max(4, w / 16))
      cv::line(img, cv::Point(0, y), cv::Point(w, y), toScalar(cv::Vec3f(0.8f, 0.8f, 0.78f)), 1);
    const int bars = rng.range(5, 12);
    for (int i = 0; i < bars; ++i) {
      const int bw = w / (bars * 2 + 1);
      const int bh = rng.range(h / 10, h * 3 / 4);
      cv::rectangle(img, cv::Point(bw * (2 * i + 1), h - h / 10 - bh),
                    cv::Point(bw * (2 * i + 2), h - h / 10), toScalar(i & 1 ? c0 : c1), -1);
    }
    cv::putText(img, pseudoWord(rng, 3, true), cv::Point(w / 10, h / 8), cv::FONT_HERSHEY_SIMPLEX,
                std::max(0.3, w / 300.0), toScalar(cv::Vec3f(0.1f, 0.1f, 0.1f)), 1, cv::LINE_AA);
  }
  // Frame or white border.
  const int border = std::max(2, std::min(w, h) / 25);
  cv::rectangle(img, cv::Point(0, 0), cv::Point(w - 1, h - 1),
                rng.chance(0.5) ? cv::Scalar(20, 20, 20) : cv::Scalar(240, 240, 240), border);
  addGrain(img, seed + 5, 0.03f, 0.f, 1.f);
  return img;
}

cv::Mat bookSpinesTexture(Rng& rng, int w, int h, int* books) {
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(30, 30, 30));
  int x = 0, n = 0;
  while (x < w) {
    const int bw = std::max(3, static_cast<int>(w * rng.uniformf(0.015f, 0.05f)));
    const int top = static_cast<int>(h * rng.uniformf(0.f, 0.3f));
    const cv::Vec3f c =
        hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.2f, 0.9f), rng.uniformf(0.2f, 0.9f));
    cv::rectangle(img, cv::Point(x, top), cv::Point(std::min(w - 1, x + bw - 1), h - 1),
                  toScalar(c), -1);
    // Title along the spine: draw horizontally on a small image and rotate it.
    const int len = h - top;
    if (len > 10 && bw > 4) {
      cv::Mat spine(bw, len, CV_8UC3, toScalar(c));
      cv::putText(spine, pseudoWord(rng, rng.range(2, 4), true), cv::Point(len / 8, bw * 2 / 3),
                  cv::FONT_HERSHEY_SIMPLEX, std::max(0.15, bw / 30.0),
                  c[0] + c[1] + c[2] > 1.5f ? cv::Scalar(20, 20, 20) : cv::Scalar(230, 230, 230), 1,
                  cv::LINE_AA);
      cv::line(spine, cv::Point(len / 20, 0), cv::Point(len / 20, bw), toScalar(scale(c, 0.5f)), 1);
      cv::Mat rot;
      cv::rotate(spine, rot, cv::ROTATE_90_COUNTERCLOCKWISE);
      const int rw = std::min(rot.cols, w - x);
      rot(cv::Rect(0, 0, rw, rot.rows)).copyTo(img(cv::Rect(x, top, rw, rot.rows)));
    }
    x += bw + (rng.chance(0.1) ? 2 : 0);
    ++n;
  }
  if (books) *books = n;
  addGrain(img, seed32(rng), 0.04f, 0.f, 1.f);
  return img;
}

// ---- Objects
// -------------------------------------------------------------------------------------

namespace {

// A simple food picture: a bowl with pieces, or fruit, or a splash.
void drawFoodPicture(Rng& rng, cv::Mat& img, const cv::Rect& r) {
  const cv::Point c(r.x + r.width / 2, r.y + r.height / 2);
  const int rad = std::max(3, std::min(r.width, r.height) / 2);
  const int kind = rng.range(0, 2);
  if (kind == 0) {
    cv::ellipse(img, c, cv::Size(rad, rad / 2), 0, 0, 180,
                toScalar(hsvColor(rng.uniformf(0.f, 360.f), 0.5f, 0.9f)), -1, cv::LINE_AA);
    for (int i = 0; i < 25; ++i) {
      const cv::Point p(c.x + rng.range(-rad * 4 / 5, rad * 4 / 5), c.y - rng.range(0, rad / 3));
      cv::circle(img, p, std::max(1, rad / rng.range(6, 10)),
                 toScalar(hsvColor(rng.uniformf(20.f, 50.f), 0.7f, rng.uniformf(0.5f, 0.9f))), -1,
                 cv::LINE_AA);
    }
  } else if (kind == 1) {
    for (int i = 0; i < rng.range(2, 4); ++i) {
      const cv::Point p(c.x + rng.range(-rad / 2, rad / 2), c.y + rng.range(-rad / 3, rad / 3));
      const cv::Vec3f fc = hsvColor(rng.uniformf(0.f, 120.f), 0.8f, 0.85f);
      cv::circle(img, p, std::max(2, rad / 2), toScalar(fc), -1, cv::LINE_AA);
      cv::circle(img, cv::Point(p.x - rad / 6, p.y - rad / 6), std::max(1, rad / 8),
                 toScalar(mix(fc, cv::Vec3f(1, 1, 1), 0.6f)), -1, cv::LINE_AA);
    }
  } else {
    for (int i = 0; i < 14; ++i) {
      const double a = rng.uniform(0, 2 * CV_PI);
      cv::line(img, c,
               cv::Point(c.x + static_cast<int>(rad * std::cos(a)),
                         c.y + static_cast<int>(rad * std::sin(a))),
               toScalar(hsvColor(rng.uniformf(0.f, 360.f), 0.7f, 0.9f)), std::max(1, rad / 8),
               cv::LINE_AA);
    }
    cv::circle(img, c, std::max(2, rad / 3),
               toScalar(hsvColor(rng.uniformf(0.f, 360.f), 0.8f, 0.7f)), -1, cv::LINE_AA);
  }
}

void drawLogo(Rng& rng, cv::Mat& img, cv::Point c, int size, const cv::Vec3f& col) {
  switch (rng.range(0, 3)) {
    case 0:
      cv::circle(img, c, size, toScalar(col), std::max(1, size / 4), cv::LINE_AA);
      break;
    case 1: {
      std::vector<cv::Point> star;
      for (int k = 0; k < 10; ++k) {
        const double a = k * CV_PI / 5 - CV_PI / 2;
        const int r = (k & 1) ? size / 2 : size;
        star.push_back(
            {c.x + static_cast<int>(r * std::cos(a)), c.y + static_cast<int>(r * std::sin(a))});
      }
      cv::fillPoly(img, std::vector<std::vector<cv::Point>>{star}, toScalar(col), cv::LINE_AA);
      break;
    }
    case 2:
      cv::rectangle(img, cv::Point(c.x - size, c.y - size / 2),
                    cv::Point(c.x + size, c.y + size / 2), toScalar(col), -1, cv::LINE_AA);
      cv::circle(img, c, size / 3, cv::Scalar(250, 250, 250), -1, cv::LINE_AA);
      break;
    default: {
      std::vector<cv::Point> tri{
          {c.x, c.y - size}, {c.x + size, c.y + size}, {c.x - size, c.y + size}};
      cv::fillConvexPoly(img, tri, toScalar(col), cv::LINE_AA);
    }
  }
}

// Writes `text` centred in rectangle r, as large as fits.
void fitText(cv::Mat& img, const std::string& text, const cv::Rect& r, int font,
             const cv::Vec3f& col, int thick_div = 12) {
  int base = 0;
  const cv::Size s1 = cv::getTextSize(text, font, 1.0, 1, &base);
  const double fs = std::max(0.1, std::min(r.width / static_cast<double>(s1.width),
                                           r.height / static_cast<double>(s1.height + base)));
  const int thick = std::max(1, static_cast<int>(fs * 30 / thick_div));
  const cv::Size s = cv::getTextSize(text, font, fs, thick, &base);
  cv::putText(img, text, cv::Point(r.x + (r.width - s.width) / 2, r.y + (r.height + s.height) / 2),
              font, fs, toScalar(col), thick, cv::LINE_AA);
}

const int kFonts[] = {cv::FONT_HERSHEY_SIMPLEX,        cv::FONT_HERSHEY_DUPLEX,
                      cv::FONT_HERSHEY_TRIPLEX,        cv::FONT_HERSHEY_COMPLEX,
                      cv::FONT_HERSHEY_SCRIPT_SIMPLEX, cv::FONT_HERSHEY_SIMPLEX | cv::FONT_ITALIC};

void smallTextLines(Rng& rng, cv::Mat& img, const cv::Rect& r, const cv::Vec3f& col) {
  const int lh = std::max(4, r.height / 10);
  for (int y = r.y + lh; y < r.y + r.height; y += lh) {
    std::string line;
    for (int k = 0; k < 6; ++k) line += pseudoWord(rng, rng.range(1, 2), false) + " ";
    cv::putText(img(r), line, cv::Point(2, y - r.y), cv::FONT_HERSHEY_SIMPLEX,
                std::max(0.15, lh / 30.0), toScalar(col), 1, cv::LINE_AA);
  }
}

}  // namespace

cv::Mat packagingTexture(Rng& rng, int w, int h, float hue, const cv::Rect& front, bool busy) {
  const cv::Vec3f bg = hsvColor(hue, rng.uniformf(0.4f, 0.95f), rng.uniformf(0.45f, 0.95f));
  const cv::Vec3f ink = rng.chance(0.5) ? cv::Vec3f(0.97f, 0.97f, 0.97f)
                                        : hsvColor(hue + rng.uniformf(120.f, 240.f), 0.8f, 0.35f);
  const cv::Vec3f accent =
      hsvColor(hue + rng.uniformf(60.f, 300.f), rng.uniformf(0.5f, 1.f), rng.uniformf(0.6f, 1.f));
  const uint32_t seed = seed32(rng);
  cv::Mat img = generate(w, h, 1.f / static_cast<float>(std::max(w, h)), [&](float x, float y) {
    return scale(bg, 0.9f + 0.1f * fbm(x * 6.f, y * 6.f, seed, 3));
  });
  // Diagonal or horizontal bands across everything.
  for (int i = 0; i < rng.range(1, 4); ++i) {
    const int y0 = rng.range(0, h), t = rng.range(std::max(2, h / 30), std::max(3, h / 8));
    const int slope = rng.chance(0.5) ? rng.range(-h / 6, h / 6) : 0;
    std::vector<cv::Point> band{{0, y0}, {w, y0 + slope}, {w, y0 + slope + t}, {0, y0 + t}};
    cv::fillConvexPoly(img, band, toScalar(i == 0 ? accent : scale(bg, 0.7f)), cv::LINE_AA);
  }
  // Front: brand word, picture, badge.
  const cv::Rect f = front & cv::Rect(0, 0, w, h);
  if (f.area() > 0) {
    const std::string brand = pseudoWord(rng, rng.range(2, 3), rng.chance(0.6));
    fitText(img, brand,
            cv::Rect(f.x + f.width / 12, f.y + f.height / 14, f.width * 5 / 6, f.height / 5),
            kFonts[rng.range(0, 5)], ink);
    drawFoodPicture(
        rng, img,
        cv::Rect(f.x + f.width / 6, f.y + f.height * 2 / 5, f.width * 2 / 3, f.height * 2 / 5));
    drawLogo(rng, img, cv::Point(f.x + f.width * rng.range(2, 8) / 10, f.y + f.height * 3 / 10),
             std::max(3, f.width / 10), accent);
    if (busy) {
      fitText(img, pseudoWord(rng, 2, false),
              cv::Rect(f.x + f.width / 8, f.y + f.height * 27 / 32, f.width * 3 / 4, f.height / 10),
              cv::FONT_HERSHEY_SIMPLEX, ink);
    }
  }
  // Everywhere else: small print (nutrition panels, barcodes).
  Rng trng = rng.fork(5);
  for (int i = 0; i < (busy ? 6 : 3); ++i) {
    const int rw = std::max(8, w / trng.range(6, 12)), rh = std::max(8, h / trng.range(5, 10));
    const cv::Rect r(trng.range(0, std::max(1, w - rw)), trng.range(0, std::max(1, h - rh)), rw,
                     rh);
    if ((r & f).area() > 0) continue;
    if (trng.chance(0.3)) {
      cv::rectangle(img, r, cv::Scalar(245, 245, 245), -1);
      for (int x = r.x + 2; x < r.x + r.width - 2; x += trng.range(1, 3))
        cv::line(img, cv::Point(x, r.y + 2), cv::Point(x, r.y + r.height * 4 / 5),
                 cv::Scalar(10, 10, 10), 1);
    } else {
      cv::rectangle(img, r, toScalar(mix(bg, cv::Vec3f(1, 1, 1), 0.7f)), -1);
      smallTextLines(trng, img, r, cv::Vec3f(0.15f, 0.15f, 0.15f));
    }
  }
  addGrain(img, seed + 9, 0.03f, 0.f, 1.f);
  return img;
}

cv::Mat labelTexture(Rng& rng, int w, int h, float hue) {
  const cv::Vec3f bg = hsvColor(hue, rng.uniformf(0.3f, 1.f), rng.uniformf(0.35f, 0.95f));
  const cv::Vec3f ink =
      rng.chance(0.5) ? cv::Vec3f(0.97f, 0.97f, 0.97f) : cv::Vec3f(0.08f, 0.08f, 0.1f);
  const cv::Vec3f accent =
      hsvColor(hue + rng.uniformf(90.f, 270.f), rng.uniformf(0.5f, 1.f), rng.uniformf(0.5f, 1.f));
  cv::Mat img(h, w, CV_8UC3, toScalar(bg));
  for (int i = 0; i < rng.range(1, 3); ++i) {
    const int y = rng.range(0, h), t = rng.range(std::max(1, h / 25), std::max(2, h / 6));
    cv::rectangle(img, cv::Point(0, y), cv::Point(w, y + t),
                  toScalar(i == 0 ? accent : scale(bg, 0.6f)), -1);
  }
  if (rng.chance(0.5)) {  // waves
    std::vector<cv::Point> wave;
    const int y0 = rng.range(h / 4, h * 3 / 4), amp = std::max(1, h / 12);
    for (int x = 0; x <= w; x += 2)
      wave.push_back(
          {x, y0 + static_cast<int>(amp * std::sin(x * 2 * CV_PI / (w / rng.range(2, 4))))});
    wave.push_back({w, h});
    wave.push_back({0, h});
    cv::fillPoly(img, std::vector<std::vector<cv::Point>>{wave}, toScalar(mix(accent, bg, 0.5f)),
                 cv::LINE_AA);
  }
  const std::string brand = pseudoWord(rng, rng.range(2, 3), rng.chance(0.7));
  const int font = kFonts[rng.range(0, 5)];
  // The brand twice around (a can shows one side at a time), different sizes.
  fitText(img, brand, cv::Rect(w / 20, h / 4, w * 2 / 5, h / 3), font, ink);
  fitText(img, brand, cv::Rect(w * 11 / 20, h * 2 / 5, w * 2 / 5, h / 5), font, ink);
  drawLogo(rng, img, cv::Point(w * 3 / 4, h / 5), std::max(3, h / 10), accent);
  drawLogo(rng, img, cv::Point(w / 4, h * 3 / 4), std::max(3, h / 9), ink);
  Rng trng = rng.fork(3);
  smallTextLines(trng, img, cv::Rect(w * 9 / 20, h * 5 / 8, w / 5, h / 3), ink);
  addGrain(img, seed32(rng), 0.03f, 0.f, 1.f);
  return img;
}

cv::Mat ceramicTexture(Rng& rng, int w, int h, cv::Vec3f base, const std::string& pattern) {
  const uint32_t seed = seed32(rng);
  const int period = std::max(1, w / 64);
  cv::Mat img = generate(w, h, 1.f / 64.f, [&](float x, float y) {
    return scale(base, 0.94f + 0.06f * fbm(x, y, seed, 3, 0.5f, period) +
                           0.03f * gradientNoise(x * 8.f, y * 8.f, seed + 1, period * 8));
  });
  const cv::Vec3f ink =
      hsvColor(rng.uniformf(0.f, 360.f), rng.uniformf(0.4f, 0.9f), rng.uniformf(0.2f, 0.8f));
  if (pattern == "bands") {
    for (int i = 0; i < rng.range(1, 4); ++i) {
      const int y = rng.range(0, h - 1), t = rng.range(std::max(1, h / 40), std::max(2, h / 10));
      cv::rectangle(img, cv::Point(0, y), cv::Point(w, y + t), toScalar(i ? ink : scale(ink, 0.7f)),
                    -1);
    }
  } else if (pattern == "dots") {
    const int step = std::max(4, w / rng.range(10, 24));
    Rng drng = rng.fork(2);
    for (int y = step / 2; y < h; y += step)
      for (int x = (y / step & 1) ? step / 2 : 0; x < w; x += step)
        cv::circle(img, cv::Point(x + drng.range(-1, 1), y + drng.range(-1, 1)),
                   std::max(1, step / drng.range(4, 6)), toScalar(ink), -1, cv::LINE_AA);
  } else if (pattern == "logo") {
    const std::string word = pseudoWord(rng, rng.range(1, 3), rng.chance(0.5));
    fitText(img, word, cv::Rect(w / 8, h * 2 / 5, w / 4, h / 4), kFonts[rng.range(0, 5)], ink);
    drawLogo(rng, img, cv::Point(w * 5 / 8, h / 2), std::max(3, h / 7), ink);
  } else if (pattern == "floral") {
    Rng frng = rng.fork(4);
    for (int i = 0; i < 30; ++i) {
      const cv::Point p(frng.range(0, w - 1), frng.range(h / 6, h * 5 / 6));
      const int r = std::max(2, h / frng.range(12, 24));
      const cv::Vec3f pc = hsvColor(frng.uniformf(0.f, 360.f), 0.6f, 0.8f);
      for (int k = 0; k < 5; ++k) {
        const double a = k * 2 * CV_PI / 5;
        cv::circle(img,
                   cv::Point(p.x + static_cast<int>(r * std::cos(a)),
                             p.y + static_cast<int>(r * std::sin(a))),
                   std::max(1, r * 2 / 3), toScalar(pc), -1, cv::LINE_AA);
      }
      cv::circle(img, p, std::max(1, r / 2), cv::Scalar(40, 200, 240), -1, cv::LINE_AA);
    }
  }
  return img;
}

cv::Mat fabricTexture(Rng& rng, int w, int h, cv::Vec3f base, bool logo, float period) {
  const uint32_t seed = seed32(rng);
  cv::Mat img = generate(w, h, 1.f, [&](float x, float y) {
    const float weave = std::sin(x * 6.2832f / period) * std::sin(y * 6.2832f / period);
    const float n = fbm(x / 40.f, y / 40.f, seed, 3, 0.5f, std::max(1, static_cast<int>(w / 40)));
    return scale(base, 0.9f + 0.08f * weave + 0.1f * n +
                           0.05f * (hash01(static_cast<int>(x), static_cast<int>(y), seed) - 0.5f));
  });
  if (logo) {
    const cv::Vec3f ink = rng.chance(0.5) ? cv::Vec3f(0.95f, 0.95f, 0.95f)
                                          : hsvColor(rng.uniformf(0.f, 360.f), 0.8f, 0.6f);
    const cv::Rect r(w * 2 / 5, h / 3, w / 5, h / 4);
    if (rng.chance(0.5)) {
      fitText(img, pseudoWord(rng, rng.range(1, 2), true), r, kFonts[rng.range(0, 3)], ink, 8);
    } else {
      drawLogo(rng, img, cv::Point(r.x + r.width / 2, r.y + r.height / 2),
               std::max(3, r.height / 2), ink);
    }
  }
  return img;
}

cv::Mat skinTexture(Rng& rng, const std::string& kind, int w, int h, cv::Vec3f base) {
  const uint32_t seed = seed32(rng);
  const int P = 8;  // noise cells around u (tiles in u)
  const float fw = static_cast<float>(w);
  if (kind == "apple" || kind == "peach" || kind == "tomato" || kind == "pepper") {
    const cv::Vec3f blush = kind == "apple"   ? jitter(rng, cv::Vec3f(0.12f, 0.12f, 0.7f), 0.15f)
                            : kind == "peach" ? jitter(rng, cv::Vec3f(0.2f, 0.3f, 0.85f), 0.1f)
                                              : scale(base, 0.8f);
    const float amount = kind == "apple" ? rng.uniformf(0.f, 0.9f)
                                         : (kind == "peach" ? rng.uniformf(0.3f, 0.8f) : 0.2f);
    return generate(w, h, 1.f, [&](float x, float y) {
      const float u = x / fw * P, v = y / fw * P;
      const float b = smoothstep(-0.3f, 0.6f, fbm(u, v * 0.7f, seed, 4, 0.5f, P)) * amount;
      cv::Vec3f c = mix(base, blush, b);
      // Streaks along the meridians (apples), lenticels (small dots).
      if (kind == "apple") {
        c = scale(c, 0.9f + 0.15f * fbm(u * 6.f, v * 0.8f, seed + 1, 3, 0.5f, P * 6));
        if (hash01(static_cast<int>(x / 2), static_cast<int>(y / 2), seed + 2) > 0.994f)
          c = mix(c, cv::Vec3f(0.6f, 0.8f, 0.9f), 0.6f);
      } else {
        c = scale(c, 0.95f + 0.06f * fbm(u * 4.f, v * 4.f, seed + 1, 3, 0.5f, P * 4));
      }
      return c;
    });
  }
  if (kind == "orange" || kind == "lemon" || kind == "lime") {
    return generate(w, h, 1.f, [&](float x, float y) {
      const float u = x / fw * P, v = y / fw * P;
      const Cell pore = worley(u * 14.f, v * 14.f, seed, P * 14);
      cv::Vec3f c = scale(base, 0.93f + 0.08f * fbm(u, v, seed + 1, 3, 0.5f, P));
      return scale(c, 0.88f + 0.12f * smoothstep(0.f, 0.45f, pore.f1));
    });
  }
  if (kind == "potato") {
    return generate(w, h, 1.f, [&](float x, float y) {
      const float u = x / fw * P, v = y / fw * P;
      cv::Vec3f c = scale(base, 0.85f + 0.2f * fbm(u * 2.f, v * 2.f, seed, 5, 0.55f, P * 2));
      const Cell eye = worley(u * 1.5f, v * 1.5f, seed + 1, static_cast<int>(P * 1.5f));
      if (eye.f1 < 0.08f) c = scale(c, 0.55f);
      if (hash01(static_cast<int>(x / 3), static_cast<int>(y / 3), seed + 2) > 0.97f)
        c = scale(c, 0.7f);
      return c;
    });
  }
  if (kind == "onion" || kind == "garlic") {
    const cv::Vec3f stripe = kind == "garlic" ? cv::Vec3f(0.6f, 0.45f, 0.7f) : scale(base, 0.65f);
    return generate(w, h, 1.f, [&](float x, float y) {
      const float u = x / fw * P, v = y / fw * P;
      const float lines = std::fabs(gradientNoise(u * 6.f, v * 0.3f, seed, P * 6));
      cv::Vec3f c = scale(base, 0.9f + 0.15f * fbm(u, v, seed + 1, 3, 0.5f, P));
      return mix(c, stripe, smoothstep(0.45f, 0.2f, lines) * 0.7f);
    });
  }
  if (kind == "mushroom" || kind == "banana" || kind == "pear" || kind == "greens") {
    return generate(w, h, 1.f, [&](float x, float y) {
      const float u = x / fw * P, v = y / fw * P;
      cv::Vec3f c = scale(base, 0.9f + 0.12f * fbm(u * 2.f, v * 2.f, seed, 4, 0.5f, P * 2));
      if (kind == "pear" &&
          hash01(static_cast<int>(x / 2), static_cast<int>(y / 2), seed + 1) > 0.98f)
        c = scale(c, 0.7f);
      if (kind == "banana") {
        if (worley(u * 3.f, v * 3.f, seed + 2, P * 3).f1 < 0.06f) c = cv::Vec3f(0.1f, 0.2f, 0.3f);
        const float ridge = std::fabs(std::sin(x / fw * 5.f * 3.14159f));
        c = scale(c, 0.9f + 0.1f * ridge);
      }
      if (kind == "greens")
        c = scale(c, 0.85f + 0.25f * std::fabs(std::sin(x / fw * 40.f +
                                                        4.f * fbm(u, v, seed + 3, 2, 0.5f, P))));
      return c;
    });
  }
  throw std::invalid_argument("unknown skin '" + kind + "'");
}

cv::Mat metalTexture(Rng& rng, int w, int h, cv::Vec3f base, bool brushed) {
  const uint32_t seed = seed32(rng);
  return generate(w, h, 1.f, [&](float x, float y) {
    const float n =
        brushed ? gradientNoise(x * 0.02f, y * 2.f, seed) : fbm(x / 16.f, y / 16.f, seed, 3);
    return scale(base, 0.88f + 0.12f * n +
                           0.04f * hash01(static_cast<int>(x), static_cast<int>(y), seed + 1));
  });
}

cv::Mat plasticTexture(Rng& rng, int w, int h, cv::Vec3f base, float noise) {
  const uint32_t seed = seed32(rng);
  const int period = std::max(1, w / 32);
  return generate(w, h, 1.f / 32.f, [&](float x, float y) {
    return scale(base, 1.f - noise +
                           noise * (fbm(x, y, seed, 4, 0.5f, period) +
                                    0.5f * hash01(static_cast<int>(x * 32),
                                                  static_cast<int>(y * 32), seed + 1)));
  });
}

cv::Mat keysTexture(Rng& rng, int w, int h, int cols, int rows, cv::Vec3f body, cv::Vec3f key,
                    bool legends) {
  cv::Mat img = plasticTexture(rng, w, h, body, 0.05f);
  const float kw = static_cast<float>(w) / static_cast<float>(cols),
              kh = static_cast<float>(h) / static_cast<float>(rows);
  const cv::Vec3f ink = key[0] + key[1] + key[2] > 1.5f ? cv::Vec3f(0.1f, 0.1f, 0.1f)
                                                        : cv::Vec3f(0.92f, 0.92f, 0.92f);
  for (int r = 0; r < rows; ++r) {
    int c = 0;
    while (c < cols) {
      const int span = (rng.chance(0.08) && c + 2 <= cols) ? 2 : 1;
      const cv::Point a(static_cast<int>(c * kw + kw * 0.1f), static_cast<int>(r * kh + kh * 0.1f));
      const cv::Point b(static_cast<int>((c + span) * kw - kw * 0.1f),
                        static_cast<int>((r + 1) * kh - kh * 0.1f));
      const cv::Vec3f kc = rng.chance(0.07) ? hsvColor(rng.uniformf(0.f, 360.f), 0.6f, 0.7f) : key;
      cv::rectangle(img, a, b, toScalar(kc), -1, cv::LINE_AA);
      cv::line(img, cv::Point(a.x, b.y), b, toScalar(scale(kc, 0.6f)),
               std::max(1, static_cast<int>(kh * 0.06f)));
      if (legends && kh > 6) {
        std::string s(1, static_cast<char>('A' + rng.range(0, 25)));
        if (rng.chance(0.3)) s = std::to_string(rng.range(0, 9));
        cv::putText(
            img, s, cv::Point(a.x + static_cast<int>(kw * 0.2f), a.y + static_cast<int>(kh * 0.5f)),
            cv::FONT_HERSHEY_SIMPLEX, std::max(0.15, kh / 45.0), toScalar(ink), 1, cv::LINE_AA);
      }
      c += span;
    }
  }
  return img;
}

cv::Mat screenTexture(Rng& rng, int w, int h, bool icons) {
  const cv::Vec3f bg = icons ? hsvColor(rng.uniformf(180.f, 300.f), rng.uniformf(0.3f, 0.8f),
                                        rng.uniformf(0.2f, 0.6f))
                             : cv::Vec3f(0.55f, 0.62f, 0.6f);
  cv::Mat img(h, w, CV_8UC3, toScalar(bg));
  if (icons) {
    const int cols = 4, rows = 6;
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) {
        const int cw = w / cols, ch = h / (rows + 1);
        cv::rectangle(img, cv::Point(c * cw + cw / 5, (r + 1) * ch),
                      cv::Point((c + 1) * cw - cw / 5, (r + 1) * ch + ch * 3 / 5),
                      toScalar(hsvColor(rng.uniformf(0.f, 360.f), 0.7f, 0.9f)), -1, cv::LINE_AA);
      }
  } else {
    fitText(img, std::to_string(rng.range(10, 99999)) + "." + std::to_string(rng.range(0, 99)),
            cv::Rect(w / 10, h / 5, w * 4 / 5, h * 3 / 5), cv::FONT_HERSHEY_SIMPLEX,
            cv::Vec3f(0.1f, 0.12f, 0.1f));
  }
  return img;
}

cv::Mat spongeTexture(Rng& rng, int w, int h, cv::Vec3f base) {
  const uint32_t seed = seed32(rng);
  return generate(w, h, 1.f, [&](float x, float y) {
    const Cell c = worley(x / 4.f, y / 4.f, seed);
    const float hole = smoothstep(0.15f, 0.4f, c.f1);
    return scale(base, 0.55f + 0.45f * hole + 0.05f * gradientNoise(x / 20.f, y / 20.f, seed + 1));
  });
}

cv::Mat coverTexture(Rng& rng, int w, int h, cv::Vec3f base) {
  cv::Mat img = plasticTexture(rng, w, h, base, 0.05f);
  const cv::Vec3f ink = base[0] + base[1] + base[2] > 1.5f ? cv::Vec3f(0.1f, 0.1f, 0.15f)
                                                           : cv::Vec3f(0.95f, 0.95f, 0.95f);
  switch (rng.range(0, 2)) {
    case 0:  // title block
      cv::rectangle(img, cv::Point(w / 6, h / 5), cv::Point(w * 5 / 6, h * 2 / 5),
                    toScalar(mix(base, ink, 0.8f)), -1);
      fitText(img, pseudoWord(rng, 3, true), cv::Rect(w / 5, h / 5 + h / 40, w * 3 / 5, h / 6),
              cv::FONT_HERSHEY_DUPLEX, base);
      break;
    case 1: {  // pattern
      Rng prng = rng.fork(1);
      for (int i = 0; i < 25; ++i)
        drawLogo(prng, img, cv::Point(prng.range(0, w), prng.range(0, h)),
                 std::max(2, w / prng.range(8, 20)),
                 hsvColor(prng.uniformf(0.f, 360.f), 0.6f, 0.8f));
      break;
    }
    default:
      fitText(img, pseudoWord(rng, 2, false), cv::Rect(w / 8, h / 3, w * 3 / 4, h / 5),
              kFonts[rng.range(0, 5)], ink);
      cv::line(img, cv::Point(w / 8, h * 3 / 5), cv::Point(w * 7 / 8, h * 3 / 5), toScalar(ink),
               std::max(1, h / 80));
  }
  return img;
}

}  // namespace slamaware::synth
