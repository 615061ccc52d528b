#include "tools/synth/rasterizer.h"

#include <algorithm>
#include <cmath>
#include <limits>

#if defined(__AVX2__)
#include <immintrin.h>
#define SLAMAWARE_SYNTH_AVX2 1
#else
#define SLAMAWARE_SYNTH_AVX2 0
#endif

namespace slamaware::synth {

namespace {

constexpr uint32_t kNone = 0xFFFFFFFFu;
constexpr int kSub = 256;  // fixed-point sub-pixel steps

int64_t floorDiv(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// Calls fn(x, y, index) for every pixel centre (x, y) of the viewport inside the screen triangle
// (xs, ys), with the top-left rule so that triangles sharing an edge never both cover a pixel and
// never leave a gap. index is the row-major offset in the viewport.
template <class Fn>
void rasterize(const float* xs, const float* ys, const Viewport& vp, Fn&& fn) {
  int64_t X[3], Y[3];
  for (int i = 0; i < 3; ++i) {
    X[i] = std::llround(static_cast<double>(xs[i]) * kSub);
    Y[i] = std::llround(static_cast<double>(ys[i]) * kSub);
  }
  int64_t area = (X[1] - X[0]) * (Y[2] - Y[0]) - (Y[1] - Y[0]) * (X[2] - X[0]);
  if (area == 0) return;
  if (area < 0) {
    std::swap(X[1], X[2]);
    std::swap(Y[1], Y[2]);
  }
  const int64_t minX = std::max<int64_t>(vp.x0, -floorDiv(-std::min({X[0], X[1], X[2]}), kSub));
  const int64_t maxX =
      std::min<int64_t>(vp.x0 + vp.w - 1, floorDiv(std::max({X[0], X[1], X[2]}), kSub));
  const int64_t minY = std::max<int64_t>(vp.y0, -floorDiv(-std::min({Y[0], Y[1], Y[2]}), kSub));
  const int64_t maxY =
      std::min<int64_t>(vp.y0 + vp.h - 1, floorDiv(std::max({Y[0], Y[1], Y[2]}), kSub));
  if (minX > maxX || minY > maxY) return;
  // Edge a->b: E(p) = (bx - ax)(py - ay) - (by - ay)(px - ax) > 0 inside; = 0 counts on top-left
  // edges.
  int64_t A[3], B[3], C[3];
  for (int e = 0; e < 3; ++e) {
    const int a = e, b = (e + 1) % 3;
    const int64_t dx = X[b] - X[a], dy = Y[b] - Y[a];
    A[e] = -dy;
    B[e] = dx;
    const bool top_left = dy < 0 || (dy == 0 && dx > 0);
    C[e] = -dx * Y[a] + dy * X[a] + (top_left ? 0 : -1);
  }
  for (int64_t y = minY; y <= maxY; ++y) {
    int64_t e0 = A[0] * minX * kSub + B[0] * y * kSub + C[0];
    int64_t e1 = A[1] * minX * kSub + B[1] * y * kSub + C[1];
    int64_t e2 = A[2] * minX * kSub + B[2] * y * kSub + C[2];
    const int64_t s0 = A[0] * kSub, s1 = A[1] * kSub, s2 = A[2] * kSub;
    size_t index = static_cast<size_t>(y - vp.y0) * static_cast<size_t>(vp.w) +
                   static_cast<size_t>(minX - vp.x0);
    bool seen = false;
    for (int64_t x = minX; x <= maxX; ++x, ++index, e0 += s0, e1 += s1, e2 += s2) {
      if ((e0 | e1 | e2) >= 0) {
        fn(static_cast<int>(x), static_cast<int>(y), index);
        seen = true;
      } else if (seen) {
        break;  // a triangle's row is one span
      }
    }
  }
}

// Clips a camera-frame triangle against z >= near; returns the polygon (0, 3 or 4 points).
int clipNear(const Eigen::Vector3f* P, float near, Eigen::Vector3f* out) {
  int n = 0;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3f& a = P[i];
    const Eigen::Vector3f& b = P[(i + 1) % 3];
    const bool ina = a.z() >= near, inb = b.z() >= near;
    if (ina) out[n++] = a;
    if (ina != inb) {
      const float t = (near - a.z()) / (b.z() - a.z());
      out[n++] = a + t * (b - a);
    }
  }
  return n;
}

// Projects a clipped polygon and rasterises it as a fan.
template <class Fn>
void rasterPolygon(const Eigen::Vector3f* poly, int n, const Intrinsics& K, const Viewport& vp,
                   Fn&& fn) {
  float xs[4], ys[4];
  for (int i = 0; i < n; ++i) {
    const float iz = 1.f / poly[i].z();
    xs[i] = K.fx * poly[i].x() * iz + K.cx;
    ys[i] = K.fy * poly[i].y() * iz + K.cy;
  }
  // Cull polygons entirely outside the viewport.
  const float lo_x = static_cast<float>(vp.x0) - 1.f, hi_x = static_cast<float>(vp.x0 + vp.w);
  const float lo_y = static_cast<float>(vp.y0) - 1.f, hi_y = static_cast<float>(vp.y0 + vp.h);
  bool all_left = true, all_right = true, all_up = true, all_down = true;
  for (int i = 0; i < n; ++i) {
    all_left = all_left && xs[i] < lo_x;
    all_right = all_right && xs[i] > hi_x;
    all_up = all_up && ys[i] < lo_y;
    all_down = all_down && ys[i] > hi_y;
  }
  if (all_left || all_right || all_up || all_down) return;
  for (int k = 1; k + 1 < n; ++k) {
    const float tx[3] = {xs[0], xs[k], xs[k + 1]}, ty[3] = {ys[0], ys[k], ys[k + 1]};
    rasterize(tx, ty, vp, fn);
  }
}

// c . (x_n, y_n, 1) as an affine function of the pixel coordinates.
void toPixelAffine(const Eigen::Vector3f& c, const Intrinsics& K, float out[3]) {
  out[0] = c.x() / K.fx;
  out[1] = c.y() / K.fy;
  out[2] = c.z() - c.x() * K.cx / K.fx - c.y() * K.cy / K.fy;
}

}  // namespace

void RenderScene::freezePrefix(size_t n) {
  frozen_items_ = 0;
  const std::vector<RenderItem> rest(items.begin() + static_cast<long>(n), items.end());
  items.resize(n);
  finalize();
  frozen_items_ = n;
  frozen_vertices_ = vertices_.size();
  frozen_triangles_ = triangles_.size();
  items.insert(items.end(), rest.begin(), rest.end());
  finalize();
}

void RenderScene::finalize() {
  // The frozen prefix (background only) comes first in the full order too, so re-using it gives
  // the same arrays as flattening everything again.
  const size_t first = frozen_items_ > 0 && items.size() >= frozen_items_ ? frozen_items_ : 0;
  vertices_.resize(first ? frozen_vertices_ : 0);
  triangles_.resize(first ? frozen_triangles_ : 0);
  int max_object = -1;
  for (const auto& it : items) max_object = std::max(max_object, it.object);
  object_ranges_.assign(static_cast<size_t>(max_object + 1), Range{});
  // Background first, then objects in id order, so that each object's triangles are contiguous.
  std::vector<size_t> order;
  for (size_t i = first; i < items.size(); ++i)
    if (items[i].object < 0) order.push_back(i);
  for (int o = 0; o <= max_object; ++o)
    for (size_t i = first; i < items.size(); ++i)
      if (items[i].object == o) order.push_back(i);
  for (size_t i : order) {
    const RenderItem& it = items[i];
    const uint32_t base = static_cast<uint32_t>(vertices_.size());
    vertices_.insert(vertices_.end(), it.mesh.vertices.begin(), it.mesh.vertices.end());
    if (it.object >= 0 && object_ranges_[it.object].begin == object_ranges_[it.object].end)
      object_ranges_[it.object].begin = static_cast<uint32_t>(triangles_.size());
    for (const auto& t : it.mesh.triangles)
      triangles_.push_back({{t[0] + base, t[1] + base, t[2] + base},
                            it.material,
                            it.object,
                            static_cast<int32_t>(i)});
    if (it.object >= 0) object_ranges_[it.object].end = static_cast<uint32_t>(triangles_.size());
  }
}

void Rasterizer::transformVertices(const RenderScene& scene,
                                   const Eigen::Isometry3d& T_world_camera) {
  const Eigen::Isometry3d T_cw = T_world_camera.inverse();
  const Eigen::Matrix3f R = T_cw.linear().cast<float>();
  const Eigen::Vector3f t = T_cw.translation().cast<float>();
  const auto& V = scene.vertices();
  cam_.resize(V.size());
  for (size_t i = 0; i < V.size(); ++i) cam_[i] = R * V[i].p + t;
}

void Rasterizer::render(const RenderScene& scene, const Intrinsics& K,
                        const Eigen::Isometry3d& T_world_camera, const Viewport& vp,
                        FrameBuffers* out, bool shade_colour) {
  const size_t npx = static_cast<size_t>(vp.w) * static_cast<size_t>(vp.h);
  out->vp = vp;
  out->inv_z.assign(npx, 0.f);
  out->setup.assign(npx, kNone);
  transformVertices(scene, T_world_camera);
  const Eigen::Matrix3f R_cw = T_world_camera.linear().transpose().cast<float>();
  const auto& V = scene.vertices();
  setups_.clear();
  light_ = scene.light;
  l_cam_ = (R_cw * scene.light.to_light).normalized();
  up_cam_ = R_cw * Eigen::Vector3f::UnitZ();

  // ---- Visibility: nearest triangle per pixel -----------------------------------------------
  for (const FlatTriangle& t : scene.triangles()) {
    const Eigen::Vector3f P[3] = {cam_[t.v[0]], cam_[t.v[1]], cam_[t.v[2]]};
    if (P[0].z() < kNear && P[1].z() < kNear && P[2].z() < kNear) continue;
    const Eigen::Vector3f e1 = P[1] - P[0], e2 = P[2] - P[0];
    const Eigen::Vector3f N = e1.cross(e2);
    const float d = N.dot(P[0]);
    const float nn = N.squaredNorm();
    if (!(nn > 0.f) || d == 0.f) continue;
    const Material& mat = scene.materials[t.material];
    const bool front = d < 0.f;
    if (!front && !mat.double_sided) continue;
    Eigen::Vector3f poly[4];
    const int n = clipNear(P, kNear, poly);
    if (n < 3) continue;

    Setup S;
    const Eigen::Vector3f c_iz = N / d;
    const Eigen::Vector3f g1 = e2.cross(N) / nn, g2 = N.cross(e1) / nn;
    const Eigen::Vector3f c1 = g1 - (g1.dot(P[0]) / d) * N;
    const Eigen::Vector3f c2 = g2 - (g2.dot(P[0]) / d) * N;
    toPixelAffine(c_iz, K, S.iz);
    toPixelAffine(c1, K, S.q1);
    toPixelAffine(c2, K, S.q2);
    const uint32_t sidx = static_cast<uint32_t>(setups_.size());
    bool drawn = false;
    float* inv_z = out->inv_z.data();
    uint32_t* setup = out->setup.data();
    rasterPolygon(poly, n, K, vp, [&](int x, int y, size_t index) {
      const float iz = S.iz[0] * static_cast<float>(x) + S.iz[1] * static_cast<float>(y) + S.iz[2];
      if (iz > inv_z[index]) {
        inv_z[index] = iz;
        setup[index] = sidx;
        drawn = true;
      }
    });
    if (!drawn) continue;
    const Vertex &v0 = V[t.v[0]], &v1 = V[t.v[1]], &v2 = V[t.v[2]];
    for (int k = 0; k < 2; ++k) {
      S.uv0[k] = v0.uv[k];
      S.duv1[k] = v1.uv[k] - v0.uv[k];
      S.duv2[k] = v2.uv[k] - v0.uv[k];
      S.uw0[k] = v0.uv2[k];
      S.duw1[k] = v1.uv2[k] - v0.uv2[k];
      S.duw2[k] = v2.uv2[k] - v0.uv2[k];
    }
    const float sign = front ? 1.f : -1.f;
    const Eigen::Vector3f n0 = sign * (R_cw * v0.n), n1 = sign * (R_cw * v1.n),
                          n2 = sign * (R_cw * v2.n);
    S.flat = v0.n == v1.n && v0.n == v2.n;
    for (int k = 0; k < 3; ++k) {
      S.n0[k] = n0[k];
      S.dn1[k] = n1[k] - n0[k];
      S.dn2[k] = n2[k] - n0[k];
    }
    S.mat = &mat;
    S.object = t.object;
    if (S.flat) {  // the same unit normal at every vertex: normalise exactly as shadePixel does
      float nf[3] = {S.n0[0], S.n0[1], S.n0[2]};
      const float inv_len = 1.f / std::sqrt(nf[0] * nf[0] + nf[1] * nf[1] + nf[2] * nf[2] + 1e-20f);
      for (int k = 0; k < 3; ++k) nf[k] *= inv_len;
      lightTerms(nf, mat, S.amb, S.dif, S.refl);
    }
    setups_.push_back(S);
  }

  shade(K, vp, out, shade_colour);
}

namespace {

// The light in the camera frame of one render.
struct CamLight {
  float l[3], up[3], sun[3], sky[3], ground[3];
};

constexpr float kInv255 = 1.f / 255.f;

// Ambient and direct factors (tint included) and the mirrored light direction for a unit normal.
inline void lightTermsScalar(const float n[3], const Material& m, const CamLight& L, float amb[3],
                             float dif[3], float refl[3]) {
  const float ndl = n[0] * L.l[0] + n[1] * L.l[1] + n[2] * L.l[2];
  const float hemi = 0.5f + 0.5f * (n[0] * L.up[0] + n[1] * L.up[1] + n[2] * L.up[2]);
  const float d = ndl > 0.f ? ndl : 0.f;
  for (int c = 0; c < 3; ++c) {
    amb[c] = m.tint[c] * (L.ground[c] + hemi * (L.sky[c] - L.ground[c]));
    dif[c] = m.tint[c] * L.sun[c] * d;
  }
  for (int k = 0; k < 3; ++k) refl[k] = ndl > 0.f ? 2.f * ndl * n[k] - L.l[k] : 0.f;
}

inline float power2k(float s, int k) {
  for (int i = 0; i < k && i < 7; ++i) s *= s;
  return s;
}

}  // namespace

void Rasterizer::lightTerms(const float n[3], const Material& m, float amb[3], float dif[3],
                            float refl[3]) const {
  CamLight L;
  for (int k = 0; k < 3; ++k) {
    L.l[k] = l_cam_[k];
    L.up[k] = up_cam_[k];
    L.sun[k] = light_.sun[k];
    L.sky[k] = light_.sky[k];
    L.ground[k] = light_.ground[k];
  }
  lightTermsScalar(n, m, L, amb, dif, refl);
}

// ---- Shading ------------------------------------------------------------------------------------
// The reference is shadePixel(); shadeSpan8() does the same operations in the same order on eight
// pixels of one triangle at once (AVX2), so both give the same bits.

namespace {

struct ShadeTarget {
  float* b;
  float* g;
  float* r;
  float* depth;
  int16_t* object;
  const float* rx;
  const float* ry;
  const float* rz;
};

}  // namespace

void Rasterizer::shadePixel(const Setup& S, float x, float y, size_t index, const void* target_ptr,
                            bool colour) const {
  const ShadeTarget& T = *static_cast<const ShadeTarget*>(target_ptr);
  const float iz = S.iz[0] * x + S.iz[1] * y + S.iz[2];
  const float z = 1.f / iz;
  T.depth[index] = z;
  T.object[index] = static_cast<int16_t>(S.object);
  if (!colour) return;
  const float b1 = (S.q1[0] * x + S.q1[1] * y + S.q1[2]) * z;
  const float b2 = (S.q2[0] * x + S.q2[1] * y + S.q2[2]) * z;
  const Material& mat = *S.mat;
  float albedo[3] = {1.f, 1.f, 1.f};
  if (mat.texture) {
    const float u = S.uv0[0] + b1 * S.duv1[0] + b2 * S.duv2[0];
    const float v = S.uv0[1] + b1 * S.duv1[1] + b2 * S.duv2[1];
    // d(b/z / (1/z))/dx = (q_x - b iz_x) z
    const float db1x = (S.q1[0] - b1 * S.iz[0]) * z, db1y = (S.q1[1] - b1 * S.iz[1]) * z;
    const float db2x = (S.q2[0] - b2 * S.iz[0]) * z, db2y = (S.q2[1] - b2 * S.iz[1]) * z;
    const uint32_t t = mat.texture->sample(
        u, v, S.duv1[0] * db1x + S.duv2[0] * db2x, S.duv1[1] * db1x + S.duv2[1] * db2x,
        S.duv1[0] * db1y + S.duv2[0] * db2y, S.duv1[1] * db1y + S.duv2[1] * db2y);
    albedo[0] = kInv255 * static_cast<float>(t & 0xFFu);
    albedo[1] = kInv255 * static_cast<float>((t >> 8) & 0xFFu);
    albedo[2] = kInv255 * static_cast<float>((t >> 16) & 0xFFu);
  }
  float amb[3], dif[3], refl[3];
  if (S.flat) {
    for (int c = 0; c < 3; ++c) {
      amb[c] = S.amb[c];
      dif[c] = S.dif[c];
      refl[c] = S.refl[c];
    }
  } else {
    float n[3];
    for (int k = 0; k < 3; ++k) n[k] = S.n0[k] + b1 * S.dn1[k] + b2 * S.dn2[k];
    const float inv_len = 1.f / std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2] + 1e-20f);
    for (int k = 0; k < 3; ++k) n[k] *= inv_len;
    lightTerms(n, mat, amb, dif, refl);
  }
  float shadow = 1.f, ao = 1.f;
  if (mat.shadow) {
    const float su = S.uw0[0] + b1 * S.duw1[0] + b2 * S.duw2[0];
    const float sv = S.uw0[1] + b1 * S.duw1[1] + b2 * S.duw2[1];
    ScalarMap::sample2(*mat.shadow, *mat.ao, su, sv, &shadow, &ao);
  }
  // Highlight: the mirrored light towards the camera (view = -ray).
  float s = -(refl[0] * T.rx[index] + refl[1] * T.ry[index] + refl[2] * T.rz[index]);
  s = s > 0.f ? s : 0.f;
  s = power2k(s, mat.shininess_log2);
  const float spec = mat.specular * s * shadow;
  T.b[index] = albedo[0] * (amb[0] * ao + dif[0] * shadow) + spec * light_.sun[0];
  T.g[index] = albedo[1] * (amb[1] * ao + dif[1] * shadow) + spec * light_.sun[1];
  T.r[index] = albedo[2] * (amb[2] * ao + dif[2] * shadow) + spec * light_.sun[2];
}

