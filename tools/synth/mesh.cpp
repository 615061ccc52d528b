#include "tools/synth/mesh.h"

#include <cmath>
#include <stdexcept>

namespace slamaware::synth {

namespace {

constexpr float kTwoPi = 6.28318530718f;

void addFace(Mesh& m, const Eigen::Vector3f& p0, const Eigen::Vector3f& a, const Eigen::Vector3f& b,
             const Eigen::Vector3f& outward, const std::array<float, 4>& uvr) {
  // Corners p0, p0 + a, p0 + a + b, p0 + b with uv from the rectangle (u along a, v along b).
  const uint32_t base = static_cast<uint32_t>(m.vertices.size());
  const Eigen::Vector3f n = outward.normalized();
  const Eigen::Vector3f pts[4] = {p0, p0 + a, p0 + a + b, p0 + b};
  const float us[4] = {uvr[0], uvr[2], uvr[2], uvr[0]};
  const float vs[4] = {uvr[1], uvr[1], uvr[3], uvr[3]};
  for (int i = 0; i < 4; ++i) {
    Vertex v;
    v.p = pts[i];
    v.n = n;
    v.uv = {us[i], vs[i]};
    m.vertices.push_back(v);
  }
  if (a.cross(b).dot(n) > 0) {
    m.triangles.push_back({base, base + 1, base + 2});
    m.triangles.push_back({base, base + 2, base + 3});
  } else {
    m.triangles.push_back({base, base + 2, base + 1});
    m.triangles.push_back({base, base + 3, base + 2});
  }
}

}  // namespace

void Mesh::append(const Mesh& other) {
  const uint32_t base = static_cast<uint32_t>(vertices.size());
  vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
  for (const auto& t : other.triangles)
    triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

void Mesh::transform(const Eigen::Affine3f& T) {
  const Eigen::Matrix3f N = T.linear().inverse().transpose();
  for (auto& v : vertices) {
    v.p = T * v.p;
    const Eigen::Vector3f n = N * v.n;
    const float len = n.norm();
    v.n = len > 0 ? Eigen::Vector3f(n / len) : Eigen::Vector3f::UnitZ();
  }
  if (T.linear().determinant() < 0) {
    for (auto& t : triangles) std::swap(t[1], t[2]);
  }
}

Eigen::AlignedBox3f Mesh::bounds() const {
  Eigen::AlignedBox3f b;
  for (const auto& v : vertices) b.extend(v.p);
  return b;
}

double Mesh::signedVolume() const {
  double vol = 0;
  for (const auto& t : triangles) {
    const Eigen::Vector3d a = vertices[t[0]].p.cast<double>(), b = vertices[t[1]].p.cast<double>(),
                          c = vertices[t[2]].p.cast<double>();
    vol += a.dot(b.cross(c));
  }
  return vol / 6.0;
}

void Mesh::flip() {
  for (auto& t : triangles) std::swap(t[1], t[2]);
  for (auto& v : vertices) v.n = -v.n;
}

void Mesh::planarUv(const Eigen::Vector3f& du, float u0, const Eigen::Vector3f& dv, float v0) {
  for (auto& v : vertices) v.uv = {du.dot(v.p) + u0, dv.dot(v.p) + v0};
}

Mesh gridMesh(int rows, int cols, const std::vector<Eigen::Vector3f>& points,
              const std::vector<Eigen::Vector2f>& uvs, bool seam) {
  return gridMeshWithBreaks(rows, cols, points, uvs, seam, {});
}

Mesh gridMeshWithBreaks(int rows, int cols, const std::vector<Eigen::Vector3f>& points,
                        const std::vector<Eigen::Vector2f>& uvs, bool seam,
                        const std::vector<bool>& row_break) {
  if (rows < 2 || cols < 2 || points.size() != static_cast<size_t>(rows) * cols ||
      uvs.size() != points.size())
    throw std::invalid_argument("gridMesh: sizes do not match");
  Mesh m;
  m.vertices.resize(points.size());
  std::vector<Eigen::Vector3f> acc(points.size(), Eigen::Vector3f::Zero());
  auto idx = [cols](int r, int c) { return static_cast<uint32_t>(r * cols + c); };
  for (int r = 0; r + 1 < rows; ++r) {
    if (!row_break.empty() && row_break[r]) continue;
    for (int c = 0; c + 1 < cols; ++c) {
      const uint32_t a = idx(r, c), b = idx(r, c + 1), d = idx(r + 1, c + 1), e = idx(r + 1, c);
      for (const auto& t : {std::array<uint32_t, 3>{a, b, d}, std::array<uint32_t, 3>{a, d, e}}) {
        const Eigen::Vector3f fn = (points[t[1]] - points[t[0]]).cross(points[t[2]] - points[t[0]]);
        if (fn.squaredNorm() <= 0) continue;  // degenerate (at a pole): no triangle
        m.triangles.push_back(t);
        for (uint32_t k : t) acc[k] += fn;
      }
    }
  }
  if (seam) {
    for (int r = 0; r < rows; ++r) {
      const Eigen::Vector3f s = acc[idx(r, 0)] + acc[idx(r, cols - 1)];
      acc[idx(r, 0)] = acc[idx(r, cols - 1)] = s;
    }
  }
  // Rows collapsed to a point (poles): one normal for the whole row.
  for (int r = 0; r < rows; ++r) {
    bool collapsed = true;
    for (int c = 1; c < cols && collapsed; ++c)
      collapsed = (points[idx(r, c)] - points[idx(r, 0)]).squaredNorm() < 1e-14f;
    if (!collapsed) continue;
    Eigen::Vector3f s = Eigen::Vector3f::Zero();
    for (int c = 0; c < cols; ++c) s += acc[idx(r, c)];
    for (int c = 0; c < cols; ++c) acc[idx(r, c)] = s;
  }
  for (size_t i = 0; i < points.size(); ++i) {
    m.vertices[i].p = points[i];
    m.vertices[i].uv = uvs[i];
    const float len = acc[i].norm();
    m.vertices[i].n = len > 0 ? Eigen::Vector3f(acc[i] / len) : Eigen::Vector3f::UnitZ();
  }
  return m;
}

Mesh lathe(const std::vector<ProfilePoint>& profile, int segments, float u_repeat,
           const std::function<float(float, float)>& radial) {
  if (profile.size() < 2 || segments < 3)
    throw std::invalid_argument("lathe: need 2 profile points, 3 segments");
  const size_t n = profile.size();
  std::vector<float> arc(n, 0.f);
  for (size_t i = 1; i < n; ++i)
    arc[i] =
        arc[i - 1] + std::hypot(profile[i].r - profile[i - 1].r, profile[i].z - profile[i - 1].z);
  const float total = arc.back() > 0 ? arc.back() : 1.f;
  // Rows: a profile point, twice at an inner crease (the two copies get the two sides' normals).
  struct Row {
    size_t i;
  };
  std::vector<Row> rows;
  std::vector<bool> breaks;
  for (size_t i = 0; i < n; ++i) {
    rows.push_back({i});
    breaks.push_back(false);
    if (profile[i].crease && i > 0 && i + 1 < n) {
      breaks.back() = true;  // no quad between the two copies
      rows.push_back({i});
      breaks.push_back(false);
    }
  }
  const int R = static_cast<int>(rows.size()), C = segments + 1;
  std::vector<Eigen::Vector3f> pts(static_cast<size_t>(R) * C);
  std::vector<Eigen::Vector2f> uvs(pts.size());
  for (int r = 0; r < R; ++r) {
    const ProfilePoint& pp = profile[rows[r].i];
    const float t = n > 1 ? static_cast<float>(rows[r].i) / static_cast<float>(n - 1) : 0.f;
    const float v = pp.v >= 0 ? pp.v : arc[rows[r].i] / total;
    for (int c = 0; c < C; ++c) {
      const float s = static_cast<float>(c) / static_cast<float>(segments);
      const float phi = kTwoPi * s;
      const float rr = pp.r * (radial ? radial(phi, t) : 1.f);
      pts[static_cast<size_t>(r) * C + c] =
          c == segments ? pts[static_cast<size_t>(r) * C]
                        : Eigen::Vector3f(rr * std::cos(phi), rr * std::sin(phi), pp.z);
      uvs[static_cast<size_t>(r) * C + c] = {s * u_repeat, 1.f - v};
    }
  }
  return gridMeshWithBreaks(R, C, pts, uvs, true, breaks);
}

Mesh parametricSphere(const std::function<Eigen::Vector3f(float, float)>& fn, int segments,
                      int rings, float u_repeat) {
  const int R = rings + 1, C = segments + 1;
  std::vector<Eigen::Vector3f> pts(static_cast<size_t>(R) * C);
  std::vector<Eigen::Vector2f> uvs(pts.size());
  for (int r = 0; r < R; ++r) {
    const float t = static_cast<float>(r) / static_cast<float>(rings);
    for (int c = 0; c < C; ++c) {
      const float s = static_cast<float>(c) / static_cast<float>(segments);
      pts[static_cast<size_t>(r) * C + c] =
          c == segments ? pts[static_cast<size_t>(r) * C] : fn(s, t);
      uvs[static_cast<size_t>(r) * C + c] = {s * u_repeat, 1.f - t};
    }
  }
  Mesh m = gridMesh(R, C, pts, uvs, true);
  if (m.signedVolume() < 0) m.flip();
  return m;
}

Mesh sweep(const std::vector<Eigen::Vector3f>& curve, const std::function<float(float)>& radius,
           int sides, bool caps, float ratio, const Eigen::Vector3f& up_hint) {
  const int n = static_cast<int>(curve.size());
  if (n < 2 || sides < 3) throw std::invalid_argument("sweep: need 2 curve points, 3 sides");
  std::vector<Eigen::Vector3f> T(n), N(n), B(n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3f d = curve[std::min(i + 1, n - 1)] - curve[std::max(i - 1, 0)];
    T[i] = d.normalized();
  }
  // Parallel transport of the first normal along the curve.
  Eigen::Vector3f n0 = up_hint - up_hint.dot(T[0]) * T[0];
  if (n0.norm() < 1e-4f) n0 = T[0].unitOrthogonal();
  N[0] = n0.normalized();
  for (int i = 1; i < n; ++i) {
    Eigen::Vector3f v = N[i - 1] - N[i - 1].dot(T[i]) * T[i];
    if (v.norm() < 1e-6f) v = T[i].unitOrthogonal();
    N[i] = v.normalized();
  }
  for (int i = 0; i < n; ++i) B[i] = T[i].cross(N[i]);
  std::vector<float> arc(n, 0.f);
  for (int i = 1; i < n; ++i) arc[i] = arc[i - 1] + (curve[i] - curve[i - 1]).norm();
  const float total = arc.back() > 0 ? arc.back() : 1.f;
  const int C = sides + 1;
  std::vector<Eigen::Vector3f> pts(static_cast<size_t>(n) * C);
  std::vector<Eigen::Vector2f> uvs(pts.size());
  for (int i = 0; i < n; ++i) {
    const float t = arc[i] / total;
    const float r = radius(t);
    for (int c = 0; c < C; ++c) {
      const float s = static_cast<float>(c) / static_cast<float>(sides);
      const float th = kTwoPi * s;
      pts[static_cast<size_t>(i) * C + c] =
          c == sides
              ? pts[static_cast<size_t>(i) * C]
              : Eigen::Vector3f(curve[i] + r * (std::cos(th) * N[i] + ratio * std::sin(th) * B[i]));
      uvs[static_cast<size_t>(i) * C + c] = {s, t};
    }
  }
  Mesh m = gridMesh(n, C, pts, uvs, true);
  if (caps) {
    for (int end = 0; end < 2; ++end) {
      const int i = end == 0 ? 0 : n - 1;
      const Eigen::Vector3f out = end == 0 ? Eigen::Vector3f(-T[0]) : T[n - 1];
      const uint32_t centre = static_cast<uint32_t>(m.vertices.size());
      Vertex cv;
      cv.p = curve[i];
      cv.n = out;
      cv.uv = {0.5f, end == 0 ? 0.f : 1.f};
      m.vertices.push_back(cv);
      for (int c = 0; c < sides; ++c) {
        Vertex v;
        v.p = pts[static_cast<size_t>(i) * C + c];
        v.n = out;
        v.uv = cv.uv;
        m.vertices.push_back(v);
      }
      for (int c = 0; c < sides; ++c) {
        const uint32_t a = centre + 1 + static_cast<uint32_t>(c);
        const uint32_t b = centre + 1 + static_cast<uint32_t>((c + 1) % sides);
        const Eigen::Vector3f fn = (m.vertices[a].p - cv.p).cross(m.vertices[b].p - cv.p);
        if (fn.dot(out) >= 0)
          m.triangles.push_back({centre, a, b});
        else
          m.triangles.push_back({centre, b, a});
      }
    }
  }
  return m;
}

BoxAtlas boxAtlasLayout(const Eigen::Vector3f& size) {
  const float U = 2.f * (size.x() + size.y());
  const float V = size.z() + 2.f * size.y();
  BoxAtlas a;
  float u = 0;
  auto col = [&](float w, float v0, float v1) {
    std::array<float, 4> r{u / U, v0 / V, (u + w) / U, v1 / V};
    u += w;
    return r;
  };
  const float side0 = size.y(), side1 = size.y() + size.z();
  a.front = col(size.x(), side0, side1);
  a.right = col(size.y(), side0, side1);
  a.back = col(size.x(), side0, side1);
  a.left = col(size.y(), side0, side1);
  a.top = {0.f, 0.f, size.x() / U, size.y() / V};
  a.bottom = {0.f, side1 / V, size.x() / U, 1.f};
  return a;
}

Mesh box(const Eigen::Vector3f& size) {
  const Eigen::Vector3f h = size / 2.f;
  const BoxAtlas a = boxAtlasLayout(size);
  Mesh m;
  const Eigen::Vector3f X = Eigen::Vector3f::UnitX(), Y = Eigen::Vector3f::UnitY(),
                        Z = Eigen::Vector3f::UnitZ();
  // Sides: u runs around the box (front -> right -> back -> left), v downwards.
  addFace(m, {-h.x(), -h.y(), h.z()}, X * size.x(), -Z * size.z(), -Y, a.front);
  addFace(m, {h.x(), -h.y(), h.z()}, Y * size.y(), -Z * size.z(), X, a.right);
  addFace(m, {h.x(), h.y(), h.z()}, -X * size.x(), -Z * size.z(), Y, a.back);
  addFace(m, {-h.x(), h.y(), h.z()}, -Y * size.y(), -Z * size.z(), -X, a.left);
  // Top: v runs from the back edge to the front edge; bottom: from the front edge to the back.
  addFace(m, {-h.x(), h.y(), h.z()}, X * size.x(), -Y * size.y(), Z, a.top);
  addFace(m, {-h.x(), -h.y(), -h.z()}, X * size.x(), Y * size.y(), -Z, a.bottom);
  return m;
}

Mesh superquadric(const Eigen::Vector3f& half, float e_h, float e_v, int segments, int rings) {
  auto spow = [](float x, float e) { return std::copysign(std::pow(std::fabs(x), e), x); };
  return parametricSphere(
      [&](float s, float t) {
        const float phi = kTwoPi * s - 3.14159265f;  // seam at the back
        const float eta = 3.14159265f * (t - 0.5f);
        const float ce = spow(std::cos(eta), e_v), se = spow(std::sin(eta), e_v);
        return Eigen::Vector3f(half.x() * ce * spow(std::cos(phi), e_h),
                               half.y() * ce * spow(std::sin(phi), e_h), half.z() * se);
      },
      segments, rings);
}

std::vector<std::array<uint32_t, 3>> triangulatePolygon(const std::vector<Eigen::Vector2f>& poly) {
  std::vector<std::array<uint32_t, 3>> out;
  std::vector<uint32_t> idx(poly.size());
  for (size_t i = 0; i < poly.size(); ++i) idx[i] = static_cast<uint32_t>(i);
  auto cross = [](const Eigen::Vector2f& a, const Eigen::Vector2f& b, const Eigen::Vector2f& c) {
    return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
  };
  size_t guard = 0;
  while (idx.size() > 3 && guard++ < 10000) {
    bool clipped = false;
    const size_t m = idx.size();
    for (size_t i = 0; i < m; ++i) {
      const uint32_t ia = idx[(i + m - 1) % m], ib = idx[i], ic = idx[(i + 1) % m];
      const Eigen::Vector2f &a = poly[ia], &b = poly[ib], &c = poly[ic];
      if (cross(a, b, c) <= 0) continue;  // reflex
      bool inside = false;
      for (size_t j = 0; j < m && !inside; ++j) {
        const uint32_t k = idx[j];
        if (k == ia || k == ib || k == ic) continue;
        const Eigen::Vector2f& p = poly[k];
        inside = cross(a, b, p) >= 0 && cross(b, c, p) >= 0 && cross(c, a, p) >= 0;
      }
      if (inside) continue;
      out.push_back({ia, ib, ic});
      idx.erase(idx.begin() + static_cast<long>(i));
      clipped = true;
      break;
    }
    if (!clipped) break;  // not simple: give up on the rest
  }
  if (idx.size() == 3) out.push_back({idx[0], idx[1], idx[2]});
  return out;
}

Mesh extrude(const std::vector<Eigen::Vector2f>& poly, float z0, float z1, float uv_scale) {
  Mesh m;
  const auto tris = triangulatePolygon(poly);
  const uint32_t n = static_cast<uint32_t>(poly.size());
  for (int cap = 0; cap < 2; ++cap) {
    const uint32_t base = static_cast<uint32_t>(m.vertices.size());
    for (const auto& p : poly) {
      Vertex v;
      v.p = {p.x(), p.y(), cap ? z1 : z0};
      v.n = cap ? Eigen::Vector3f::UnitZ() : Eigen::Vector3f(-Eigen::Vector3f::UnitZ());
      v.uv = {p.x() * uv_scale, p.y() * uv_scale};
      m.vertices.push_back(v);
    }
    for (const auto& t : tris) {
      if (cap)
        m.triangles.push_back({base + t[0], base + t[1], base + t[2]});
      else
        m.triangles.push_back({base + t[0], base + t[2], base + t[1]});
    }
  }
  float perimeter = 0;
  for (uint32_t i = 0; i < n; ++i) perimeter += (poly[(i + 1) % n] - poly[i]).norm();
  float u = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const Eigen::Vector2f a = poly[i], b = poly[(i + 1) % n];
    const Eigen::Vector2f d = b - a;
    const float len = d.norm();
    if (len <= 0) continue;
    const Eigen::Vector3f out(d.y() / len, -d.x() / len, 0.f);
    addFace(m, {a.x(), a.y(), z0}, Eigen::Vector3f(d.x(), d.y(), 0.f),
            Eigen::Vector3f(0, 0, z1 - z0), out, {u / perimeter, 1.f, (u + len) / perimeter, 0.f});
    u += len;
  }
  return m;
}

Mesh quad(const Eigen::Vector3f& origin, const Eigen::Vector3f& a, const Eigen::Vector3f& b,
          float u_max, float v_max, int nx, int ny) {
  const int R = ny + 1, C = nx + 1;
  std::vector<Eigen::Vector3f> pts(static_cast<size_t>(R) * C);
  std::vector<Eigen::Vector2f> uvs(pts.size());
  for (int r = 0; r < R; ++r)
    for (int c = 0; c < C; ++c) {
      const float s = static_cast<float>(c) / static_cast<float>(nx),
                  t = static_cast<float>(r) / static_cast<float>(ny);
      pts[static_cast<size_t>(r) * C + c] = origin + s * a + t * b;
      uvs[static_cast<size_t>(r) * C + c] = {s * u_max, t * v_max};
    }
  Mesh m = gridMesh(R, C, pts, uvs, false);
  const Eigen::Vector3f n = a.cross(b).normalized();
  for (auto& v : m.vertices) v.n = n;
  return m;
}

}  // namespace slamaware::synth
