#include "tools/synth/categories.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "tools/synth/noise.h"
#include "tools/synth/textures.h"

namespace slamaware::synth {

namespace {

constexpr float kPi = 3.14159265f;
using V2 = Eigen::Vector2f;
using V3 = Eigen::Vector3f;

TexturePtr tex(const cv::Mat& m, bool wrap_u = true, bool wrap_v = false) {
  return std::make_shared<const Texture>(m, wrap_u, wrap_v);
}

cv::Vec3f anyColor(Rng& r, float s0 = 0.3f, float s1 = 0.9f, float v0 = 0.3f, float v1 = 0.9f) {
  return hsvColor(r.uniformf(0.f, 360.f), r.uniformf(s0, s1), r.uniformf(v0, v1));
}

cv::Vec3f ceramicColor(Rng& r) {
  switch (r.range(0, 4)) {
    case 0:
      return hsvColor(r.uniformf(30.f, 60.f), r.uniformf(0.0f, 0.12f),
                      r.uniformf(0.85f, 0.97f));  // white / cream
    case 1:
      return hsvColor(r.uniformf(0.f, 360.f), r.uniformf(0.15f, 0.4f),
                      r.uniformf(0.7f, 0.92f));  // pastel
    case 2:
      return hsvColor(r.uniformf(0.f, 360.f), r.uniformf(0.5f, 0.9f),
                      r.uniformf(0.35f, 0.8f));  // strong glaze
    case 3:
      return hsvColor(r.uniformf(0.f, 360.f), r.uniformf(0.0f, 0.2f),
                      r.uniformf(0.1f, 0.3f));  // dark
    default:
      return hsvColor(r.uniformf(15.f, 35.f), r.uniformf(0.3f, 0.6f),
                      r.uniformf(0.4f, 0.7f));  // earthenware
  }
}

std::string pattern(Rng& r) {
  static const std::vector<std::string> p{"plain", "bands", "dots", "logo", "floral", "plain"};
  return r.pick(p);
}

class Builder {
 public:
  Builder(const std::string& category, uint64_t seed) : rng(seed) {
    model.category = category;
    model.seed = seed;
  }
  Rng rng;
  ObjectModel model;