#if SLAMAWARE_SYNTH_AVX2
namespace {

using F8 = __m256;
using I8 = __m256i;

inline F8 splat(float v) { return _mm256_set1_ps(v); }
inline I8 splati(int v) { return _mm256_set1_epi32(v); }
// std::max / std::min semantics (a < b ? b : a, b < a ? b : a).
inline F8 vmax(F8 a, F8 b) { return _mm256_blendv_ps(a, b, _mm256_cmp_ps(a, b, _CMP_LT_OQ)); }
inline F8 vmin(F8 a, F8 b) { return _mm256_blendv_ps(a, b, _mm256_cmp_ps(b, a, _CMP_LT_OQ)); }
inline I8 imin(I8 a, I8 b) { return _mm256_min_epi32(a, b); }
inline I8 iselect(I8 a, I8 b, I8 mask) { return _mm256_blendv_epi8(a, b, mask); }  // mask ? b : a
// a * x + b * y + c, in the order of the scalar code.
inline F8 affine(const float c[3], F8 x, float y) {
  return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(splat(c[0]), x), splat(c[1] * y)), splat(c[2]));
}

inline F8 log2v(F8 x) {
  const I8 i = _mm256_castps_si256(x);
  const F8 e = _mm256_cvtepi32_ps(_mm256_sub_epi32(_mm256_srli_epi32(i, 23), splati(127)));
  const F8 m = _mm256_castsi256_ps(
      _mm256_or_si256(_mm256_and_si256(i, splati(0x7FFFFF)), splati(0x3F800000)));
  const F8 p =
      _mm256_mul_ps(_mm256_add_ps(_mm256_mul_ps(splat(-0.34484843f), m), splat(2.02466578f)), m);
  return _mm256_sub_ps(_mm256_add_ps(e, p), splat(0.67487759f));
}

