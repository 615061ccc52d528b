#include "tools/synth/sensor.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "tools/synth/rng.h"

namespace slamaware::synth {

namespace {

// 65536 standard normal samples, the same in every run.
const std::vector<float>& gaussianTable() {
  static const std::vector<float> table = [] {
    std::vector<float> t(1 << 16);
    Rng rng(0x5EED5EEDull);
    for (auto& v : t) v = static_cast<float>(rng.normal());
    return t;
  }();
  return table;
}

// Bilinear sample of the three colour planes (w x h each) at (x, y).
void sampleBilinear(const std::vector<float>& img, int w, int h, float x, float y, float out[3]) {
  x = std::min(std::max(x, 0.f), static_cast<float>(w - 1));
  y = std::min(std::max(y, 0.f), static_cast<float>(h - 1));
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const int x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
  const float fx = x - static_cast<float>(x0), fy = y - static_cast<float>(y0);
  const size_t npx = static_cast<size_t>(w) * h;
  const size_t a = static_cast<size_t>(y0) * w + x0, b = static_cast<size_t>(y0) * w + x1;
  const size_t c = static_cast<size_t>(y1) * w + x0, d = static_cast<size_t>(y1) * w + x1;
  for (int k = 0; k < 3; ++k) {
    const float* p = &img[k * npx];
    const float top = p[a] + fx * (p[b] - p[a]), bot = p[c] + fx * (p[d] - p[c]);
    out[k] = top + fy * (bot - top);
  }
}

void motionBlur(const FrameBuffers& fb, const Intrinsics& K,
                const Eigen::Isometry3d& T_world_camera, const ShutterMotion& motion,
                std::vector<float>* img) {
  const int w = fb.vp.w, h = fb.vp.h;
  const size_t npx = static_cast<size_t>(w) * h;
  const std::vector<float> src = *img;
  // Maps points of the current camera into the camera half a shutter time earlier; the blur is
  // spread symmetrically around the current pose (the ground-truth pose is mid-exposure).
  const Eigen::Isometry3d T = motion.T_world_camera_open.inverse() * T_world_camera;
  const Eigen::Matrix3f R = T.linear().cast<float>();
  const Eigen::Vector3f t = T.translation().cast<float>();
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      const float z = fb.depth[i];
      if (!(z > 0.f)) continue;
      const float px = static_cast<float>(x + fb.vp.x0), py = static_cast<float>(y + fb.vp.y0);
      const Eigen::Vector3f P(z * (px - K.cx) / K.fx, z * (py - K.cy) / K.fy, z);
      const Eigen::Vector3f Q = R * P + t;
      if (Q.z() < 0.05f) continue;
      const float dx = K.fx * Q.x() / Q.z() + K.cx - px, dy = K.fy * Q.y() / Q.z() + K.cy - py;
      const float len = std::sqrt(dx * dx + dy * dy);
      if (len < 0.25f) continue;
      const int n = std::min(24, static_cast<int>(std::ceil(2.f * len)) + 1);
      float acc[3] = {0, 0, 0};
      for (int k = 0; k < n; ++k) {
        const float s = -1.f + 2.f * static_cast<float>(k) / static_cast<float>(n - 1);
        float c[3];
        sampleBilinear(src, w, h, static_cast<float>(x) + s * dx, static_cast<float>(y) + s * dy,
                       c);
        for (int j = 0; j < 3; ++j) acc[j] += c[j];
      }
      for (int j = 0; j < 3; ++j) (*img)[j * npx + i] = acc[j] / static_cast<float>(n);
    }
  }
}