  void add(Mesh m, TexturePtr t, float spec = 0.05f, int shin = 4, bool double_sided = false) {
    ObjectPart p;
    p.mesh = std::move(m);
    p.material.texture = std::move(t);
    p.material.specular = spec;
    p.material.shininess_log2 = shin;
    p.material.double_sided = double_sided;
    model.parts.push_back(std::move(p));
  }
  void transformAll(const Eigen::Affine3f& T) {
    for (auto& p : model.parts) p.mesh.transform(T);
  }
};

Eigen::Affine3f translation(float x, float y, float z) {
  return Eigen::Affine3f(Eigen::Translation3f(x, y, z));
}
Eigen::Affine3f rotationZ(float a) { return Eigen::Affine3f(Eigen::AngleAxisf(a, V3::UnitZ())); }
Eigen::Affine3f rotationY(float a) { return Eigen::Affine3f(Eigen::AngleAxisf(a, V3::UnitY())); }
Eigen::Affine3f rotationX(float a) { return Eigen::Affine3f(Eigen::AngleAxisf(a, V3::UnitX())); }
Eigen::Affine3f scaling(float x, float y, float z) {
  Eigen::Affine3f T = Eigen::Affine3f::Identity();
  T.scale(V3(x, y, z));
  return T;
}
float smoothstep(float e0, float e1, float x) {
  const float t = std::min(1.f, std::max(0.f, (x - e0) / (e1 - e0)));
  return t * t * (3.f - 2.f * t);
}

// A lathe profile sampled from r(t), z(t), t in [0, 1].
std::vector<ProfilePoint> sampled(int n, const std::function<float(float)>& r,
                                  const std::function<float(float)>& z) {
  std::vector<ProfilePoint> p;
  for (int i = 0; i <= n; ++i) {
    const float t = static_cast<float>(i) / static_cast<float>(n);
    p.push_back({std::max(0.f, r(t)), z(t)});
  }
  return p;
}

// A closed round body from a radius function of the polar angle theta (0 = bottom pole) and the
// azimuth phi, with height H: (r sin(theta) cos(phi), r sin(theta) sin(phi), H/2 (1 - cos(theta))).
Mesh roundBody(float R, float H, const std::function<float(float theta, float phi)>& rmod,
               int seg = 40, int rings = 24) {
  return parametricSphere(
      [&](float s, float t) {
        const float th = kPi * t, ph = 2.f * kPi * s;
        const float k = rmod ? rmod(th, ph) : 1.f;
        return V3(R * k * std::sin(th) * std::cos(ph), R * k * std::sin(th) * std::sin(ph),
                  0.5f * H * (1.f - std::cos(th)));
      },
      seg, rings);
}

// Arc-length fraction of a lathe profile at point `index` (the texture's v there).
float arcFraction(const std::vector<ProfilePoint>& p, size_t index) {
  float upto = 0, total = 0;
  for (size_t i = 1; i < p.size(); ++i) {
    const float d = std::hypot(p[i].r - p[i - 1].r, p[i].z - p[i - 1].z);
    total += d;
    if (i <= index) upto += d;
  }
  return total > 0 ? upto / total : 0.f;
}

// Repaints the rows of a lathe texture above v = v_rim (the inside of a vessel) in the plain glaze.
void plainInside(Rng& r, cv::Mat& t, const cv::Vec3f& col, float v_rim) {
  const int rows =
      std::clamp(static_cast<int>((1.f - v_rim) * static_cast<float>(t.rows)), 0, t.rows);
  if (rows == 0) return;
  cv::Mat plain = ceramicTexture(r, t.cols, t.rows, col, "plain");
  plain(cv::Rect(0, 0, t.cols, rows)).copyTo(t(cv::Rect(0, 0, t.cols, rows)));
}

void polygonCcw(std::vector<V2>& p) {
  float a = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const V2& u = p[i];
    const V2& v = p[(i + 1) % p.size()];
    a += u.x() * v.y() - v.x() * u.y();
  }
  if (a < 0) std::reverse(p.begin(), p.end());
}

// A box with a packaging print: the atlas is generated at `ppm` pixels per metre.
void printedBox(Builder& b, const V3& size, float hue, bool busy, const Eigen::Affine3f& T,
                float ppm = 1800.f) {
  const BoxAtlas a = boxAtlasLayout(size);
  float U = 2.f * (size.x() + size.y()), Vv = size.z() + 2.f * size.y();
  const float k = std::min(ppm, 1024.f / std::max(U, Vv));
  const int w = std::max(16, static_cast<int>(U * k)), h = std::max(16, static_cast<int>(Vv * k));
  const cv::Rect front(static_cast<int>(a.front[0] * w), static_cast<int>(a.front[1] * h),
                       static_cast<int>((a.front[2] - a.front[0]) * w),
                       static_cast<int>((a.front[3] - a.front[1]) * h));
  cv::Mat t = packagingTexture(b.rng, w, h, hue, front, busy);
  // The back gets a second picture of the front's style (boxes are printed on both faces).
  const cv::Rect back(static_cast<int>(a.back[0] * w), front.y, front.width, front.height);
  if (back.x + back.width <= w) {
    Rng r2 = b.rng.fork(77);
    cv::Mat t2 = packagingTexture(r2, w, h, hue, back, false);
    t2(back).copyTo(t(back));
  }
  Mesh m = box(size);
  m.transform(T * translation(0, 0, size.z() / 2));
  b.add(std::move(m), tex(t, false, false), 0.12f, 5);
}

// ---- The categories
// ------------------------------------------------------------------------------

void makeBowl(Builder& b) {
  Rng& r = b.rng;
  const float R = r.uniformf(0.06f, 0.1f), H = R * r.uniformf(0.5f, 0.8f),
              th = r.uniformf(0.003f, 0.006f);
  const float rf = R * r.uniformf(0.35f, 0.5f), foot = r.uniformf(0.005f, 0.012f),
              p = r.uniformf(0.5f, 1.1f);
  auto outer = [&](float t) { return rf + (R - rf) * std::pow(std::sin(t * kPi / 2), p); };
  std::vector<ProfilePoint> prof{{0, 0}, {rf * 0.95f, 0, true}, {rf, foot, true}};
  for (int i = 1; i <= 14; ++i) {
    const float t = static_cast<float>(i) / 14.f;
    prof.push_back({outer(t), foot + (H - foot) * t});
  }
  prof.back().crease = true;
  prof.push_back({R - th, H, true});
  for (int i = 13; i >= 0; --i) {
    const float t = static_cast<float>(i) / 14.f;
    prof.push_back({std::max(0.f, outer(t) - th * 1.2f), foot + th + (H - foot - th) * t});
  }
  prof.push_back({0, foot + th});
  Mesh m = lathe(prof, 48);
  const cv::Vec3f col = ceramicColor(r);
  b.add(std::move(m), tex(ceramicTexture(r, 384, 192, col, pattern(r))), r.uniformf(0.15f, 0.35f),
        5);
}

void makeCap(Builder& b) {
  Rng& r = b.rng;
  const float rx = r.uniformf(0.088f, 0.1f), ry = rx * r.uniformf(1.08f, 1.18f),
              H = r.uniformf(0.08f, 0.11f);
  const cv::Vec3f col = anyColor(r, 0.2f, 0.9f, 0.15f, 0.9f);
  const cv::Vec3f brim_col = r.chance(0.7) ? col : anyColor(r, 0.3f, 0.9f, 0.2f, 0.9f);
  const float lift = 0.006f;
  // Crown: a half ellipsoid, a little flattened on top, in six panels (seams in the texture).
  std::vector<ProfilePoint> prof{{0, lift}, {1.f, lift, true}};
  for (int i = 1; i <= 12; ++i) {
    const float a = static_cast<float>(i) / 12.f * kPi / 2;
    prof.push_back({std::cos(a), lift + H * std::pow(std::sin(a), 0.8f)});
  }
  Mesh crown = lathe(prof, 48);
  crown.transform(scaling(rx, ry, 1.f));
  // Undo the radius scaling of the profile's r = 1 convention: the scaling above applies rx, ry.
  cv::Mat ct = fabricTexture(r, 512, 256, col, false, 2.5f);
  for (int k = 0; k < 6; ++k)
    cv::line(ct, cv::Point(k * 512 / 6, 0), cv::Point(k * 512 / 6, 256), cv::Scalar(20, 20, 20), 1,
             cv::LINE_AA);
  // Logo on the front panel (front = -y, u = 0.75).
  {
    cv::Mat logo = fabricTexture(r, 128, 96, col, true, 2.5f);
    logo.copyTo(ct(cv::Rect(384 - 64, 110, 128, 96)));
  }
  b.add(std::move(crown), tex(ct), 0.03f, 3);
  // Button on top.
  Mesh button = roundBody(0.008f, 0.008f, nullptr, 12, 8);
  button.transform(translation(0, 0, lift + H - 0.003f));
  b.add(std::move(button), tex(fabricTexture(r, 32, 32, brim_col, false)), 0.05f, 3);
  // Brim: a crescent in front (-y), drooping towards its edge.
  const float reach = r.uniformf(0.06f, 0.08f);
  std::vector<V2> poly;
  for (int i = 0; i <= 24; ++i) {
    const float a = kPi + kPi * static_cast<float>(i) / 24.f;  // from -x through -y to +x
    poly.push_back(
        {(rx * 0.98f) * std::cos(a), (ry + reach * std::pow(std::sin(a), 2.f)) * std::sin(a)});
  }
  for (int i = 23; i >= 1; --i) {
    const float a = kPi + kPi * static_cast<float>(i) / 24.f;
    poly.push_back({rx * 0.97f * std::cos(a), ry * 0.9f * std::sin(a)});
  }
  polygonCcw(poly);
  Mesh brim = extrude(poly, 0.f, 0.004f, 5.f);
  for (auto& v : brim.vertices) {
    const float out = std::max(0.f, -v.p.y() - ry * 0.9f);
    v.p.z() += lift + 0.002f - 0.1f * out * out / reach + 0.004f * std::fabs(v.p.x()) / rx;
  }
  b.add(std::move(brim), tex(fabricTexture(r, 128, 128, brim_col, false)), 0.03f, 3, true);
}

void makeCerealBox(Builder& b) {
  Rng& r = b.rng;
  const V3 size(r.uniformf(0.19f, 0.29f), r.uniformf(0.05f, 0.08f), r.uniformf(0.25f, 0.34f));
  printedBox(b, size, r.uniformf(0.f, 360.f), true, Eigen::Affine3f::Identity());
}

void makeMug(Builder& b) {
  Rng& r = b.rng;
  const float R = r.uniformf(0.037f, 0.05f), H = r.uniformf(0.08f, 0.115f),
              th = r.uniformf(0.004f, 0.006f);
  const float taper = r.uniformf(0.85f, 1.f);
  std::vector<ProfilePoint> prof{{0, 0},
                                 {R * taper * 0.94f, 0, true},
                                 {R * taper, 0.005f},
                                 {R, H, true},
                                 {R - th, H, true},
                                 {(R - th) * (0.5f + 0.5f * taper), th + 0.006f},
                                 {0, th + 0.006f}};
  Mesh body = lathe(prof, 48);
  const cv::Vec3f col = ceramicColor(r);
  std::string pat = pattern(r);
  if (pat == "plain" && r.chance(0.6)) pat = "logo";
  cv::Mat t = ceramicTexture(r, 512, 256, col, pat);
  plainInside(r, t, col, arcFraction(prof, 3));  // the print is on the outside only
  b.add(std::move(body), tex(t), r.uniformf(0.2f, 0.4f), 5);
  // Handle: a C-shaped tube on the +x side.
  const float d = r.uniformf(0.022f, 0.032f), hh = H * r.uniformf(0.55f, 0.75f),
              zm = H * r.uniformf(0.45f, 0.55f);
  std::vector<V3> curve;
  for (int i = 0; i <= 20; ++i) {
    const float s = static_cast<float>(i) / 20.f;
    curve.push_back({R - 0.004f + d * std::sin(s * kPi) * (1.f + 0.15f * std::sin(s * 2 * kPi)),
                     0.f, zm + 0.5f * hh * std::cos(s * kPi)});
  }
  const float hr = r.uniformf(0.005f, 0.008f);
  Mesh handle = sweep(
      curve, [&](float) { return hr; }, 12, true, r.uniformf(0.5f, 0.9f), V3::UnitY());
  b.add(std::move(handle), tex(plasticTexture(r, 64, 64, col, 0.03f)), 0.3f, 5);
}

void makeCan(Builder& b, bool soda) {
  Rng& r = b.rng;
  float R, H;
  if (soda) {
    const int kind = r.range(0, 2);
    R = kind == 2 ? r.uniformf(0.028f, 0.03f) : r.uniformf(0.032f, 0.034f);
    H = kind == 2 ? r.uniformf(0.14f, 0.16f) : r.uniformf(0.115f, 0.125f);
  } else {
    R = r.uniformf(0.035f, 0.052f);
    H = r.uniformf(0.06f, 0.125f);
  }
  const float neck = soda ? 0.82f : 0.96f;
  std::vector<ProfilePoint> prof{{0, 0.005f, false, 0.f},
                                 {R * 0.78f, 0.f, true, 0.02f},
                                 {R * 0.92f, 0.002f, false, 0.04f},
                                 {R, 0.01f, true, 0.07f},
                                 {R, H - (soda ? 0.013f : 0.004f), true, 0.93f},
                                 {R * neck, H - 0.002f, false, 0.96f},
                                 {R * neck + 0.001f, H, true, 0.97f},
                                 {R * neck - 0.002f, H - 0.001f, true, 0.98f},
                                 {R * neck - 0.003f, H - 0.005f, true, 0.99f},
                                 {0, H - 0.005f, false, 1.f}};
  if (!soda) {
    // Food cans: ribbed bodies.
    std::vector<ProfilePoint> p2(prof.begin(), prof.begin() + 4);
    const int ribs = r.range(0, 1) ? 6 : 0;
    for (int i = 1; i <= ribs; ++i) {
      const float z = 0.01f + (H - 0.014f) * static_cast<float>(i) / static_cast<float>(ribs + 1);
      p2.push_back({R * 0.985f, z, false, 0.07f + 0.86f * (z - 0.01f) / (H - 0.014f)});
      p2.push_back({R, z + 0.003f, false, 0.07f + 0.86f * (z + 0.003f - 0.01f) / (H - 0.014f)});
    }
    p2.insert(p2.end(), prof.begin() + 4, prof.end());
    prof = p2;
  }
  const int w = 512, h = std::clamp(static_cast<int>(512.f * H / (2 * kPi * R)), 64, 512);
  cv::Mat t = labelTexture(r, w, h, r.uniformf(0.f, 360.f));
  if (!soda && r.chance(0.5)) {
    // A paper label with a food picture on it.
    Rng pr = r.fork(3);
    cv::Mat pic = packagingTexture(pr, w / 2, h * 7 / 8, pr.uniformf(0.f, 360.f),
                                   cv::Rect(0, 0, w / 2, h * 7 / 8), false);
    pic.copyTo(t(cv::Rect(w / 4, h / 16, w / 2, h * 7 / 8)));
  }
  const cv::Scalar metal = soda ? cv::Scalar(200, 200, 205) : cv::Scalar(175, 178, 180);
  cv::rectangle(t, cv::Point(0, 0), cv::Point(w, static_cast<int>(0.07f * h)), metal, -1);
  cv::rectangle(t, cv::Point(0, static_cast<int>(0.93f * h)), cv::Point(w, h), metal, -1);
  b.add(lathe(prof, 48), tex(t), soda ? 0.5f : 0.3f, 6);
}

void makeApple(Builder& b) {
  Rng& r = b.rng;
  const float R = r.uniformf(0.034f, 0.045f), H = 2 * R * r.uniformf(0.82f, 0.98f);
  const float top_w = r.uniformf(0.05f, 0.15f), lobes = r.uniformf(0.f, 0.03f),
              asym = r.uniformf(0.f, 0.04f);
  const float dimple = R * r.uniformf(0.15f, 0.3f);
  Mesh m = parametricSphere(
      [&](float s, float t) {
        const float th = kPi * t, ph = 2 * kPi * s;
        const float k = (1.f + top_w * (0.5f - 0.5f * std::cos(th)) - top_w * 0.5f) *
                        (1.f + lobes * std::cos(5 * ph) * std::sin(th)) *
                        (1.f + asym * std::cos(ph));
        float rr = R * k * std::sin(th);
        float z = 0.5f * H * (1.f - std::cos(th));
        // Dimples at both poles.
        const float near_top = std::exp(-std::pow((kPi - th) / 0.45f, 2.f)),
                    near_bot = std::exp(-std::pow(th / 0.5f, 2.f));
        z -= dimple * near_top;
        z += 0.5f * dimple * near_bot;
        return V3(rr * std::cos(ph), rr * std::sin(ph), z);
      },
      40, 28);
  static const cv::Vec3f kBase[] = {
      {0.1f, 0.15f, 0.65f}, {0.2f, 0.65f, 0.55f}, {0.2f, 0.7f, 0.8f}, {0.15f, 0.35f, 0.7f}};
  b.add(std::move(m), tex(skinTexture(r, "apple", 256, 128, kBase[r.range(0, 3)])), 0.35f, 5);
  std::vector<V3> stem{{0, 0, H - dimple},
                       {0.002f, 0, H - dimple + 0.008f},
                       {r.uniformf(0.003f, 0.007f), 0, H - dimple + r.uniformf(0.012f, 0.02f)}};
  b.add(sweep(
            stem, [](float) { return 0.0016f; }, 6, true),
        tex(plasticTexture(r, 16, 16, {0.1f, 0.2f, 0.3f})), 0.05f, 3);
}

void makeBall(Builder& b) {
  Rng& r = b.rng;
  const int kind = r.range(0, 3);
  const float R = kind == 0   ? r.uniformf(0.032f, 0.034f)
                  : kind == 1 ? r.uniformf(0.036f, 0.038f)
                              : r.uniformf(0.035f, 0.075f);
  const cv::Vec3f c0 = kind == 0   ? cv::Vec3f(0.2f, 0.85f, 0.8f)
                       : kind == 1 ? cv::Vec3f(0.9f, 0.92f, 0.93f)
                                   : anyColor(r, 0.5f, 1.f, 0.5f, 0.95f);
  const cv::Vec3f c1 = kind == 1   ? cv::Vec3f(0.15f, 0.1f, 0.75f)
                       : kind == 3 ? cv::Vec3f(0.1f, 0.1f, 0.1f)
                                   : anyColor(r, 0.5f, 1.f, 0.4f, 0.95f);
  const uint32_t seed = static_cast<uint32_t>(r.next());
  const int w = 256, h = 128;
  cv::Mat t(h, w, CV_8UC3);
  // The pattern as a function of the direction on the sphere (no distortion at the poles).
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float ph = 2 * kPi * (x + 0.5f) / w, th = kPi * (1.f - (y + 0.5f) / h);
      const V3 d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), -std::cos(th));
      cv::Vec3f c = c0;
      if (kind == 0 || kind == 1) {
        // Tennis / baseball seam: a curve where a saddle function crosses zero.
        const float f = d.x() * d.x() - d.y() * d.y() + 0.35f * d.z();
        if (std::fabs(f) < (kind == 0 ? 0.05f : 0.04f))
          c = kind == 0 ? cv::Vec3f(0.9f, 0.95f, 0.95f) : c1;
        c = c * (0.9f + 0.1f * gradientNoise(x / 3.f, y / 3.f, seed, w / 3));
      } else if (kind == 2) {
        const int band = static_cast<int>(std::floor((d.z() + 1.f) * 3.f));
        const int seg = static_cast<int>(std::floor((ph / (2 * kPi)) * 6.f));
        c = ((band + seg) & 1) ? c1 : c0;
      } else {
        // Panels: nearest of 12 icosahedron vertices (black) or of the rest (white).
        const float g = 1.618f;
        static const V3 kIco[12] = {{-1, 1.618f, 0},  {1, 1.618f, 0},   {-1, -1.618f, 0},
                                    {1, -1.618f, 0},  {0, -1, 1.618f},  {0, 1, 1.618f},
                                    {0, -1, -1.618f}, {0, 1, -1.618f},  {1.618f, 0, -1},
                                    {1.618f, 0, 1},   {-1.618f, 0, -1}, {-1.618f, 0, 1}};
        float best = -2;
        for (const auto& v : kIco) best = std::max(best, d.dot(v / std::sqrt(1.f + g * g)));
        c = best > 0.93f ? c1 : c0;
      }
      t.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<uint8_t>(255 * c[0]), static_cast<uint8_t>(255 * c[1]),
                    static_cast<uint8_t>(255 * c[2]));
    }
  b.add(roundBody(R, 2 * R, nullptr, 40, 24), tex(t), kind >= 2 ? 0.45f : 0.05f, kind >= 2 ? 6 : 3);
}