inline I8 lerpTexel8(I8 a, I8 b, I8 w) {
  const I8 M = splati(0x00FF00FF);
  const I8 iw = _mm256_sub_epi32(splati(256), w);
  const I8 rb = _mm256_and_si256(
      _mm256_srli_epi32(_mm256_add_epi32(_mm256_mullo_epi32(_mm256_and_si256(a, M), iw),
                                         _mm256_mullo_epi32(_mm256_and_si256(b, M), w)),
                        8),
      M);
  const I8 ga = _mm256_andnot_si256(
      M, _mm256_add_epi32(_mm256_mullo_epi32(_mm256_and_si256(_mm256_srli_epi32(a, 8), M), iw),
                          _mm256_mullo_epi32(_mm256_and_si256(_mm256_srli_epi32(b, 8), M), w)));
  return _mm256_or_si256(rb, ga);
}

inline I8 fixIndex8(I8 i, I8 n, bool wrap) {
  const I8 zero = _mm256_setzero_si256();
  const I8 last = _mm256_sub_epi32(n, splati(1));
  i = iselect(i, wrap ? last : zero, _mm256_cmpgt_epi32(zero, i));
  i = iselect(i, wrap ? zero : last, _mm256_cmpgt_epi32(n, i) ^ splati(-1));  // i >= n
  return iselect(i, zero, _mm256_cmpgt_epi32(zero, i));
}