// Separable Gaussian blur of the three planes, edges repeated.
void gaussianBlur(std::vector<float>* img, int w, int h, double sigma) {
  if (!(sigma > 0.05)) return;
  const int r = std::min(4, static_cast<int>(std::ceil(3.0 * sigma)));
  std::vector<float> k(2 * r + 1);
  float sum = 0;
  for (int i = -r; i <= r; ++i)
    sum += k[i + r] = static_cast<float>(std::exp(-0.5 * i * i / (sigma * sigma)));
  for (auto& v : k) v /= sum;
  const size_t npx = static_cast<size_t>(w) * h;
  std::vector<float> tmp(w), pad(static_cast<size_t>(w + 2 * r));
  std::vector<float> rows(npx);
  for (int c = 0; c < 3; ++c) {
    float* plane = &(*img)[c * npx];
    for (int y = 0; y < h; ++y) {
      const float* row = plane + static_cast<size_t>(y) * w;
      for (int x = -r; x < w + r; ++x)
        pad[static_cast<size_t>(x + r)] = row[std::min(std::max(x, 0), w - 1)];
      float* dst = &rows[static_cast<size_t>(y) * w];
      for (int x = 0; x < w; ++x) {
        float acc = 0;
        for (int t = 0; t <= 2 * r; ++t) acc += k[t] * pad[static_cast<size_t>(x + t)];
        dst[x] = acc;
      }
    }
    for (int y = 0; y < h; ++y) {
      float* dst = plane + static_cast<size_t>(y) * w;
      std::fill(dst, dst + w, 0.f);
      for (int t = -r; t <= r; ++t) {
        const float* src = &rows[static_cast<size_t>(std::min(std::max(y + t, 0), h - 1)) * w];
        const float kt = k[t + r];
        for (int x = 0; x < w; ++x) dst[x] += kt * src[x];
      }
    }
  }
}

}  // namespace

cv::Mat applySensor(const FrameBuffers& fb, const Intrinsics& K,
                    const Eigen::Isometry3d& T_world_camera, const SensorOptions& opt,
                    const ShutterMotion& motion, uint64_t noise_seed) {
  const int w = fb.vp.w, h = fb.vp.h;
  std::vector<float> img = fb.bgr;
  if (motion.enabled && opt.shutter_s > 0) motionBlur(fb, K, T_world_camera, motion, &img);
  gaussianBlur(&img, w, h, opt.psf_sigma_px);

  const std::vector<float>& gauss = gaussianTable();
  const float gain = static_cast<float>(opt.gain), vig = static_cast<float>(opt.vignetting);
  const float read2 = static_cast<float>(opt.read_noise * opt.read_noise),
              shot = static_cast<float>(opt.shot_noise);
  // Vignetting over the full image (the viewport may be a window of it).
  const float cxi = K.cx, cyi = K.cy;
  const float r2max = cxi * cxi + cyi * cyi;
  // Noise sigma per signal level (DN): sqrt(read^2 + shot * signal).
  float sigma[256];
  for (int i = 0; i < 256; ++i) sigma[i] = std::sqrt(read2 + shot * static_cast<float>(i));
  cv::Mat out(h, w, CV_8UC3);
  std::vector<uint16_t> noise_idx(static_cast<size_t>(w) * 3 + 4);
  std::vector<float> vig_row(static_cast<size_t>(w));
  for (int y = 0; y < h; ++y) {
    // The noise of a row: 16-bit table indices, four from each 64-bit draw.
    Rng rng(hashCombine(noise_seed, static_cast<uint64_t>(y + fb.vp.y0)));
    for (size_t i = 0; i < noise_idx.size(); i += 4) {
      const uint64_t bits = rng.next();
      for (size_t k = 0; k < 4 && i + k < noise_idx.size(); ++k)
        noise_idx[i + k] = static_cast<uint16_t>(bits >> (16 * k));
    }
    const float dy = static_cast<float>(y + fb.vp.y0) - cyi;
    for (int x = 0; x < w; ++x) {
      const float dx = static_cast<float>(x + fb.vp.x0) - cxi;
      vig_row[static_cast<size_t>(x)] = 255.f * gain * (1.f - vig * (dx * dx + dy * dy) / r2max);
    }
    uint8_t* row = out.ptr<uint8_t>(y);
    const size_t npx = static_cast<size_t>(w) * h;
    const float* src[3] = {&img[static_cast<size_t>(y) * w], &img[npx + static_cast<size_t>(y) * w],
                           &img[2 * npx + static_cast<size_t>(y) * w]};
    for (int x = 0; x < w; ++x) {
      const float v = vig_row[static_cast<size_t>(x)];
      for (int c = 0; c < 3; ++c) {
        float dn = src[c][x] * v;
        if (dn > 216.75f)
          dn = 216.75f + 38.25f * (1.f - std::exp(-(dn - 216.75f) / 38.25f));  // soft shoulder
        dn = std::min(std::max(dn, 0.f), 255.f);
        dn += gauss[noise_idx[static_cast<size_t>(3 * x + c)]] * sigma[static_cast<int>(dn)];
        dn = std::min(std::max(dn, 0.f), 255.f);
        row[3 * x + c] = static_cast<uint8_t>(static_cast<int>(dn + 0.5f));
      }
    }
  }
  return out;
}

}  // namespace slamaware::synth