void makeBanana(Builder& b) {
  Rng& r = b.rng;
  const float L = r.uniformf(0.15f, 0.22f), bend = r.uniformf(0.5f, 1.1f),
              R = r.uniformf(0.015f, 0.02f);
  std::vector<V3> curve;
  const float rad = L / bend;
  for (int i = 0; i <= 24; ++i) {
    const float a = -bend / 2 + bend * static_cast<float>(i) / 24.f;
    curve.push_back({rad * std::sin(a),
                     rad * (1.f - std::cos(a)) - rad * (1.f - std::cos(bend / 2)) * 0.5f, 0.f});
  }
  Mesh m = sweep(
      curve,
      [&](float t) { return R * std::pow(std::sin(kPi * (0.04f + 0.92f * t)), 0.6f) + 0.002f; }, 10,
      true, 0.9f, V3::UnitZ());
  const cv::Vec3f col =
      r.chance(0.7) ? cv::Vec3f(0.2f, 0.78f, 0.9f) : cv::Vec3f(0.25f, 0.75f, 0.65f);
  b.add(std::move(m), tex(skinTexture(r, "banana", 128, 256, col)), 0.15f, 4);
}

void makePepper(Builder& b) {
  Rng& r = b.rng;
  const float R = r.uniformf(0.038f, 0.05f), H = r.uniformf(0.07f, 0.1f);
  const int lobes = r.range(3, 4);
  const float depth = r.uniformf(0.06f, 0.12f);
  Mesh m = parametricSphere(
      [&](float s, float t) {
        const float th = kPi * t, ph = 2 * kPi * s;
        const float prof = std::pow(std::max(0.f, std::sin(th)), 0.6f) * (0.85f + 0.2f * t);
        const float k = 1.f + depth * std::cos(lobes * ph) * std::sin(th);
        float z = 0.5f * H * (1.f - std::cos(th));
        z -= 0.012f * std::exp(-std::pow((kPi - th) / 0.5f, 2.f));
        z += 0.01f * std::exp(-std::pow(th / 0.4f, 2.f)) * (0.5f + 0.5f * std::cos(lobes * ph));
        return V3(R * k * prof * std::cos(ph), R * k * prof * std::sin(ph), z);
      },
      48, 24);
  static const cv::Vec3f kCols[] = {
      {0.1f, 0.1f, 0.75f}, {0.1f, 0.75f, 0.9f}, {0.15f, 0.55f, 0.2f}, {0.1f, 0.45f, 0.9f}};
  b.add(std::move(m), tex(skinTexture(r, "pepper", 256, 128, kCols[r.range(0, 3)])), 0.5f, 6);
  std::vector<V3> stem{{0, 0, H - 0.014f}, {0, 0, H - 0.004f}, {0.004f, 0, H + 0.008f}};
  b.add(sweep(
            stem, [](float t) { return 0.005f - 0.002f * t; }, 8, true),
        tex(plasticTexture(r, 16, 16, {0.15f, 0.45f, 0.25f})), 0.1f, 3);
}

void makeBinder(Builder& b) {
  Rng& r = b.rng;
  const V3 size(r.uniformf(0.26f, 0.32f), r.uniformf(0.27f, 0.31f), r.uniformf(0.03f, 0.07f));
  const cv::Vec3f col = anyColor(r, 0.2f, 0.9f, 0.15f, 0.9f);
  const BoxAtlas a = boxAtlasLayout(size);
  const int w = 1024,
            h = static_cast<int>(1024.f * (size.z() + 2 * size.y()) / (2 * (size.x() + size.y())));
  cv::Mat t = plasticTexture(r, w, h, col, 0.05f);
  // Cover on top, a label window on the spine (the -x side).
  const cv::Rect top(0, 0, static_cast<int>(a.top[2] * w), static_cast<int>(a.top[3] * h));
  cv::Mat cover = coverTexture(r, top.width, top.height, col);
  cover.copyTo(t(top));
  const cv::Rect spine(static_cast<int>(a.left[0] * w) + 10, static_cast<int>(a.left[1] * h) + 2,
                       static_cast<int>((a.left[2] - a.left[0]) * w) - 20,
                       static_cast<int>((a.left[3] - a.left[1]) * h) - 4);
  if (spine.width > 8 && spine.height > 4) {
    cv::rectangle(t, spine, cv::Scalar(240, 240, 240), -1);
    cv::putText(t, pseudoWord(r, 3, true), cv::Point(spine.x + 4, spine.y + spine.height * 3 / 4),
                cv::FONT_HERSHEY_SIMPLEX, std::max(0.2, spine.height / 40.0),
                cv::Scalar(30, 30, 30), 1, cv::LINE_AA);
  }
  Mesh m = box(size);
  m.transform(translation(0, 0, size.z() / 2));
  b.add(std::move(m), tex(t, false, false), 0.15f, 5);
}

// A box whose top face shows `top` (e.g. keys) and whose sides are `side` coloured plastic.
void boxWithTop(Builder& b, const V3& size, const cv::Mat& top, const cv::Vec3f& side, float spec,
                const Eigen::Affine3f& T) {
  const BoxAtlas a = boxAtlasLayout(size);
  const float U = 2 * (size.x() + size.y()), Vv = size.z() + 2 * size.y();
  const int w = 1024, h = std::max(32, static_cast<int>(1024.f * Vv / U));
  cv::Mat t = plasticTexture(b.rng, w, h, side, 0.05f);
  const cv::Rect tr(0, 0, std::max(1, static_cast<int>(a.top[2] * w)),
                    std::max(1, static_cast<int>(a.top[3] * h)));
  cv::Mat resized;
  cv::resize(top, resized, tr.size(), 0, 0, cv::INTER_AREA);
  resized.copyTo(t(tr));
  Mesh m = box(size);
  m.transform(T * translation(0, 0, size.z() / 2));
  b.add(std::move(m), tex(t, false, false), spec, 5);
}

void makeCalculator(Builder& b) {
  Rng& r = b.rng;
  const V3 size(r.uniformf(0.075f, 0.1f), r.uniformf(0.13f, 0.18f), r.uniformf(0.012f, 0.025f));
  const cv::Vec3f body =
      r.chance(0.6) ? cv::Vec3f(0.15f, 0.15f, 0.16f) : anyColor(r, 0.f, 0.3f, 0.3f, 0.9f);
  const int tw = 300, th = static_cast<int>(300.f * size.y() / size.x());
  cv::Mat top = keysTexture(r, tw, th, 5, 8, body, anyColor(r, 0.f, 0.3f, 0.2f, 0.95f), true);
  // The display in the upper quarter (the -y edge is the bottom of the top face's image).
  cv::Mat scr = screenTexture(r, tw * 4 / 5, th / 6, false);
  scr.copyTo(top(cv::Rect(tw / 10, th / 24, scr.cols, scr.rows)));
  cv::rectangle(top, cv::Rect(0, 0, tw, th / 4), cv::Scalar(0, 0, 0), 0);
  boxWithTop(b, size, top, body, 0.2f, Eigen::Affine3f::Identity());
}

void makeCamera(Builder& b) {
  Rng& r = b.rng;
  const V3 size(r.uniformf(0.095f, 0.13f), r.uniformf(0.03f, 0.05f), r.uniformf(0.058f, 0.08f));
  const cv::Vec3f body =
      r.chance(0.6) ? cv::Vec3f(0.08f, 0.08f, 0.09f) : anyColor(r, 0.f, 0.3f, 0.5f, 0.85f);
  // A plain body with a brand word and a strap lug on the front face.
  const BoxAtlas a = boxAtlasLayout(size);
  cv::Mat bt = plasticTexture(r, 512, 256, body, 0.06f);
  const cv::Scalar ink = body[0] < 0.4f ? cv::Scalar(225, 225, 225) : cv::Scalar(25, 25, 25);
  cv::putText(bt, pseudoWord(r, 2, true),
              cv::Point(static_cast<int>(a.front[0] * 512) + 8,
                        static_cast<int>((0.75f * a.front[1] + 0.25f * a.front[3]) * 256)),
              cv::FONT_HERSHEY_DUPLEX, 0.6, ink, 1, cv::LINE_AA);
  cv::rectangle(bt, cv::Point(static_cast<int>(a.top[0] * 512) + 20, 8),
                cv::Point(static_cast<int>(a.top[2] * 512) - 60, 20), ink, -1);
  Mesh body_mesh = box(size);
  body_mesh.transform(translation(0, 0, size.z() / 2));
  b.add(std::move(body_mesh), tex(bt, false, false), 0.3f, 5);
  // Lens: a stepped cylinder on the front (-y).
  const float LR = r.uniformf(0.018f, 0.028f), LL = r.uniformf(0.015f, 0.05f);
  std::vector<ProfilePoint> lens{{0, 0},
                                 {LR, 0, true},
                                 {LR, LL * 0.6f, true},
                                 {LR * 0.9f, LL * 0.62f, true},
                                 {LR * 0.9f, LL, true},
                                 {LR * 0.6f, LL, true},
                                 {0, LL - 0.003f}};
  Mesh lm = lathe(lens, 32);
  lm.transform(translation(r.uniformf(-0.015f, 0.015f), -size.y() / 2, size.z() * 0.5f) *
               rotationX(kPi / 2));
  cv::Mat lt = metalTexture(r, 256, 64, {0.12f, 0.12f, 0.13f}, false);
  for (int x = 0; x < 256; x += 4)
    cv::line(lt, cv::Point(x, 20), cv::Point(x, 34), cv::Scalar(60, 60, 60), 1);
  b.add(std::move(lm), tex(lt), 0.4f, 6);
  // Shutter button.
  std::vector<ProfilePoint> btn{{0, 0}, {0.005f, 0, true}, {0.005f, 0.004f, true}, {0, 0.004f}};
  Mesh bm = lathe(btn, 12);
  bm.transform(translation(size.x() * 0.3f, 0, size.z()));
  b.add(std::move(bm), tex(metalTexture(r, 16, 16, {0.7f, 0.7f, 0.72f}, false)), 0.5f, 6);
}