// Texture::fetch for eight lanes at levels lv.
inline I8 fetch8(const Texture& t, I8 lv, F8 u, F8 v, I8 mask) {
  lv = _mm256_max_epi32(_mm256_setzero_si256(), imin(lv, splati(t.levels() - 1)));
  const I8 w = _mm256_i32gather_epi32(t.widths(), lv, 4),
           h = _mm256_i32gather_epi32(t.heights(), lv, 4);
  const I8 off = _mm256_i32gather_epi32(t.offsets(), lv, 4);
  if (t.wrapU()) u = _mm256_sub_ps(u, _mm256_floor_ps(u));
  if (t.wrapV()) v = _mm256_sub_ps(v, _mm256_floor_ps(v));
  const F8 k = splat(4096.f), s256 = splat(256.f);
  const I8 bias = splati(static_cast<int>(4096.f * 256.f));
  const I8 xi = _mm256_sub_epi32(
      _mm256_cvttps_epi32(_mm256_mul_ps(
          _mm256_add_ps(_mm256_sub_ps(_mm256_mul_ps(u, _mm256_cvtepi32_ps(w)), splat(0.5f)), k),
          s256)),
      bias);
  const I8 yi = _mm256_sub_epi32(
      _mm256_cvttps_epi32(_mm256_mul_ps(
          _mm256_add_ps(_mm256_sub_ps(_mm256_mul_ps(v, _mm256_cvtepi32_ps(h)), splat(0.5f)), k),
          s256)),
      bias);
  const I8 fx = _mm256_and_si256(xi, splati(255)), fy = _mm256_and_si256(yi, splati(255));
  const I8 xb = _mm256_srai_epi32(xi, 8), yb = _mm256_srai_epi32(yi, 8);
  const I8 x0 = fixIndex8(xb, w, t.wrapU()),
           x1 = fixIndex8(_mm256_add_epi32(xb, splati(1)), w, t.wrapU());
  const I8 y0 = fixIndex8(yb, h, t.wrapV()),
           y1 = fixIndex8(_mm256_add_epi32(yb, splati(1)), h, t.wrapV());
  const I8 r0 = _mm256_add_epi32(off, _mm256_mullo_epi32(y0, w)),
           r1 = _mm256_add_epi32(off, _mm256_mullo_epi32(y1, w));
  const int* base = reinterpret_cast<const int*>(t.texels());
  const I8 zero = _mm256_setzero_si256();
  const I8 p00 = _mm256_mask_i32gather_epi32(zero, base, _mm256_add_epi32(r0, x0), mask, 4);
  const I8 p10 = _mm256_mask_i32gather_epi32(zero, base, _mm256_add_epi32(r0, x1), mask, 4);
  const I8 p01 = _mm256_mask_i32gather_epi32(zero, base, _mm256_add_epi32(r1, x0), mask, 4);
  const I8 p11 = _mm256_mask_i32gather_epi32(zero, base, _mm256_add_epi32(r1, x1), mask, 4);
  return lerpTexel8(lerpTexel8(p00, p10, fx), lerpTexel8(p01, p11, fx), fy);
}

// Texture::sample for eight lanes.
inline I8 sample8(const Texture& t, F8 u, F8 v, F8 dudx, F8 dvdx, F8 dudy, F8 dvdy, I8 mask) {
  const F8 tw = splat(static_cast<float>(t.widths()[0])),
           th = splat(static_cast<float>(t.heights()[0]));
  const F8 ax = _mm256_mul_ps(dudx, tw), ay = _mm256_mul_ps(dvdx, th), bx = _mm256_mul_ps(dudy, tw),
           by = _mm256_mul_ps(dvdy, th);
  const F8 rho2 = vmax(_mm256_add_ps(_mm256_mul_ps(ax, ax), _mm256_mul_ps(ay, ay)),
                       _mm256_add_ps(_mm256_mul_ps(bx, bx), _mm256_mul_ps(by, by)));
  const int levels = t.levels();
  if (levels == 1) return fetch8(t, _mm256_setzero_si256(), u, v, mask);
  // chooseLevels() lane by lane.
  const I8 small =
      _mm256_castps_si256(_mm256_cmp_ps(rho2, splat(1.f), _CMP_NGT_UQ));  // !(rho2 > 1)
  const F8 lod = _mm256_mul_ps(splat(0.5f), log2v(rho2));
  const I8 top =
      _mm256_castps_si256(_mm256_cmp_ps(lod, splat(static_cast<float>(levels - 1)), _CMP_GE_OQ));
  const I8 l0 = _mm256_cvttps_epi32(lod);
  const F8 tt = _mm256_mul_ps(
      _mm256_sub_ps(_mm256_sub_ps(lod, _mm256_cvtepi32_ps(l0)), splat(0.25f)), splat(2.f));
  I8 wmid = _mm256_cvttps_epi32(_mm256_mul_ps(tt, splat(256.f)));
  wmid = iselect(wmid, _mm256_setzero_si256(),
                 _mm256_castps_si256(_mm256_cmp_ps(tt, splat(0.f), _CMP_LE_OQ)));
  wmid = iselect(wmid, splati(256), _mm256_castps_si256(_mm256_cmp_ps(tt, splat(1.f), _CMP_GE_OQ)));
  const I8 last = splati(levels - 1);
  const I8 flat_level = iselect(_mm256_setzero_si256(), last, _mm256_andnot_si256(small, top));
  const I8 single = _mm256_or_si256(small, top);
  const I8 first = iselect(l0, flat_level, single);
  const I8 second = iselect(_mm256_add_epi32(l0, splati(1)), flat_level, single);
  const I8 weight = iselect(wmid, _mm256_setzero_si256(), single);
  const int w0 = _mm256_movemask_ps(_mm256_castsi256_ps(
      _mm256_and_si256(mask, _mm256_cmpeq_epi32(weight, _mm256_setzero_si256()))));
  const int w256 = _mm256_movemask_ps(
      _mm256_castsi256_ps(_mm256_and_si256(mask, _mm256_cmpeq_epi32(weight, splati(256)))));
  const int active = _mm256_movemask_ps(_mm256_castsi256_ps(mask));
  if (w0 == active) return fetch8(t, first, u, v, mask);
  if (w256 == active) return fetch8(t, second, u, v, mask);
  return lerpTexel8(fetch8(t, first, u, v, mask), fetch8(t, second, u, v, mask), weight);
}