void makePhone(Builder& b) {
  Rng& r = b.rng;
  const bool smart = r.chance(0.7);
  const V3 size =
      smart ? V3(r.uniformf(0.065f, 0.078f), r.uniformf(0.13f, 0.16f), r.uniformf(0.007f, 0.01f))
            : V3(r.uniformf(0.045f, 0.052f), r.uniformf(0.1f, 0.12f), r.uniformf(0.013f, 0.02f));
  const cv::Vec3f body =
      r.chance(0.5) ? cv::Vec3f(0.1f, 0.1f, 0.1f) : anyColor(r, 0.f, 0.4f, 0.3f, 0.9f);
  const int tw = 200, th = static_cast<int>(200.f * size.y() / size.x());
  cv::Mat top = plasticTexture(r, tw, th, body, 0.03f);
  if (smart) {
    cv::Mat scr = screenTexture(r, tw * 9 / 10, th * 8 / 10, true);
    scr.copyTo(top(cv::Rect(tw / 20, th / 10, scr.cols, scr.rows)));
  } else {
    cv::Mat scr = screenTexture(r, tw * 4 / 5, th * 3 / 10, true);
    scr.copyTo(top(cv::Rect(tw / 10, th / 12, scr.cols, scr.rows)));
    cv::Mat keys =
        keysTexture(r, tw * 4 / 5, th / 2, 3, 5, body, anyColor(r, 0.f, 0.2f, 0.5f, 0.9f), true);
    keys.copyTo(top(cv::Rect(tw / 10, th * 9 / 20, keys.cols, keys.rows)));
  }
  boxWithTop(b, size, top, body, 0.45f, Eigen::Affine3f::Identity());
}

void makeComb(Builder& b) {
  Rng& r = b.rng;
  const float L = r.uniformf(0.12f, 0.2f), W = r.uniformf(0.025f, 0.04f),
              T = r.uniformf(0.003f, 0.005f);
  const int teeth = static_cast<int>(L / r.uniformf(0.0025f, 0.004f));
  const float spine = W * r.uniformf(0.25f, 0.4f);
  std::vector<V2> poly{{-L / 2, W / 2}, {-L / 2, W / 2 - spine - W * 0.1f}};
  const float step = L / static_cast<float>(teeth);
  for (int i = 0; i < teeth; ++i) {
    const float x = -L / 2 + step * static_cast<float>(i);
    poly.push_back({x + step * 0.1f, -W / 2});
    poly.push_back({x + step * 0.5f, -W / 2});
    poly.push_back({x + step * 0.55f, W / 2 - spine});
    poly.push_back({x + step * 1.f, W / 2 - spine});
  }
  poly.push_back({L / 2, W / 2});
  polygonCcw(poly);
  const cv::Vec3f col = anyColor(r, 0.f, 0.8f, 0.05f, 0.8f);
  b.add(extrude(poly, 0, T, 10.f), tex(plasticTexture(r, 64, 64, col, 0.05f)), 0.3f, 5);
}

void makeBattery(Builder& b) {
  Rng& r = b.rng;
  const int kind = r.range(0, 3);
  const float R = kind == 0 ? 0.007f : kind == 1 ? 0.0125f : kind == 2 ? 0.0165f : 0.005f;
  const float L = kind == 0 ? 0.05f : kind == 1 ? 0.05f : kind == 2 ? 0.061f : 0.0445f;
  std::vector<ProfilePoint> prof{{0, 0, false, 0},
                                 {R * 0.9f, 0, true, 0.01f},
                                 {R, 0.001f, true, 0.02f},
                                 {R, L - 0.001f, true, 0.97f},
                                 {R * 0.9f, L, true, 0.98f},
                                 {R * 0.35f, L, true, 0.985f},
                                 {R * 0.35f, L + 0.0015f, true, 0.99f},
                                 {0, L + 0.0015f, false, 1.f}};
  cv::Mat t = labelTexture(r, 256, 128, r.uniformf(0.f, 360.f));
  const cv::Scalar tip = r.chance(0.5) ? cv::Scalar(30, 140, 200) : cv::Scalar(20, 20, 20);
  cv::rectangle(t, cv::Point(0, 0), cv::Point(256, 30), tip, -1);
  Mesh m = lathe(prof, 24);
  if (r.chance(0.6)) {  // lying on its side
    m.transform(translation(0, 0, R) * rotationY(kPi / 2) * translation(0, 0, -L / 2));
  }
  b.add(std::move(m), tex(t), 0.35f, 6);
}

void makeFlashlight(Builder& b) {
  Rng& r = b.rng;
  const float R = r.uniformf(0.012f, 0.02f), L = r.uniformf(0.12f, 0.24f),
              head = R * r.uniformf(1.1f, 1.6f);
  std::vector<ProfilePoint> prof{{0, 0},          {R, 0, true},
                                 {R, L * 0.7f},   {head, L * 0.82f},
                                 {head, L, true}, {head * 0.85f, L, true},
                                 {0, L - 0.002f}};
  Mesh m = lathe(prof, 32);
  m.transform(translation(0, 0, head) * rotationY(kPi / 2) * translation(0, 0, -L / 2));
  const cv::Vec3f col =
      r.chance(0.5) ? cv::Vec3f(0.1f, 0.1f, 0.1f) : anyColor(r, 0.3f, 0.9f, 0.3f, 0.9f);
  cv::Mat t = metalTexture(r, 256, 256, col, r.chance(0.5));
  for (int y = 120; y < 200; y += 6)
    cv::line(t, cv::Point(0, y), cv::Point(256, y), cv::Scalar(40, 40, 40), 2);  // grip
  cv::putText(t, pseudoWord(r, 2, true), cv::Point(40, 100), cv::FONT_HERSHEY_SIMPLEX, 0.6,
              cv::Scalar(230, 230, 230), 1, cv::LINE_AA);
  b.add(std::move(m), tex(t), 0.45f, 6);
}

void makeFoodBag(Builder& b) {
  Rng& r = b.rng;
  const V3 half(r.uniformf(0.08f, 0.13f), r.uniformf(0.1f, 0.16f), r.uniformf(0.02f, 0.04f));
  Mesh m = superquadric(half, r.uniformf(0.15f, 0.3f), r.uniformf(0.5f, 0.8f), 40, 20);
  const uint32_t seed = static_cast<uint32_t>(r.next());
  for (auto& v : m.vertices) {  // crinkles
    v.p.z() += 0.003f * gradientNoise(v.p.x() * 60.f, v.p.y() * 60.f, seed) *
               (std::fabs(v.p.z()) > 0.3f * half.z() ? 1.f : 0.f);
  }
  m.transform(translation(0, 0, half.z()));
  // Print projected from above onto both faces.
  m.planarUv(V3(0.5f / half.x(), 0, 0), 0.5f, V3(0, -0.5f / half.y(), 0), 0.5f);
  const int w = 512, h = static_cast<int>(512.f * half.y() / half.x());
  cv::Mat t = packagingTexture(r, w, h, r.uniformf(0.f, 360.f),
                               cv::Rect(w / 10, h / 10, w * 4 / 5, h * 4 / 5), true);
  b.add(std::move(m), tex(t, false, false), 0.45f, 6);
}

void makeFoodBox(Builder& b) {
  Rng& r = b.rng;
  const V3 size(r.uniformf(0.1f, 0.2f), r.uniformf(0.03f, 0.08f), r.uniformf(0.08f, 0.2f));
  if (r.chance(0.4)) {  // lying on its back
    printedBox(b, size, r.uniformf(0.f, 360.f), true,
               translation(0, 0, size.y() / 2 - size.z() / 2) * rotationX(-kPi / 2));
  } else {
    printedBox(b, size, r.uniformf(0.f, 360.f), true, Eigen::Affine3f::Identity());
  }
}

void makeFoodCup(Builder& b, bool noodles) {
  Rng& r = b.rng;
  const float Rt = noodles ? r.uniformf(0.045f, 0.055f) : r.uniformf(0.033f, 0.048f);
  const float Rb = Rt * r.uniformf(0.65f, 0.8f),
              H = noodles ? r.uniformf(0.085f, 0.11f) : r.uniformf(0.05f, 0.09f);
  std::vector<ProfilePoint> prof{{0, 0, false, 0},
                                 {Rb, 0, true, 0.02f},
                                 {Rt, H - 0.004f, false, 0.92f},
                                 {Rt + 0.003f, H - 0.002f, true, 0.95f},
                                 {Rt + 0.003f, H, true, 0.97f},
                                 {0, H + 0.001f, false, 1.f}};
  const int w = 512, h = std::clamp(static_cast<int>(512.f * H / (2 * kPi * Rt)), 64, 512);
  cv::Mat t = labelTexture(r, w, h, r.uniformf(0.f, 360.f));
  b.add(lathe(prof, 40), tex(t), 0.25f, 5);
}

void makeJar(Builder& b) {
  Rng& r = b.rng;
  const float R = r.uniformf(0.03f, 0.045f), H = r.uniformf(0.08f, 0.14f),
              neck = R * r.uniformf(0.75f, 0.95f);
  const float lid = r.uniformf(0.012f, 0.02f);
  std::vector<ProfilePoint> body{{0, 0, false, 0},
                                 {R * 0.95f, 0, true, 0.02f},
                                 {R, 0.006f, false, 0.05f},
                                 {R, H - lid - 0.015f, false, 0.85f},
                                 {neck, H - lid - 0.003f, true, 0.95f},
                                 {0, H - lid - 0.003f, false, 1.f}};
  const int w = 512, h = std::clamp(static_cast<int>(512.f * H / (2 * kPi * R)), 64, 512);
  cv::Mat t = labelTexture(r, w, h, r.uniformf(0.f, 360.f));
  // Contents seen through the glass above and below the label.
  const cv::Vec3f contents = anyColor(r, 0.3f, 0.9f, 0.15f, 0.7f);
  cv::Mat glass = plasticTexture(r, w, h, contents, 0.1f);
  glass(cv::Rect(0, 0, w, h / 6)).copyTo(t(cv::Rect(0, 0, w, h / 6)));
  glass(cv::Rect(0, h * 5 / 6, w, h - h * 5 / 6))
      .copyTo(t(cv::Rect(0, h * 5 / 6, w, h - h * 5 / 6)));
  b.add(lathe(body, 40), tex(t), 0.5f, 6);
  std::vector<ProfilePoint> cap{{0, H - lid - 0.004f},
                                {neck + 0.002f, H - lid - 0.004f, true},
                                {neck + 0.002f, H, true},
                                {0, H}};
  const uint32_t ribs = static_cast<uint32_t>(r.range(20, 60));
  Mesh cm = lathe(cap, 48, 1.f, [&](float ph, float) {
    return 1.f + 0.015f * std::cos(static_cast<float>(ribs) * ph);
  });
  b.add(std::move(cm), tex(metalTexture(r, 128, 64, anyColor(r, 0.f, 0.8f, 0.3f, 0.9f), false)),
        0.5f, 6);
}