// The shadow and ambient-occlusion maps (same size) at (su, sv), bilinear, for the lanes of
// `mask`: the operations of shadePixel's lookup, in its order.
inline void shadowAndAo8(const ScalarMap& A, const ScalarMap& B, F8 su, F8 sv, I8 mask, F8* a,
                         F8* b) {
  const int W = A.width(), H = A.height();
  F8 px = _mm256_sub_ps(_mm256_mul_ps(su, splat(static_cast<float>(W))), splat(0.5f));
  F8 py = _mm256_sub_ps(_mm256_mul_ps(sv, splat(static_cast<float>(H))), splat(0.5f));
  px = vmin(vmax(px, _mm256_setzero_ps()), splat(static_cast<float>(W - 1)));
  py = vmin(vmax(py, _mm256_setzero_ps()), splat(static_cast<float>(H - 1)));
  const I8 x0 = _mm256_cvttps_epi32(px), y0 = _mm256_cvttps_epi32(py);
  const I8 x1 = imin(_mm256_add_epi32(x0, splati(1)), splati(W - 1)),
           y1 = imin(_mm256_add_epi32(y0, splati(1)), splati(H - 1));
  const F8 fx = _mm256_sub_ps(px, _mm256_cvtepi32_ps(x0)),
           fy = _mm256_sub_ps(py, _mm256_cvtepi32_ps(y0));
  const F8 one = splat(1.f);
  const F8 w00 = _mm256_mul_ps(_mm256_sub_ps(one, fx), _mm256_sub_ps(one, fy)),
           w10 = _mm256_mul_ps(fx, _mm256_sub_ps(one, fy));
  const F8 w01 = _mm256_mul_ps(_mm256_sub_ps(one, fx), fy), w11 = _mm256_mul_ps(fx, fy);
  const I8 wv = splati(W);
  const I8 i00 = _mm256_add_epi32(_mm256_mullo_epi32(y0, wv), x0),
           i10 = _mm256_add_epi32(_mm256_mullo_epi32(y0, wv), x1);
  const I8 i01 = _mm256_add_epi32(_mm256_mullo_epi32(y1, wv), x0),
           i11 = _mm256_add_epi32(_mm256_mullo_epi32(y1, wv), x1);
  const F8 maskf = _mm256_castsi256_ps(mask), zf = _mm256_setzero_ps();
  auto bil = [&](const float* d) {
    const F8 a00 = _mm256_mask_i32gather_ps(zf, d, i00, maskf, 4),
             a10 = _mm256_mask_i32gather_ps(zf, d, i10, maskf, 4);
    const F8 a01 = _mm256_mask_i32gather_ps(zf, d, i01, maskf, 4),
             a11 = _mm256_mask_i32gather_ps(zf, d, i11, maskf, 4);
    return _mm256_add_ps(
        _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(w00, a00), _mm256_mul_ps(w10, a10)),
                      _mm256_mul_ps(w01, a01)),
        _mm256_mul_ps(w11, a11));
  };
  *a = bil(A.data());
  *b = bil(B.data());
}

}  // namespace

void Rasterizer::shadeSpan8(const Setup& S, int x, float y, size_t index, int n,
                            const void* target_ptr) const {
  const ShadeTarget& T = *static_cast<const ShadeTarget*>(target_ptr);
  const I8 lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const I8 mask = _mm256_cmpgt_epi32(splati(n), lane);
  const F8 xv = _mm256_cvtepi32_ps(_mm256_add_epi32(splati(x), lane));
  const F8 iz = affine(S.iz, xv, y);
  const F8 z = _mm256_div_ps(splat(1.f), iz);
  _mm256_maskstore_ps(T.depth + index, mask, z);
  for (int k = 0; k < n; ++k)
    T.object[index + static_cast<size_t>(k)] = static_cast<int16_t>(S.object);
  const F8 b1 = _mm256_mul_ps(affine(S.q1, xv, y), z);
  const F8 b2 = _mm256_mul_ps(affine(S.q2, xv, y), z);
  const Material& mat = *S.mat;
  auto interp = [&](float a0, float d1, float d2) {
    return _mm256_add_ps(_mm256_add_ps(splat(a0), _mm256_mul_ps(b1, splat(d1))),
                         _mm256_mul_ps(b2, splat(d2)));
  };
  F8 alb[3] = {splat(1.f), splat(1.f), splat(1.f)};
  if (mat.texture) {
    const F8 u = interp(S.uv0[0], S.duv1[0], S.duv2[0]);
    const F8 v = interp(S.uv0[1], S.duv1[1], S.duv2[1]);
    const F8 db1x =
        _mm256_mul_ps(_mm256_sub_ps(splat(S.q1[0]), _mm256_mul_ps(b1, splat(S.iz[0]))), z);
    const F8 db1y =
        _mm256_mul_ps(_mm256_sub_ps(splat(S.q1[1]), _mm256_mul_ps(b1, splat(S.iz[1]))), z);
    const F8 db2x =
        _mm256_mul_ps(_mm256_sub_ps(splat(S.q2[0]), _mm256_mul_ps(b2, splat(S.iz[0]))), z);
    const F8 db2y =
        _mm256_mul_ps(_mm256_sub_ps(splat(S.q2[1]), _mm256_mul_ps(b2, splat(S.iz[1]))), z);
    auto deriv = [&](float d1, float d2, F8 a, F8 b) {
      return _mm256_add_ps(_mm256_mul_ps(splat(d1), a), _mm256_mul_ps(splat(d2), b));
    };
    const I8 t =
        sample8(*mat.texture, u, v, deriv(S.duv1[0], S.duv2[0], db1x, db2x),
                deriv(S.duv1[1], S.duv2[1], db1x, db2x), deriv(S.duv1[0], S.duv2[0], db1y, db2y),
                deriv(S.duv1[1], S.duv2[1], db1y, db2y), mask);
    const I8 ff = splati(0xFF);
    alb[0] = _mm256_mul_ps(splat(kInv255), _mm256_cvtepi32_ps(_mm256_and_si256(t, ff)));
    alb[1] = _mm256_mul_ps(splat(kInv255),
                           _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(t, 8), ff)));
    alb[2] = _mm256_mul_ps(splat(kInv255),
                           _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(t, 16), ff)));
  }
  F8 amb[3], dif[3], refl[3];
  if (S.flat) {
    for (int c = 0; c < 3; ++c) {
      amb[c] = splat(S.amb[c]);
      dif[c] = splat(S.dif[c]);
      refl[c] = splat(S.refl[c]);
    }
  } else {
    F8 nv[3];
    for (int k = 0; k < 3; ++k) nv[k] = interp(S.n0[k], S.dn1[k], S.dn2[k]);
    const F8 len2 = _mm256_add_ps(
        _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nv[0], nv[0]), _mm256_mul_ps(nv[1], nv[1])),
                      _mm256_mul_ps(nv[2], nv[2])),
        splat(1e-20f));
    const F8 inv_len = _mm256_div_ps(splat(1.f), _mm256_sqrt_ps(len2));
    for (int k = 0; k < 3; ++k) nv[k] = _mm256_mul_ps(nv[k], inv_len);
    // lightTermsScalar, lane by lane.
    const F8 ndl = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nv[0], splat(l_cam_[0])),
                                               _mm256_mul_ps(nv[1], splat(l_cam_[1]))),
                                 _mm256_mul_ps(nv[2], splat(l_cam_[2])));
    const F8 nup = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nv[0], splat(up_cam_[0])),
                                               _mm256_mul_ps(nv[1], splat(up_cam_[1]))),
                                 _mm256_mul_ps(nv[2], splat(up_cam_[2])));
    const F8 hemi = _mm256_add_ps(splat(0.5f), _mm256_mul_ps(splat(0.5f), nup));
    const F8 lit = _mm256_cmp_ps(ndl, _mm256_setzero_ps(), _CMP_GT_OQ);
    const F8 d = _mm256_blendv_ps(_mm256_setzero_ps(), ndl, lit);
    for (int c = 0; c < 3; ++c) {
      const float g = light_.ground[c], sk = light_.sky[c];
      amb[c] = _mm256_mul_ps(splat(mat.tint[c]),
                             _mm256_add_ps(splat(g), _mm256_mul_ps(hemi, splat(sk - g))));
      dif[c] = _mm256_mul_ps(splat(mat.tint[c] * light_.sun[c]), d);
    }
    const F8 two_ndl = _mm256_mul_ps(splat(2.f), ndl);
    for (int k = 0; k < 3; ++k)
      refl[k] = _mm256_blendv_ps(
          _mm256_setzero_ps(), _mm256_sub_ps(_mm256_mul_ps(two_ndl, nv[k]), splat(l_cam_[k])), lit);
  }
  F8 shadow = splat(1.f), ao = splat(1.f);
  if (mat.shadow) {
    shadowAndAo8(*mat.shadow, *mat.ao, interp(S.uw0[0], S.duw1[0], S.duw2[0]),
                 interp(S.uw0[1], S.duw1[1], S.duw2[1]), mask, &shadow, &ao);
  }
  const F8 rx = _mm256_maskload_ps(T.rx + index, mask), ry = _mm256_maskload_ps(T.ry + index, mask);
  const F8 rz = _mm256_maskload_ps(T.rz + index, mask);
  F8 sp = _mm256_sub_ps(
      _mm256_setzero_ps(),
      _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(refl[0], rx), _mm256_mul_ps(refl[1], ry)),
                    _mm256_mul_ps(refl[2], rz)));
  sp =
      _mm256_blendv_ps(_mm256_setzero_ps(), sp, _mm256_cmp_ps(sp, _mm256_setzero_ps(), _CMP_GT_OQ));
  for (int i = 0; i < mat.shininess_log2 && i < 7; ++i) sp = _mm256_mul_ps(sp, sp);
  const F8 spec = _mm256_mul_ps(_mm256_mul_ps(splat(mat.specular), sp), shadow);
  float* out[3] = {T.b, T.g, T.r};
  for (int c = 0; c < 3; ++c) {
    const F8 v = _mm256_add_ps(_mm256_mul_ps(alb[c], _mm256_add_ps(_mm256_mul_ps(amb[c], ao),
                                                                   _mm256_mul_ps(dif[c], shadow))),
                               _mm256_mul_ps(spec, splat(light_.sun[c])));
    _mm256_maskstore_ps(out[c] + index, mask, v);
  }
}
#endif