void makeGarlic(Builder& b) {
  Rng& r = b.rng;
  const float R = r.uniformf(0.024f, 0.034f), H = r.uniformf(0.04f, 0.056f);
  const int cloves = r.range(7, 12);
  Mesh m = parametricSphere(
      [&](float s, float t) {
        const float th = kPi * t, ph = 2 * kPi * s;
        const float prof = std::sin(th) * (1.f - 0.35f * std::pow(t, 2.f));
        const float k = 1.f + 0.06f * std::fabs(std::cos(cloves * ph / 2)) * std::sin(th);
        float z = 0.5f * H * (1.f - std::cos(th));
        z += 0.012f * std::pow(std::max(0.f, t - 0.7f) / 0.3f, 2.f);  // pointed top
        return V3(R * k * prof * std::cos(ph), R * k * prof * std::sin(ph), z);
      },
      48, 24);
  b.add(std::move(m), tex(skinTexture(r, "garlic", 256, 128, {0.88f, 0.9f, 0.92f})), 0.1f, 3);
}

void makeGlueStick(Builder& b) {
  Rng& r = b.rng;
  const float R = r.uniformf(0.008f, 0.015f), L = r.uniformf(0.06f, 0.1f),
              cap = L * r.uniformf(0.25f, 0.35f);
  std::vector<ProfilePoint> prof{{0, 0, false, 0},
                                 {R, 0, true, 0.02f},
                                 {R, L - cap, true, 0.7f},
                                 {R * 1.06f, L - cap, true, 0.72f},
                                 {R * 1.06f, L, true, 0.97f},
                                 {0, L, false, 1.f}};
  cv::Mat t = labelTexture(r, 256, 256, r.uniformf(0.f, 360.f));
  const cv::Vec3f capc = anyColor(r, 0.5f, 1.f, 0.4f, 0.9f);
  cv::rectangle(t, cv::Point(0, 0), cv::Point(256, static_cast<int>(256 * 0.28f)),
                cv::Scalar(255 * capc[0], 255 * capc[1], 255 * capc[2]), -1);
  b.add(lathe(prof, 24), tex(t), 0.3f, 5);
}

void makeGreens(Builder& b) {
  Rng& r = b.rng;
  const int leaves = r.range(4, 8);
  const float L = r.uniformf(0.12f, 0.22f);
  const cv::Vec3f col =
      hsvColor(r.uniformf(85.f, 130.f), r.uniformf(0.5f, 0.85f), r.uniformf(0.35f, 0.7f));
  TexturePtr t = tex(skinTexture(r, "greens", 128, 128, col));
  for (int i = 0; i < leaves; ++i) {
    const float len = L * r.uniformf(0.7f, 1.f), wid = len * r.uniformf(0.2f, 0.35f),
                ang = r.uniformf(-0.5f, 0.5f);
    Mesh leaf = roundBody(1.f, 1.f, nullptr, 16, 10);
    const float curl = r.uniformf(0.02f, 0.06f);
    leaf.transform(scaling(len / 2, wid / 2, 0.006f));
    for (auto& v : leaf.vertices)
      v.p.z() +=
          curl * (v.p.y() / wid) * (v.p.y() / wid) * 4.f + 0.01f * std::pow(v.p.x() / len * 2, 2.f);
    leaf.transform(translation(0, 0, 0.004f * static_cast<float>(i)) * rotationZ(ang) *
                   translation(len / 2, 0, 0));
    b.add(std::move(leaf), t, 0.2f, 4);
  }
}

void makeTowel(Builder& b) {
  Rng& r = b.rng;
  const V3 half(r.uniformf(0.08f, 0.15f), r.uniformf(0.05f, 0.1f), r.uniformf(0.012f, 0.028f));
  Mesh m = superquadric(half, 0.15f, 0.35f, 40, 16);
  m.transform(translation(0, 0, half.z()));
  const cv::Vec3f col = anyColor(r, 0.f, 0.7f, 0.4f, 0.95f);
  cv::Mat t = fabricTexture(r, 512, 256, col, false, 2.f);
  if (r.chance(0.6)) {
    const int y = r.range(40, 200);
    cv::rectangle(t, cv::Point(0, y), cv::Point(512, y + r.range(8, 30)),
                  cv::Scalar(255 * (1 - col[0]), 255 * (1 - col[1]), 255 * (1 - col[2])) * 0.7, -1);
  }
  b.add(std::move(m), tex(t), 0.02f, 2);
}

void makeKeyboard(Builder& b) {
  Rng& r = b.rng;
  const V3 size(r.uniformf(0.3f, 0.44f), r.uniformf(0.11f, 0.16f), r.uniformf(0.018f, 0.03f));
  const cv::Vec3f body =
      r.chance(0.7) ? cv::Vec3f(0.1f, 0.1f, 0.11f) : cv::Vec3f(0.85f, 0.86f, 0.86f);
  const cv::Vec3f key =
      body[0] < 0.5f ? cv::Vec3f(0.16f, 0.16f, 0.17f) : cv::Vec3f(0.95f, 0.95f, 0.95f);
  cv::Mat top = keysTexture(r, 1024, static_cast<int>(1024.f * size.y() / size.x()),
                            r.range(16, 22), 6, body, key, true);
  boxWithTop(b, size, top, body, 0.15f, Eigen::Affine3f::Identity());
  // A wedge: raise the back edge.
  for (auto& v : b.model.parts.back().mesh.vertices)
    if (v.p.z() > size.z() * 0.5f) v.p.z() += 0.01f * (v.p.y() / size.y() + 0.5f);
}

void makeKleenex(Builder& b) {
  Rng& r = b.rng;
  const bool cube = r.chance(0.4);
  const V3 size =
      cube ? V3(r.uniformf(0.11f, 0.12f), r.uniformf(0.11f, 0.12f), r.uniformf(0.12f, 0.135f))
           : V3(r.uniformf(0.22f, 0.25f), r.uniformf(0.11f, 0.125f), r.uniformf(0.06f, 0.095f));
  printedBox(b, size, r.uniformf(0.f, 360.f), false, Eigen::Affine3f::Identity());
  // A tissue poking out of the top.
  const uint32_t seed = static_cast<uint32_t>(r.next());
  Mesh tissue = superquadric(V3(size.x() * 0.2f, size.y() * 0.12f, r.uniformf(0.02f, 0.04f)), 0.5f,
                             0.6f, 20, 12);
  for (auto& v : tissue.vertices)
    v.p += 0.006f * V3(gradientNoise(v.p.x() * 80, v.p.y() * 80, seed),
                       gradientNoise(v.p.y() * 80, v.p.z() * 80, seed + 1),
                       gradientNoise(v.p.z() * 80, v.p.x() * 80, seed + 2));
  tissue.transform(translation(0, 0, size.z()));
  b.add(std::move(tissue), tex(fabricTexture(r, 64, 64, {0.95f, 0.95f, 0.96f}, false, 5.f)), 0.02f,
        2);
}

void makeCitrus(Builder& b, const std::string& kind) {
  Rng& r = b.rng;
  const bool lemon = kind == "lemon";
  const float R = kind == "orange" ? r.uniformf(0.034f, 0.045f)
                  : lemon          ? r.uniformf(0.025f, 0.032f)
                                   : r.uniformf(0.021f, 0.028f);
  const float elong = lemon            ? r.uniformf(1.3f, 1.55f)
                      : kind == "lime" ? r.uniformf(1.0f, 1.15f)
                                       : r.uniformf(0.9f, 1.0f);
  const float tip = lemon ? r.uniformf(0.12f, 0.25f) : 0.02f;
  Mesh m = parametricSphere(
      [&](float s, float t) {
        const float th = kPi * t, ph = 2 * kPi * s;
        const float tipk = 1.f + tip * (std::exp(-std::pow(th / 0.25f, 2.f)) +
                                        std::exp(-std::pow((kPi - th) / 0.25f, 2.f)));
        return V3(R * std::sin(th) * std::cos(ph), R * std::sin(th) * std::sin(ph),
                  -R * elong * tipk * std::cos(th));
      },
      40, 24);
  // Lemons and limes lie along x.
  if (lemon || kind == "lime") m.transform(rotationY(kPi / 2));
  const cv::Vec3f col = kind == "orange" ? cv::Vec3f(0.1f, 0.5f, 0.95f)
                        : lemon          ? cv::Vec3f(0.15f, 0.85f, 0.95f)
                                         : cv::Vec3f(0.2f, 0.7f, 0.35f);
  b.add(std::move(m), tex(skinTexture(r, kind, 256, 128, col)), 0.3f, 5);
}

void makeLightbulb(Builder& b) {
  Rng& r = b.rng;
  const float R = r.uniformf(0.027f, 0.034f), base = r.uniformf(0.012f, 0.014f),
              bl = r.uniformf(0.022f, 0.028f);
  std::vector<ProfilePoint> prof{
      {0, 0, false, 1.f}, {base * 0.5f, 0, true, 0.99f}, {base * 0.8f, 0.004f, true, 0.97f}};
  for (int i = 0; i < 5; ++i) {  // screw threads
    prof.push_back({base, 0.004f + bl * (0.1f + 0.18f * static_cast<float>(i)), false, 0.9f});
    prof.push_back(
        {base * 0.9f, 0.004f + bl * (0.19f + 0.18f * static_cast<float>(i)), false, 0.9f});
  }
  const float z0 = 0.004f + bl;
  prof.push_back({base * 1.02f, z0, true, 0.8f});
  for (int i = 0; i <= 14; ++i) {
    const float a = -0.6f + (kPi / 2 + 0.6f) * static_cast<float>(i) / 14.f;
    prof.push_back({R * std::cos(a) * (i == 0 ? 0.7f : 1.f), z0 + R * 0.9f + R * std::sin(a), false,
                    0.8f - 0.8f * static_cast<float>(i) / 14.f});
  }
  for (auto& p : prof) p.v = 1.f - p.v;
  prof.back().r = 0;
  cv::Mat t = plasticTexture(r, 128, 256, {0.93f, 0.94f, 0.95f}, 0.02f);
  cv::rectangle(t, cv::Point(0, 200), cv::Point(128, 256), cv::Scalar(170, 175, 180), -1);
  Mesh m = lathe(prof, 32);
  m.transform(translation(0, 0, R) * rotationY(kPi / 2) * translation(0, 0, -(z0 + R)));
  b.add(std::move(m), tex(t), 0.6f, 6);
}

void makeMarker(Builder& b) {
  Rng& r = b.rng;
  const float R = r.uniformf(0.006f, 0.0095f), L = r.uniformf(0.11f, 0.14f),
              cap = L * r.uniformf(0.3f, 0.4f);
  std::vector<ProfilePoint> prof{{0, 0, false, 0},
                                 {R * 0.8f, 0, true, 0.01f},
                                 {R, 0.004f, false, 0.03f},
                                 {R, L - cap, true, 0.6f},
                                 {R * 1.1f, L - cap, true, 0.62f},
                                 {R * 1.1f, L - 0.004f, false, 0.97f},
                                 {R * 0.7f, L, true, 0.99f},
                                 {0, L, false, 1.f}};
  const cv::Vec3f ink = anyColor(r, 0.6f, 1.f, 0.3f, 0.9f);
  cv::Mat t = labelTexture(r, 256, 128, r.uniformf(0.f, 360.f));
  cv::rectangle(t, cv::Point(0, 0), cv::Point(256, static_cast<int>(128 * 0.4f)),
                cv::Scalar(255 * ink[0], 255 * ink[1], 255 * ink[2]), -1);
  Mesh m = lathe(prof, 20);
  m.transform(translation(0, 0, R * 1.1f) * rotationY(kPi / 2) * translation(0, 0, -L / 2));
  b.add(std::move(m), tex(t), 0.35f, 5);
}

void makeMushroom(Builder& b) {
  Rng& r = b.rng;
  const float Rc = r.uniformf(0.02f, 0.038f), Hs = r.uniformf(0.015f, 0.03f),
              Rs = Rc * r.uniformf(0.3f, 0.45f), Hc = Rc * r.uniformf(0.6f, 0.9f);
  std::vector<ProfilePoint> prof{{0, 0, false, 0},
                                 {Rs, 0, true, 0.05f},
                                 {Rs * 0.9f, Hs, true, 0.3f},
                                 {Rc * 0.9f, Hs + 0.004f, true, 0.35f}};
  for (int i = 0; i <= 10; ++i) {
    const float a = kPi / 2 * static_cast<float>(i) / 10.f;
    prof.push_back({Rc * std::cos(a), Hs + 0.004f + Hc * std::sin(a), false,
                    0.4f + 0.6f * static_cast<float>(i) / 10.f});
  }
  prof.back().r = 0;
  const cv::Vec3f col = r.chance(0.6) ? cv::Vec3f(0.85f, 0.88f, 0.9f)
                                      : hsvColor(r.uniformf(20.f, 35.f), r.uniformf(0.3f, 0.6f),
                                                 r.uniformf(0.35f, 0.6f));
  b.add(lathe(prof, 32), tex(skinTexture(r, "mushroom", 128, 128, col)), 0.1f, 3);
}

void makeNotebook(Builder& b) {
  Rng& r = b.rng;
  const V3 size(r.uniformf(0.14f, 0.21f), r.uniformf(0.2f, 0.3f), r.uniformf(0.005f, 0.018f));
  const cv::Vec3f col = anyColor(r, 0.2f, 0.9f, 0.2f, 0.9f);
  cv::Mat top = coverTexture(r, 512, static_cast<int>(512.f * size.y() / size.x()), col);
  boxWithTop(b, size, top, {0.9f, 0.92f, 0.93f}, 0.1f, Eigen::Affine3f::Identity());
}

void makeOnion(Builder& b) {
  Rng& r = b.rng;
  const float R = r.uniformf(0.03f, 0.045f), H = R * r.uniformf(1.6f, 2.1f);
  Mesh m = parametricSphere(
      [&](float s, float t) {
        const float th = kPi * t, ph = 2 * kPi * s;
        const float prof =
            std::sin(th) * (1.f - 0.4f * std::pow(std::max(0.f, t - 0.55f) / 0.45f, 1.5f));
        float z = 0.5f * H * 0.85f * (1.f - std::cos(th));
        z += 0.15f * H * std::pow(std::max(0.f, t - 0.6f) / 0.4f, 2.f);
        return V3(R * prof * std::cos(ph), R * prof * std::sin(ph), z);
      },
      40, 28);
  static const cv::Vec3f kCols[] = {
      {0.3f, 0.55f, 0.75f}, {0.45f, 0.2f, 0.5f}, {0.85f, 0.88f, 0.9f}};
  b.add(std::move(m), tex(skinTexture(r, "onion", 256, 128, kCols[r.range(0, 2)])), 0.15f, 4);
}

void makePeach(Builder& b) {
  Rng& r = b.rng;
  const float R = r.uniformf(0.03f, 0.04f);
  const float crease = r.uniformf(0.04f, 0.08f);
  Mesh m = roundBody(R, 2 * R * r.uniformf(0.9f, 1.f), [&](float th, float ph) {
    return 1.f -
           crease * std::exp(-std::pow(std::fabs(std::sin(ph / 2)) / 0.12f, 2.f)) * std::sin(th);
  });
  b.add(std::move(m), tex(skinTexture(r, "peach", 256, 128, {0.35f, 0.7f, 0.95f})), 0.05f, 3);
}

void makePear(Builder& b) {
  Rng& r = b.rng;
  const float R = r.uniformf(0.03f, 0.04f), H = r.uniformf(0.08f, 0.11f),
              neck = r.uniformf(0.35f, 0.5f);
  auto rad = [&](float t) {
    const float bottom = t < 0.4f ? std::pow(std::sin(t / 0.4f * kPi / 2), 0.55f) : 1.f;
    const float top = 1.f - (1.f - neck) * smoothstep(0.3f, 0.85f, t);
    const float tip = t > 0.95f ? std::sqrt((1.f - t) / 0.05f) : 1.f;
    return R * bottom * top * tip;
  };
  std::vector<ProfilePoint> prof = sampled(30, rad, [&](float t) { return H * t; });
  prof.front().r = 0;
  prof.back().r = 0;
  static const cv::Vec3f kCols[] = {{0.2f, 0.7f, 0.55f}, {0.2f, 0.75f, 0.85f}, {0.2f, 0.45f, 0.6f}};
  b.add(lathe(prof, 40), tex(skinTexture(r, "pear", 256, 128, kCols[r.range(0, 2)])), 0.2f, 4);
  std::vector<V3> stem{{0, 0, H - 0.002f}, {0.002f, 0, H + 0.01f}, {0.005f, 0, H + 0.018f}};
  b.add(sweep(
            stem, [](float) { return 0.0018f; }, 6, true),
        tex(plasticTexture(r, 16, 16, {0.1f, 0.2f, 0.3f})), 0.05f, 3);
}

void makePitcher(Builder& b) {
  Rng& r = b.rng;
  const float R = r.uniformf(0.05f, 0.075f), H = r.uniformf(0.15f, 0.22f), th = 0.005f,
              waist = r.uniformf(0.8f, 1.f);
  auto outer = [&](float t) {
    return R * (1.f - (1.f - waist) * std::sin(t * kPi)) * (0.9f + 0.1f * t);
  };
  std::vector<ProfilePoint> prof{{0, 0}, {outer(0) * 0.95f, 0, true}};
  for (int i = 1; i <= 12; ++i)
    prof.push_back({outer(static_cast<float>(i) / 12.f), H * static_cast<float>(i) / 12.f});
  prof.back().crease = true;
  for (int i = 12; i >= 1; --i)
    prof.push_back({outer(static_cast<float>(i) / 12.f) - th,
                    H * static_cast<float>(i) / 12.f - (i == 12 ? 0.0005f : 0.f)});
  prof[prof.size() - 12].crease = true;
  prof.push_back({0, th});
  // Spout at phi = 0 near the top.
  Mesh m = lathe(prof, 48);
  for (auto& v : m.vertices) {
    const float ph = std::atan2(v.p.y(), v.p.x());
    const float k = std::pow(std::max(0.f, std::cos(ph)), 12.f) * smoothstep(0.7f * H, H, v.p.z());
    v.p.x() += 0.025f * k;
  }
  const cv::Vec3f col = ceramicColor(r);
  cv::Mat t = ceramicTexture(r, 512, 256, col, pattern(r));
  plainInside(r, t, col, arcFraction(prof, 13));
  b.add(std::move(m), tex(t), 0.3f, 5);
  const float d = R * 0.55f, hh = H * 0.6f, zm = H * 0.55f;
  std::vector<V3> curve;
  for (int i = 0; i <= 20; ++i) {
    const float s = static_cast<float>(i) / 20.f;
    curve.push_back({-(outer(zm / H) - 0.004f + d * std::sin(s * kPi)), 0.f,
                     zm + 0.5f * hh * std::cos(s * kPi)});
  }
  b.add(sweep(
            curve, [](float) { return 0.008f; }, 12, true, 0.6f, V3::UnitY()),
        tex(plasticTexture(r, 64, 64, col, 0.03f)), 0.3f, 5);
}

void makePlate(Builder& b) {
  Rng& r = b.rng;
  const float R = r.uniformf(0.09f, 0.135f), H = r.uniformf(0.014f, 0.025f),
              well = R * r.uniformf(0.55f, 0.7f), th = 0.004f;
  std::vector<ProfilePoint> prof{
      {0, 0.f},     {well * 0.7f, 0.f, true}, {well * 0.75f, 0.004f, true}, {well, 0.004f},
      {R, H, true}, {R - 0.003f, H, true},    {well - 0.002f, 0.004f + th}, {0, 0.004f + th}};
  const cv::Vec3f col = ceramicColor(r);
  b.add(lathe(prof, 64), tex(ceramicTexture(r, 512, 128, col, pattern(r))), 0.3f, 5);
}

void makePliers(Builder& b) {
  Rng& r = b.rng;
  const float L = r.uniformf(0.14f, 0.2f), T = r.uniformf(0.008f, 0.012f),
              spread = r.uniformf(0.015f, 0.03f);
  const cv::Vec3f grip = anyColor(r, 0.6f, 1.f, 0.3f, 0.85f);
  TexturePtr metal = tex(metalTexture(r, 64, 64, {0.55f, 0.56f, 0.58f}, true));
  TexturePtr gt = tex(plasticTexture(r, 64, 64, grip, 0.06f));
  const float head = L * 0.35f;
  for (int side = -1; side <= 1; side += 2) {
    const float s = static_cast<float>(side);
    // Jaw: from the pivot to the nose.
    std::vector<V2> jaw{{0, 0}, {head, s * 0.002f}, {head, s * 0.006f}, {0, s * 0.012f}};
    polygonCcw(jaw);
    b.add(extrude(jaw, 0, T, 20.f), metal, 0.5f, 6);
    // Handle: from the pivot backwards, spreading out.
    std::vector<V2> handle{{0, s * 0.001f},
                           {0, s * 0.011f},
                           {-(L - head), s * (spread + 0.012f)},
                           {-(L - head), s * spread}};
    polygonCcw(handle);
    b.add(extrude(handle, 0.0005f, T - 0.0005f, 20.f), gt, 0.15f, 4);
  }
  std::vector<ProfilePoint> pivot{
      {0, 0}, {0.006f, 0, true}, {0.006f, T + 0.001f, true}, {0, T + 0.001f}};
  Mesh pm = lathe(pivot, 16);
  pm.transform(translation(0, 0.006f, 0));
  b.add(std::move(pm), metal, 0.5f, 6);
}