void Rasterizer::shade(const Intrinsics& K, const Viewport& vp, FrameBuffers* out, bool colour) {
  const size_t npx = static_cast<size_t>(vp.w) * static_cast<size_t>(vp.h);
  out->depth.assign(npx, 0.f);
  out->object.assign(npx, -1);
  if (colour) out->bgr.assign(npx * 3, 0.f);
  if (rays_.size() != npx * 3 || rays_K_.fx != K.fx || rays_K_.fy != K.fy || rays_K_.cx != K.cx ||
      rays_K_.cy != K.cy || rays_vp_.x0 != vp.x0 || rays_vp_.y0 != vp.y0 || rays_vp_.w != vp.w ||
      rays_vp_.h != vp.h) {
    rays_.resize(npx * 3);
    for (int j = 0; j < vp.h; ++j)
      for (int i = 0; i < vp.w; ++i) {
        const float rx = (static_cast<float>(vp.x0 + i) - K.cx) / K.fx,
                    ry = (static_cast<float>(vp.y0 + j) - K.cy) / K.fy;
        const float inv = 1.f / std::sqrt(rx * rx + ry * ry + 1.f);
        const size_t index = static_cast<size_t>(j) * vp.w + i;
        rays_[index] = rx * inv;
        rays_[npx + index] = ry * inv;
        rays_[2 * npx + index] = inv;
      }
    rays_K_ = K;
    rays_vp_ = vp;
  }
  ShadeTarget T;
  T.b = colour ? out->bgr.data() : nullptr;
  T.g = colour ? out->bgr.data() + npx : nullptr;
  T.r = colour ? out->bgr.data() + 2 * npx : nullptr;
  T.depth = out->depth.data();
  T.object = out->object.data();
  T.rx = rays_.data();
  T.ry = rays_.data() + npx;
  T.rz = rays_.data() + 2 * npx;
  const uint32_t* setup = out->setup.data();
  for (int j = 0; j < vp.h; ++j) {
    const float y = static_cast<float>(vp.y0 + j);
    const size_t row = static_cast<size_t>(j) * vp.w;
    int i = 0;
    while (i < vp.w) {
      const uint32_t sidx = setup[row + static_cast<size_t>(i)];
      int e = i + 1;
      while (e < vp.w && setup[row + static_cast<size_t>(e)] == sidx) ++e;
      if (sidx != kNone) {
        const Setup& S = setups_[sidx];
#if SLAMAWARE_SYNTH_AVX2
        if (colour && vector_) {
          for (int k = i; k < e; k += 8)
            shadeSpan8(S, vp.x0 + k, y, row + static_cast<size_t>(k), std::min(8, e - k), &T);
        } else
#endif
        {
          for (int k = i; k < e; ++k)
            shadePixel(S, static_cast<float>(vp.x0 + k), y, row + static_cast<size_t>(k), &T,
                       colour);
        }
      }
      i = e;
    }
  }
}

int64_t Rasterizer::silhouettePixels(const RenderScene& scene, int object, const Intrinsics& K,
                                     const Eigen::Isometry3d& T_world_camera, const Viewport& vp) {
  if (object < 0 || object >= scene.objectCount()) return 0;
  const auto range = scene.objectRanges()[object];
  const Eigen::Isometry3d T_cw = T_world_camera.inverse();
  const Eigen::Matrix3f R = T_cw.linear().cast<float>();
  const Eigen::Vector3f tr = T_cw.translation().cast<float>();
  mask_.assign(static_cast<size_t>(vp.w) * static_cast<size_t>(vp.h), 0);
  int64_t count = 0;
  const auto& V = scene.vertices();
  for (uint32_t ti = range.begin; ti < range.end; ++ti) {
    const FlatTriangle& t = scene.triangles()[ti];
    const Eigen::Vector3f P[3] = {R * V[t.v[0]].p + tr, R * V[t.v[1]].p + tr, R * V[t.v[2]].p + tr};
    if (P[0].z() < kNear && P[1].z() < kNear && P[2].z() < kNear) continue;
    const Eigen::Vector3f N = (P[1] - P[0]).cross(P[2] - P[0]);
    const float d = N.dot(P[0]);
    if (!(N.squaredNorm() > 0.f) || d == 0.f) continue;
    if (d > 0.f && !scene.materials[t.material].double_sided) continue;
    Eigen::Vector3f poly[4];
    const int n = clipNear(P, kNear, poly);
    if (n < 3) continue;
    rasterPolygon(poly, n, K, vp, [&](int, int, size_t index) {
      count += mask_[index] == 0;
      mask_[index] = 1;
    });
  }
  return count;
}

bool Rasterizer::projectedBounds(const RenderScene& scene, int object, const Intrinsics& K,
                                 const Eigen::Isometry3d& T_world_camera, Eigen::Vector4f* box) {
  if (object < 0 || object >= scene.objectCount()) return false;
  const auto range = scene.objectRanges()[object];
  if (range.begin == range.end) return false;
  const Eigen::Isometry3d T_cw = T_world_camera.inverse();
  const Eigen::Matrix3f R = T_cw.linear().cast<float>();
  const Eigen::Vector3f tr = T_cw.translation().cast<float>();
  float x0 = std::numeric_limits<float>::max(), y0 = x0, x1 = -x0, y1 = -x0;
  for (uint32_t ti = range.begin; ti < range.end; ++ti) {
    for (uint32_t vi : scene.triangles()[ti].v) {
      const Eigen::Vector3f p = R * scene.vertices()[vi].p + tr;
      if (p.z() < kNear) return false;
      const float u = K.fx * p.x() / p.z() + K.cx, v = K.fy * p.y() / p.z() + K.cy;
      x0 = std::min(x0, u);
      x1 = std::max(x1, u);
      y0 = std::min(y0, v);
      y1 = std::max(y1, v);
    }
  }
  *box = {x0, y0, x1, y1};
  return true;
}

float HeightMap::at(const Eigen::Vector3f& p) const {
  const Eigen::Vector3f q = p - origin;
  const int x = static_cast<int>(std::floor(q.dot(axis_u) / texel));
  const int y = static_cast<int>(std::floor(q.dot(axis_v) / texel));
  if (x < 0 || y < 0 || x >= w || y >= h) return -std::numeric_limits<float>::infinity();
  return height[static_cast<size_t>(y) * w + x];
}

float HeightMap::occlusion(const Eigen::Vector3f& p, float radius, float bias) const {
  const float hp = dir.dot(p) + bias;
  int hits = 0;
  for (int j = -1; j <= 1; ++j)
    for (int i = -1; i <= 1; ++i)
      hits +=
          at(p + radius * (static_cast<float>(i) * axis_u + static_cast<float>(j) * axis_v)) > hp;
  return static_cast<float>(hits) / 9.f;
}

HeightMap renderHeightMap(const RenderScene& scene, const std::vector<int>& items,
                          const Eigen::Vector3f& dir_in, const Eigen::Vector3f& axis_u_in,
                          const Eigen::Vector3f& centre, float half_extent, float texel) {
  HeightMap hm;
  hm.dir = dir_in.normalized();
  hm.axis_u = (axis_u_in - axis_u_in.dot(hm.dir) * hm.dir).normalized();
  hm.axis_v = hm.dir.cross(hm.axis_u);
  const Eigen::Vector3f axis_v = hm.axis_v;
  hm.texel = texel;
  hm.w = hm.h = std::max(1, static_cast<int>(std::ceil(2.f * half_extent / texel)));
  hm.origin = centre - half_extent * hm.axis_u - half_extent * axis_v;
  hm.height.assign(static_cast<size_t>(hm.w) * hm.h, -std::numeric_limits<float>::infinity());
  const Viewport vp{0, 0, hm.w, hm.h};
  for (int item : items) {
    const Mesh& m = scene.items[static_cast<size_t>(item)].mesh;
    for (const auto& t : m.triangles) {
      float xs[3], ys[3], hs[3];
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3f q = m.vertices[t[k]].p - hm.origin;
        xs[k] = q.dot(hm.axis_u) / texel - 0.5f;  // texel centres at integers
        ys[k] = q.dot(axis_v) / texel - 0.5f;
        hs[k] = hm.dir.dot(m.vertices[t[k]].p);
      }
      // Height as an affine function of the grid position.
      const float ax = xs[1] - xs[0], ay = ys[1] - ys[0], bx = xs[2] - xs[0], by = ys[2] - ys[0];
      const float det = ax * by - ay * bx;
      if (std::fabs(det) < 1e-9f) continue;
      const float dh1 = hs[1] - hs[0], dh2 = hs[2] - hs[0];
      const float gx = (dh1 * by - dh2 * ay) / det, gy = (dh2 * ax - dh1 * bx) / det;
      rasterize(xs, ys, vp, [&](int x, int y, size_t index) {
        const float h =
            hs[0] + gx * (static_cast<float>(x) - xs[0]) + gy * (static_cast<float>(y) - ys[0]);
        if (h > hm.height[index]) hm.height[index] = h;
      });
    }
  }
  return hm;
}

}  // namespace slamaware::synth