void makePotato(Builder& b) {
  Rng& r = b.rng;
  const V3 half(r.uniformf(0.035f, 0.06f), r.uniformf(0.027f, 0.04f), r.uniformf(0.022f, 0.033f));
  const uint32_t seed = static_cast<uint32_t>(r.next());
  Mesh m = parametricSphere(
      [&](float s, float t) {
        const float th = kPi * t, ph = 2 * kPi * s;
        V3 d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), -std::cos(th));
        const float k =
            1.f +
            0.12f * gradientNoise(d.x() * 1.5f + d.z() * 0.7f, d.y() * 1.5f - d.z() * 0.3f, seed) +
            0.04f * gradientNoise(d.x() * 5.f + d.z(), d.y() * 5.f, seed + 1);
        return V3(half.x() * k * d.x(), half.y() * k * d.y(), half.z() * k * d.z());
      },
      36, 24);
  m.transform(translation(0, 0, -m.bounds().min().z()));
  const cv::Vec3f col = r.chance(0.7) ? hsvColor(r.uniformf(28.f, 40.f), r.uniformf(0.4f, 0.6f),
                                                 r.uniformf(0.45f, 0.7f))
                                      : hsvColor(r.uniformf(0.f, 15.f), 0.55f, 0.45f);
  b.add(std::move(m), tex(skinTexture(r, "potato", 256, 128, col)), 0.05f, 3);
}

void makeEraser(Builder& b) {
  Rng& r = b.rng;
  const V3 size(r.uniformf(0.04f, 0.065f), r.uniformf(0.018f, 0.026f), r.uniformf(0.009f, 0.013f));
  const cv::Vec3f col =
      r.chance(0.5) ? cv::Vec3f(0.93f, 0.93f, 0.95f) : anyColor(r, 0.2f, 0.6f, 0.6f, 0.95f);
  printedBox(b, size, r.uniformf(0.f, 360.f), false, Eigen::Affine3f::Identity(), 3000.f);
  // The rubber shows at both ends of the paper sleeve: repaint a band of the atlas.
  cv::Mat t = b.model.parts.back().material.texture->image();
  const int x0 = static_cast<int>(t.cols * 0.0f), band = static_cast<int>(t.cols * 0.05f);
  cv::rectangle(t, cv::Point(x0, 0), cv::Point(x0 + band, t.rows),
                cv::Scalar(255 * col[0], 255 * col[1], 255 * col[2]), -1);
  b.model.parts.back().material.texture = tex(t, false, false);
}

void makeScissors(Builder& b) {
  Rng& r = b.rng;
  const float L = r.uniformf(0.13f, 0.2f), blade = L * r.uniformf(0.5f, 0.6f), T = 0.003f;
  const float open = r.uniformf(0.f, 0.25f);
  const cv::Vec3f grip = anyColor(r, 0.5f, 1.f, 0.2f, 0.85f);
  TexturePtr metal = tex(metalTexture(r, 64, 64, {0.7f, 0.71f, 0.73f}, true));
  TexturePtr gt = tex(plasticTexture(r, 64, 64, grip, 0.05f));
  for (int side = -1; side <= 1; side += 2) {
    const float s = static_cast<float>(side), a = s * open / 2;
    std::vector<V2> bl{{-0.01f, 0}, {blade, s * 0.001f}, {0, s * 0.009f}};
    polygonCcw(bl);
    Mesh bm = extrude(bl, side > 0 ? T : 0.f, side > 0 ? 2 * T : T, 20.f);
    bm.transform(rotationZ(a));
    b.add(std::move(bm), metal, 0.6f, 6);
    // Handle ring.
    const float rr = r.uniformf(0.013f, 0.02f);
    std::vector<V3> ring;
    for (int i = 0; i <= 24; ++i) {
      const float t = 2 * kPi * static_cast<float>(i) / 24.f;
      ring.push_back({-0.01f - rr - rr * std::cos(t),
                      s * (0.008f + rr * 0.8f) + rr * 0.8f * std::sin(t), 0.f});
    }
    Mesh hm = sweep(
        ring, [](float) { return 0.0035f; }, 8, false, 1.f, V3::UnitZ());
    hm.transform(rotationZ(-a) * translation(0, 0, 0.0035f + (side > 0 ? T : 0.f)));
    b.add(std::move(hm), gt, 0.2f, 4, true);
  }
}

void makeShampoo(Builder& b) {
  Rng& r = b.rng;
  const float R = r.uniformf(0.028f, 0.04f), H = r.uniformf(0.14f, 0.22f),
              depth = r.uniformf(0.5f, 0.9f);
  const float shoulder = H * r.uniformf(0.75f, 0.88f), neck = R * r.uniformf(0.35f, 0.5f);
  std::vector<ProfilePoint> prof{
      {0, 0, false, 0},           {R * 0.92f, 0, true, 0.01f},    {R, 0.006f, false, 0.03f},
      {R, shoulder, false, 0.8f}, {neck, H - 0.01f, true, 0.95f}, {0, H - 0.01f, false, 1.f}};
  Mesh m = lathe(prof, 40);
  m.transform(scaling(1.f, depth, 1.f));
  const cv::Vec3f col = anyColor(r, 0.2f, 0.9f, 0.3f, 0.95f);
  cv::Mat t = plasticTexture(r, 512, 256, col, 0.03f);
  {
    Rng lr = r.fork(2);
    cv::Mat label = labelTexture(lr, 200, 150, lr.uniformf(0.f, 360.f));
    label.copyTo(t(cv::Rect(384 - 100, 60, 200, 150)));  // front (-y: u = 0.75)
  }
  b.add(std::move(m), tex(t), 0.45f, 6);
  const float ch = r.uniformf(0.02f, 0.035f);
  std::vector<ProfilePoint> cap{{0, H - 0.012f},
                                {neck * 1.3f, H - 0.012f, true},
                                {neck * 1.3f, H - 0.012f + ch, true},
                                {0, H - 0.012f + ch}};
  b.add(lathe(cap, 24), tex(plasticTexture(r, 64, 64, anyColor(r, 0.f, 0.9f, 0.2f, 0.95f), 0.03f)),
        0.4f, 6);
}

void makeSponge(Builder& b) {
  Rng& r = b.rng;
  const V3 size(r.uniformf(0.065f, 0.1f), r.uniformf(0.1f, 0.14f), r.uniformf(0.025f, 0.045f));
  const float pad = r.chance(0.7) ? size.z() * r.uniformf(0.2f, 0.3f) : 0.f;
  const cv::Vec3f foam = anyColor(r, 0.4f, 0.9f, 0.6f, 0.95f);
  Mesh m = box(V3(size.x(), size.y(), size.z() - pad));
  m.transform(translation(0, 0, (size.z() - pad) / 2));
  b.add(std::move(m), tex(spongeTexture(r, 256, 256, foam), true, true), 0.02f, 2);
  if (pad > 0) {
    Mesh p = box(V3(size.x(), size.y(), pad));
    p.transform(translation(0, 0, size.z() - pad / 2));
    b.add(
        std::move(p),
        tex(fabricTexture(r, 256, 256, hsvColor(r.uniformf(90.f, 150.f), 0.6f, 0.35f), false, 3.f),
            true, true),
        0.02f, 2);
  }
}

void makeStapler(Builder& b) {
  Rng& r = b.rng;
  const float L = r.uniformf(0.12f, 0.2f), W = r.uniformf(0.03f, 0.045f),
              H = r.uniformf(0.04f, 0.065f);
  const cv::Vec3f col =
      r.chance(0.4) ? cv::Vec3f(0.1f, 0.1f, 0.1f) : anyColor(r, 0.5f, 1.f, 0.3f, 0.85f);
  // Side outline in x-z (base plate + arm rising towards the back), extruded across y.
  std::vector<V2> side{{-L / 2, 0},        {L / 2, 0},
                       {L / 2, 0.008f},    {L / 2 - 0.01f, H * 0.75f},
                       {L / 2 - 0.03f, H}, {-L / 2 + 0.01f, H * 0.95f},
                       {-L / 2, H * 0.5f}};
  polygonCcw(side);
  Mesh m = extrude(side, -W / 2, W / 2, 10.f);
  m.transform(rotationX(kPi / 2));  // the outline's y becomes z
  m.transform(translation(0, 0, -m.bounds().min().z()));
  cv::Mat t = metalTexture(r, 256, 256, col, false);
  cv::putText(t, pseudoWord(r, 2, true), cv::Point(30, 140), cv::FONT_HERSHEY_SIMPLEX, 0.9,
              cv::Scalar(220, 220, 220), 2, cv::LINE_AA);
  b.add(std::move(m), tex(t), 0.35f, 5);
}

void makeTomato(Builder& b) {
  Rng& r = b.rng;
  const float R = r.uniformf(0.022f, 0.045f), H = 2 * R * r.uniformf(0.7f, 0.9f);
  const int ribs = r.range(4, 7);
  const float rib = r.uniformf(0.01f, 0.05f);
  Mesh m = parametricSphere(
      [&](float s, float t) {
        const float th = kPi * t, ph = 2 * kPi * s;
        const float k = 1.f + rib * std::cos(ribs * ph) * std::pow(std::sin(th), 2.f);
        float z =
            0.5f * H * (1.f - std::cos(th)) - 0.006f * std::exp(-std::pow((kPi - th) / 0.4f, 2.f));
        return V3(R * k * std::sin(th) * std::cos(ph), R * k * std::sin(th) * std::sin(ph), z);
      },
      40, 24);
  const cv::Vec3f col = r.chance(0.8) ? cv::Vec3f(0.1f, 0.15f, 0.8f) : cv::Vec3f(0.1f, 0.55f, 0.9f);
  b.add(std::move(m), tex(skinTexture(r, "tomato", 256, 128, col)), 0.55f, 6);
  std::vector<V2> star;
  for (int k = 0; k < 10; ++k) {
    const float a = static_cast<float>(k) * kPi / 5, rr = (k & 1) ? 0.004f : R * 0.45f;
    star.push_back({rr * std::cos(a), rr * std::sin(a)});
  }
  polygonCcw(star);
  b.add(extrude(star, H - 0.007f, H - 0.004f, 30.f),
        tex(plasticTexture(r, 32, 32, {0.2f, 0.5f, 0.25f}, 0.1f)), 0.1f, 3);
}

void makeToothbrush(Builder& b) {
  Rng& r = b.rng;
  const float L = r.uniformf(0.17f, 0.19f), R = r.uniformf(0.005f, 0.007f);
  const cv::Vec3f col = anyColor(r, 0.4f, 1.f, 0.4f, 0.95f);
  std::vector<V3> curve;
  for (int i = 0; i <= 20; ++i) {
    const float t = static_cast<float>(i) / 20.f;
    curve.push_back(
        {-L / 2 + L * t, 0.f, R + 0.006f * std::sin(t * kPi) * (t > 0.5f ? 1.f : 0.4f)});
  }
  b.add(sweep(
            curve, [&](float t) { return R * (t > 0.75f ? 0.75f : (t < 0.3f ? 1.1f : 0.9f)); }, 10,
            true, 0.55f, V3::UnitZ()),
        tex(plasticTexture(r, 64, 64, col, 0.05f)), 0.4f, 5);
  Mesh br = box(V3(0.025f, 0.011f, 0.011f));
  br.transform(translation(L / 2 - 0.018f, 0, 2 * R + 0.005f));
  const cv::Vec3f bristle =
      r.chance(0.5) ? cv::Vec3f(0.95f, 0.95f, 0.95f) : anyColor(r, 0.3f, 0.8f, 0.6f, 0.95f);
  b.add(std::move(br), tex(spongeTexture(r, 64, 64, bristle), true, true), 0.05f, 3);
}

void makeToothpaste(Builder& b) {
  Rng& r = b.rng;
  const float L = r.uniformf(0.14f, 0.2f), R = r.uniformf(0.014f, 0.02f);
  // A tube: round at the cap end (x < 0), flat and wider at the crimped end.
  Mesh m = parametricSphere(
      [&](float s, float t) {
        const float ph = 2 * kPi * s;
        const float k = std::min(1.f, t / 0.04f);
        const float width = R * (1.f + 0.4f * t), flat = std::max(0.08f, 1.f - 0.95f * t);
        return V3(-L / 2 + L * t, width * k * std::cos(ph), R * flat * k * std::sin(ph));
      },
      24, 24);
  m.transform(translation(0, 0, R));
  const int w = 512, h = 128;
  cv::Mat t = labelTexture(r, w, h, r.uniformf(0.f, 360.f));
  cv::Mat tt;
  cv::rotate(t, tt, cv::ROTATE_90_CLOCKWISE);  // text along the tube
  b.add(std::move(m), tex(tt, true, false), 0.35f, 5);
  std::vector<ProfilePoint> cap{{0, 0}, {R * 0.7f, 0, true}, {R * 0.7f, 0.015f, true}, {0, 0.015f}};
  Mesh cm = lathe(cap, 20);
  cm.transform(translation(-L / 2 + 0.001f, 0, R) * rotationY(-kPi / 2));
  b.add(std::move(cm), tex(plasticTexture(r, 32, 32, anyColor(r, 0.f, 0.8f, 0.3f, 0.95f), 0.03f)),
        0.3f, 5);
}

void makeWaterBottle(Builder& b) {
  Rng& r = b.rng;
  const float R = r.uniformf(0.029f, 0.036f), H = r.uniformf(0.19f, 0.25f),
              neck = r.uniformf(0.012f, 0.015f);
  const int ridges = r.range(3, 8);
  std::vector<ProfilePoint> prof{{0, 0.003f, false, 0}, {R * 0.9f, 0, true, 0.01f}};
  for (int i = 0; i <= 20; ++i) {
    const float t = static_cast<float>(i) / 20.f;
    const float ridge = 1.f - 0.04f * std::pow(std::sin(t * static_cast<float>(ridges) * kPi), 8.f);
    prof.push_back({R * ridge, 0.005f + (H * 0.72f) * t, false, 0.02f + 0.7f * t});
  }
  for (int i = 1; i <= 8; ++i) {
    const float t = static_cast<float>(i) / 8.f;
    prof.push_back({neck + (R - neck) * std::cos(t * kPi / 2), 0.005f + H * 0.72f + (H * 0.2f) * t,
                    false, 0.72f + 0.22f * t});
  }
  prof.push_back({0, 0.005f + H * 0.92f, false, 1.f});
  const cv::Vec3f water =
      hsvColor(r.uniformf(185.f, 215.f), r.uniformf(0.1f, 0.35f), r.uniformf(0.75f, 0.95f));
  cv::Mat t = plasticTexture(r, 512, 512, water, 0.08f);
  {
    Rng lr = r.fork(4);
    cv::Mat label = labelTexture(lr, 512, 120, lr.uniformf(0.f, 360.f));
    label.copyTo(t(cv::Rect(0, 512 - static_cast<int>(512 * 0.6f), 512, 120)));
  }
  b.add(lathe(prof, 40), tex(t), 0.7f, 7);
  std::vector<ProfilePoint> cap{{0, H * 0.92f},
                                {neck * 1.25f, H * 0.92f, true},
                                {neck * 1.25f, H * 0.92f + 0.018f, true},
                                {0, H * 0.92f + 0.018f}};
  b.add(lathe(cap, 24, 1.f, [](float ph, float) { return 1.f + 0.02f * std::cos(24.f * ph); }),
        tex(plasticTexture(r, 64, 64, anyColor(r, 0.3f, 1.f, 0.3f, 0.95f), 0.03f)), 0.4f, 5);
}

struct CategoryDef {
  std::string family;
  std::function<void(Builder&)> make;
};

const std::map<std::string, CategoryDef>& registry() {
  static const std::map<std::string, CategoryDef> m = {
      {"bowl", {"open ceramic shell on a foot ring (lathe)", makeBowl}},
      {"cap", {"baseball cap: panelled crown, drooping brim, button", makeCap}},
      {"cereal_box", {"tall printed cuboid", makeCerealBox}},
      {"coffee_mug", {"open cylinder with a handle (lathe + swept tube)", makeMug}},
      {"soda_can",
       {"can with rims and necked top, printed metal (lathe)",
        [](Builder& b) { makeCan(b, true); }}},
      {"apple", {"dimpled round fruit with a stem", makeApple}},
      {"ball", {"sphere: tennis, baseball, striped or panelled", makeBall}},
      {"banana", {"curved tapered tube", makeBanana}},
      {"bell_pepper", {"lobed fruit with a stem", makePepper}},
      {"binder", {"flat cuboid with a cover print and a spine label", makeBinder}},
      {"calculator", {"flat cuboid with keys and a display", makeCalculator}},
      {"camera", {"cuboid body with a stepped lens and a button", makeCamera}},
      {"cell_phone", {"thin cuboid with a screen (or keypad)", makePhone}},
      {"comb", {"flat toothed prism", makeComb}},
      {"dry_battery", {"small labelled cylinder (AA, C, D, AAA)", makeBattery}},
      {"flashlight", {"tube with a wider head, lying", makeFlashlight}},
      {"food_bag", {"puffy printed pillow, lying", makeFoodBag}},
      {"food_box", {"printed cuboid, standing or lying", makeFoodBox}},
      {"food_can",
       {"can with rims and a paper label (lathe)", [](Builder& b) { makeCan(b, false); }}},
      {"food_cup",
       {"tapered cup with a lid rim (yogurt)", [](Builder& b) { makeFoodCup(b, false); }}},
      {"food_jar", {"jar with a ribbed metal lid", makeJar}},
      {"garlic", {"lobed bulb with a pointed top", makeGarlic}},
      {"glue_stick", {"cylinder with a coloured cap", makeGlueStick}},
      {"greens", {"bunch of curled leaves", makeGreens}},
      {"hand_towel", {"folded fabric, rounded cuboid", makeTowel}},
      {"instant_noodles",
       {"wide tapered cup with a printed wrap", [](Builder& b) { makeFoodCup(b, true); }}},
      {"keyboard", {"long flat wedge with keys", makeKeyboard}},
      {"kleenex", {"printed box with a tissue on top", makeKleenex}},
      {"lemon", {"elongated citrus with pointed ends", [](Builder& b) { makeCitrus(b, "lemon"); }}},
      {"lightbulb", {"glass bulb on a screw base, lying", makeLightbulb}},
      {"lime", {"small green citrus", [](Builder& b) { makeCitrus(b, "lime"); }}},
      {"marker", {"pen-like cylinder with a cap, lying", makeMarker}},
      {"mushroom", {"cap on a stem", makeMushroom}},
      {"notebook", {"thin cuboid with a printed cover", makeNotebook}},
      {"onion", {"bulb with a pointed top", makeOnion}},
      {"orange", {"round citrus with pores", [](Builder& b) { makeCitrus(b, "orange"); }}},
      {"peach", {"round fruit with a crease", makePeach}},
      {"pear", {"pear-shaped lathe with a stem", makePear}},
      {"pitcher", {"open vessel with a spout and a handle", makePitcher}},
      {"plate", {"flat dish with a well (lathe)", makePlate}},
      {"pliers", {"two jaws and two grips on a pivot, lying", makePliers}},
      {"potato", {"lumpy ellipsoid", makePotato}},
      {"rubber_eraser", {"small cuboid in a paper sleeve", makeEraser}},
      {"scissors", {"two blades and two handle rings, lying", makeScissors}},
      {"shampoo", {"oval bottle with a cap and a label", makeShampoo}},
      {"sponge", {"foam cuboid with a scouring pad", makeSponge}},
      {"stapler", {"extruded side profile", makeStapler}},
      {"tomato", {"ribbed round fruit with a calyx", makeTomato}},
      {"toothbrush", {"slim handle with a bristle block, lying", makeToothbrush}},
      {"toothpaste", {"tube flattening to a crimp, with a cap, lying", makeToothpaste}},
      {"water_bottle", {"ridged bottle with a cap and a label band", makeWaterBottle}},
  };
  return m;
}

}  // namespace

const std::vector<std::string>& paperClasses() {
  static const std::vector<std::string> v{"bowl", "cap", "cereal_box", "coffee_mug", "soda_can"};
  return v;
}

const std::vector<std::string>& categoryNames() {
  static const std::vector<std::string> v = [] {
    std::vector<std::string> out = paperClasses();
    for (const auto& kv : registry())
      if (std::find(out.begin(), out.end(), kv.first) == out.end()) out.push_back(kv.first);
    return out;
  }();
  return v;
}

bool isCategory(const std::string& name) { return registry().count(name) > 0; }

std::string categoryFamily(const std::string& category) {
  auto it = registry().find(category);
  if (it == registry().end()) throw std::invalid_argument("unknown category '" + category + "'");
  return it->second.family;
}

Eigen::AlignedBox3f ObjectModel::bounds() const {
  Eigen::AlignedBox3f b;
  for (const auto& p : parts) b.extend(p.mesh.bounds());
  return b;
}

float ObjectModel::footprintRadius() const {
  float r = 0;
  for (const auto& p : parts)
    for (const auto& v : p.mesh.vertices) r = std::max(r, std::hypot(v.p.x(), v.p.y()));
  return r;
}

size_t ObjectModel::triangleCount() const {
  size_t n = 0;
  for (const auto& p : parts) n += p.mesh.triangles.size();
  return n;
}

ObjectModel makeObject(const std::string& category, uint64_t instance_seed) {
  auto it = registry().find(category);
  if (it == registry().end()) throw std::invalid_argument("unknown category '" + category + "'");
  Builder b(category, hashCombine(instance_seed, hashString(category)));
  b.model.seed = instance_seed;
  it->second.make(b);
  // Settle: base on z = 0, centred on the z axis (the centre of the bounding box).
  const Eigen::AlignedBox3f bb = b.model.bounds();
  const V3 c = bb.center();
  b.transformAll(translation(-c.x(), -c.y(), -bb.min().z()));
  return std::move(b.model);
}

uint64_t instanceSeed(SeedDomain domain, uint64_t set_seed, const std::string& category,
                      uint64_t index) {
  const uint64_t h = hashCombine(hashCombine(set_seed, hashString(category)), index);
  return (h & 0x7FFFFFFFFFFFFFFFull) | (static_cast<uint64_t>(domain) << 63);
}

SeedDomain seedDomain(uint64_t instance_seed) {
  return static_cast<SeedDomain>(instance_seed >> 63);
}

}  // namespace slamaware::synth
