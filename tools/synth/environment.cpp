#include "tools/synth/environment.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "tools/synth/rasterizer.h"
#include "tools/synth/textures.h"

namespace slamaware::synth {

namespace {

constexpr float kPi = 3.14159265f;
using V3 = Eigen::Vector3f;

TexturePtr tex(const cv::Mat& m, bool wrap_u = false, bool wrap_v = false) {
  return std::make_shared<const Texture>(m, wrap_u, wrap_v);
}

int addItem(RenderScene* s, Mesh m, TexturePtr t, float spec = 0.04f, int shin = 4,
            int object = -1) {
  Material mat;
  mat.texture = std::move(t);
  mat.specular = spec;
  mat.shininess_log2 = shin;
  const int mi = s->addMaterial(mat);
  s->add(std::move(m), mi, object);
  return static_cast<int>(s->items.size()) - 1;
}

// A rectangle facing `facing`: uv (0..u_max) along a, (0..v_max) along b.
Mesh orientedQuad(const V3& origin, const V3& a, const V3& b, const V3& facing, int nx = 1,
                  int ny = 1) {
  Mesh m = quad(origin, a, b, 1.f, 1.f, nx, ny);
  if (a.cross(b).dot(facing) < 0) m.flip();
  return m;
}

// A box of size (w along u, d along -n, h) standing at floor point `base` (centre of its back
// edge on the wall), rotated so that its front (atlas "front", local -y) faces the room (n).
Eigen::Affine3f wallFrame(const V3& base, const V3& u, const V3& n) {
  Eigen::Matrix3f R;
  R.col(0) = u;
  R.col(1) = -n;
  R.col(2) = V3::UnitZ();
  Eigen::Affine3f T = Eigen::Affine3f::Identity();
  T.linear() = R;
  T.translation() = base;
  return T;
}

cv::Vec3f woodLight(Rng& r) {
  static const cv::Vec3f kTones[] = {{0.42f, 0.64f, 0.82f},
                                     {0.52f, 0.74f, 0.9f},
                                     {0.22f, 0.34f, 0.5f},
                                     {0.24f, 0.38f, 0.64f},
                                     {0.7f, 0.75f, 0.78f}};
  return kTones[r.range(0, 4)];
}

cv::Mat woodFor(Rng& r, float w, float h, float texel = 0.003f) {
  const cv::Vec3f light = woodLight(r);
  return woodTexture(r, w, h, texel, light, light * 0.6f);
}

struct WallSpan {
  V3 start, u, n;
  float length = 0;
  std::vector<std::pair<float, float>> used;  // occupied intervals along the wall
  bool reserve(float s0, float s1) {
    if (s0 < 0.05f || s1 > length - 0.05f) return false;
    for (const auto& iv : used)
      if (s0 < iv.second + 0.1f && s1 > iv.first - 0.1f) return false;
    used.push_back({s0, s1});
    return true;
  }
};

// Cardboard with tape and a printed label.
cv::Mat cardboard(Rng& r, int w, int h) {
  cv::Mat t = plasticTexture(
      r, w, h, hsvColor(r.uniformf(28.f, 38.f), r.uniformf(0.35f, 0.5f), r.uniformf(0.55f, 0.75f)),
      0.08f);
  cv::rectangle(t, cv::Point(0, h / 2 - h / 20), cv::Point(w, h / 2 + h / 20),
                cv::Scalar(150, 170, 185), -1);
  cv::putText(t, pseudoWord(r, 3, true), cv::Point(w / 8, h / 3), cv::FONT_HERSHEY_SIMPLEX,
              std::max(0.3, w / 250.0), cv::Scalar(40, 40, 50), std::max(1, w / 150), cv::LINE_AA);
  std::vector<cv::Point> arrow{{w * 3 / 4, h * 3 / 5},
                               {w * 3 / 4 + w / 16, h * 3 / 5 + h / 8},
                               {w * 3 / 4 - w / 16, h * 3 / 5 + h / 8}};
  cv::fillConvexPoly(t, arrow, cv::Scalar(30, 30, 40), cv::LINE_AA);
  return t;
}

void addBookshelf(RenderScene* s, Environment* env, Rng& r, const Eigen::Affine3f& F, float w,
                  float d, float h) {
  const float th = 0.02f;
  const cv::Mat wood = woodFor(r, 1.0f, 0.5f);
  auto panel = [&](const V3& size, const V3& centre) {
    Mesh m = box(size);
    m.transform(F * Eigen::Translation3f(centre));
    env->furniture_items.push_back(addItem(s, std::move(m), tex(wood, true, true), 0.08f, 4));
  };
  panel({th, d, h}, {-w / 2 + th / 2, -d / 2, h / 2});
  panel({th, d, h}, {w / 2 - th / 2, -d / 2, h / 2});
  panel({w, th, h}, {0, -th / 2, h / 2});
  const int shelves = std::max(3, static_cast<int>(h / 0.35f));
  const float gap = (h - th) / static_cast<float>(shelves);
  for (int i = 0; i <= shelves; ++i) {
    const float z = static_cast<float>(i) * gap;
    panel({w - 2 * th, d - th, th}, {0, -d / 2 - th / 2, z + th / 2});
    if (i == shelves) break;
    // Books (or boxes) on the shelf, their spines facing the room.
    const float bh = gap * r.uniformf(0.7f, 0.9f), bw = (w - 2 * th) * r.uniformf(0.6f, 1.f),
                bd = d * 0.75f;
    const float x0 = -w / 2 + th + r.uniformf(0.f, (w - 2 * th) - bw);
    int books = 0;
    cv::Mat spines = bookSpinesTexture(r, std::max(32, static_cast<int>(bw * 400)),
                                       std::max(16, static_cast<int>(bh * 400)), &books);
    Mesh front =
        orientedQuad(V3(x0, -d + 0.002f, z + th + bh), V3(bw, 0, 0), V3(0, 0, -bh), V3(0, -1, 0));
    front.transform(F);
    env->furniture_items.push_back(addItem(s, std::move(front), tex(spines), 0.05f, 3));
    Mesh top = orientedQuad(V3(x0, -d + 0.002f, z + th + bh * 0.95f), V3(bw, 0, 0), V3(0, bd, 0),
                            V3(0, 0, 1));
    top.transform(F);
    env->furniture_items.push_back(
        addItem(s, std::move(top), tex(cv::Mat(8, 8, CV_8UC3, cv::Scalar(60, 70, 80))), 0.02f, 3));
  }
}

void addCabinet(RenderScene* s, Environment* env, Rng& r, const Eigen::Affine3f& F, float w,
                float d, float h) {
  Mesh m = box(V3(w, d, h));
  m.transform(F * Eigen::Translation3f(0, -d / 2, h / 2));
  const cv::Vec3f light = woodLight(r);
  cv::Mat wood = woodTexture(r, w * 2 + d * 2, h + 2 * d, 0.003f, light, light * 0.6f);
  env->furniture_items.push_back(addItem(s, std::move(m), tex(wood), 0.1f, 4));
  // Doors / drawers on the front.
  cv::Mat front = woodTexture(r, w, h, 0.003f, light, light * 0.6f);
  const int doors = std::max(1, static_cast<int>(std::round(w / 0.45f)));
  const int fw = front.cols, fh = front.rows;
  const bool drawers = r.chance(0.4);
  for (int i = 0; i < doors; ++i) {
    const int x0 = i * fw / doors, x1 = (i + 1) * fw / doors;
    if (drawers) {
      for (int k = 0; k < 3; ++k) {
        const int y0 = k * fh / 3, y1 = (k + 1) * fh / 3;
        cv::rectangle(front, cv::Point(x0 + 3, y0 + 3), cv::Point(x1 - 3, y1 - 3),
                      cv::Scalar(30, 40, 55), 2, cv::LINE_AA);
        cv::rectangle(front, cv::Point((x0 + x1) / 2 - 20, (y0 + y1) / 2 - 4),
                      cv::Point((x0 + x1) / 2 + 20, (y0 + y1) / 2 + 4), cv::Scalar(170, 170, 175),
                      -1);
      }
    } else {
      cv::rectangle(front, cv::Point(x0 + 3, 3), cv::Point(x1 - 3, fh - 3), cv::Scalar(30, 40, 55),
                    2, cv::LINE_AA);
      cv::rectangle(front, cv::Point(x0 + 20, 20), cv::Point(x1 - 20, fh - 20),
                    cv::Scalar(50, 65, 85), 1, cv::LINE_AA);
      cv::circle(front, cv::Point(i % 2 ? x0 + 18 : x1 - 18, fh / 4), 6, cv::Scalar(160, 165, 170),
                 -1, cv::LINE_AA);
    }
  }
  Mesh fq = orientedQuad(V3(-w / 2, -d - 0.002f, h), V3(w, 0, 0), V3(0, 0, -h), V3(0, -1, 0));
  fq.transform(F);
  env->furniture_items.push_back(addItem(s, std::move(fq), tex(front), 0.1f, 4));
  // A vase or a stack of books on top.
  if (r.chance(0.6)) {
    const float R = r.uniformf(0.05f, 0.09f), H = r.uniformf(0.15f, 0.35f);
    std::vector<ProfilePoint> prof{{0, 0},
                                   {R * 0.7f, 0, true},
                                   {R, H * 0.4f},
                                   {R * 0.5f, H * 0.85f},
                                   {R * 0.6f, H, true},
                                   {0, H - 0.01f}};
    Mesh v = lathe(prof, 32);
    v.transform(F * Eigen::Translation3f(r.uniformf(-w / 3, w / 3), -d / 2, h));
    env->furniture_items.push_back(addItem(
        s, std::move(v),
        tex(ceramicTexture(r, 256, 128, hsvColor(r.uniformf(0.f, 360.f), 0.5f, 0.6f), "bands"),
            true),
        0.4f, 5));
  } else {
    float z = h;
    for (int i = 0; i < r.range(2, 5); ++i) {
      const float bt = r.uniformf(0.02f, 0.05f);
      Mesh bk = box(V3(r.uniformf(0.15f, 0.25f), r.uniformf(0.2f, 0.3f), bt));
      bk.transform(F * Eigen::Translation3f(r.uniformf(-0.03f, 0.03f), -d / 2, z + bt / 2) *
                   Eigen::AngleAxisf(r.uniformf(-0.3f, 0.3f), V3::UnitZ()));
      env->furniture_items.push_back(addItem(
          s, std::move(bk),
          tex(coverTexture(r, 256, 256, hsvColor(r.uniformf(0.f, 360.f), 0.5f, 0.6f))), 0.1f, 4));
      z += bt;
    }
  }
}

void addBoxes(RenderScene* s, Environment* env, Rng& r, const Eigen::Affine3f& F, float w,
              float d) {
  float z = 0;
  for (int i = 0; i < r.range(1, 3); ++i) {
    const V3 size(w * r.uniformf(0.75f, 1.f), d * r.uniformf(0.75f, 1.f), r.uniformf(0.2f, 0.45f));
    Mesh m = box(size);
    m.transform(F * Eigen::Translation3f(r.uniformf(-0.03f, 0.03f), -d / 2, z + size.z() / 2) *
                Eigen::AngleAxisf(r.uniformf(-0.15f, 0.15f), V3::UnitZ()));
    env->furniture_items.push_back(addItem(s, std::move(m), tex(cardboard(r, 512, 384)), 0.03f, 3));
    z += size.z();
  }
}

void addPlant(RenderScene* s, Environment* env, Rng& r, const Eigen::Affine3f& F, float d) {
  const float R = r.uniformf(0.1f, 0.18f), H = r.uniformf(0.2f, 0.35f);
  std::vector<ProfilePoint> pot{
      {0, 0}, {R * 0.75f, 0, true}, {R, H, true}, {R * 0.9f, H, true}, {0, H * 0.9f}};
  Mesh pm = lathe(pot, 32);
  pm.transform(F * Eigen::Translation3f(0, -d / 2, 0));
  const cv::Vec3f pc =
      r.chance(0.5) ? cv::Vec3f(0.3f, 0.42f, 0.65f) : hsvColor(r.uniformf(0.f, 360.f), 0.3f, 0.8f);
  env->furniture_items.push_back(
      addItem(s, std::move(pm), tex(ceramicTexture(r, 256, 128, pc, "plain"), true), 0.2f, 4));
  const cv::Vec3f leaf = hsvColor(r.uniformf(90.f, 140.f), 0.6f, 0.45f);
  TexturePtr lt = tex(skinTexture(r, "greens", 128, 128, leaf), true);
  const int leaves = r.range(8, 16);
  const float top = r.uniformf(0.5f, 1.1f);
  for (int i = 0; i < leaves; ++i) {
    const float len = r.uniformf(0.15f, 0.35f), az = r.uniformf(0.f, 2 * kPi),
                tilt = r.uniformf(0.3f, 1.2f);
    Mesh m = parametricSphere(
        [&](float u, float t) {
          const float th = kPi * t, ph = 2 * kPi * u;
          return V3(len * 0.5f * (1.f - std::cos(th)), 0.25f * len * std::sin(th) * std::cos(ph),
                    0.01f * std::sin(th) * std::sin(ph));
        },
        10, 8);
    const float z0 = H + (top - H) * r.uniformf(0.2f, 1.f);
    m.transform(F * Eigen::Translation3f(0, -d / 2, z0) * Eigen::AngleAxisf(az, V3::UnitZ()) *
                Eigen::AngleAxisf(-tilt + kPi / 2 - 0.6f, V3::UnitY()));
    env->furniture_items.push_back(addItem(s, std::move(m), lt, 0.15f, 4));
  }
}

}  // namespace

bool TableGeometry::fits(float x, float y, float r, float margin) const {
  if (round) return std::hypot(x, y) + r + margin <= half_x;
  return std::fabs(x) + r + margin <= half_x && std::fabs(y) + r + margin <= half_y;
}

LightSetup makeLight(const LightOptions& o, Rng& rng) {
  LightSetup L;
  const float el =
      static_cast<float>(o.elevation_deg > 0 ? o.elevation_deg : rng.uniform(50, 75)) * kPi / 180.f;
  const float az =
      static_cast<float>(o.azimuth_deg >= 0 ? o.azimuth_deg : rng.uniform(0, 360)) * kPi / 180.f;
  L.to_light =
      V3(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)).normalized();
  const float w = static_cast<float>(o.warmth), sun = static_cast<float>(o.sun),
              amb = static_cast<float>(o.ambient);
  L.sun = sun * V3(1.f - 0.18f * w, 1.f, 1.f + 0.12f * w);
  L.sky = amb * V3(1.05f - 0.1f * w, 1.f, 0.95f + 0.1f * w);
  L.ground = 0.55f * amb * V3(0.95f, 1.f, 1.05f);
  return L;
}

Mesh disc(float cx, float cy, float radius, float z, int segments) {
  Mesh m;
  Vertex c;
  c.p = {cx, cy, z};
  c.n = V3::UnitZ();
  c.uv = {0.5f, 0.5f};
  c.uv2 = {0.5f, 0.5f};
  m.vertices.push_back(c);
  for (int i = 0; i <= segments; ++i) {
    const float a = 2 * kPi * static_cast<float>(i) / static_cast<float>(segments);
    Vertex v;
    v.p = {cx + radius * std::cos(a), cy + radius * std::sin(a), z};
    v.n = V3::UnitZ();
    v.uv = {0.5f + 0.5f * std::cos(a), 0.5f - 0.5f * std::sin(a)};
    v.uv2 = {0.5f + 0.5f * std::cos(a), 0.5f + 0.5f * std::sin(a)};
    m.vertices.push_back(v);
  }
  for (int i = 0; i < segments; ++i)
    m.triangles.push_back({0u, static_cast<uint32_t>(i + 1), static_cast<uint32_t>(i + 2)});
  return m;
}

namespace {

const std::vector<std::string> kFloors{"wood",   "parquet",  "tiles",
                                       "carpet", "concrete", "linoleum"};
const std::vector<std::string> kWalls{"wallpaper", "brick",   "plaster",
                                      "panels",    "stripes", "tiles"};
const std::vector<std::string> kTops{"wood", "laminate", "cloth", "marble", "checker", "stone"};

// The floor (a shadow and ambient-occlusion receiver) and the ceiling of the room env spans.
void addFloorAndCeiling(RenderScene* s, Environment* e, const RoomOptions& ro, Rng& rng) {
  Environment& env = *e;
  const float X = static_cast<float>(ro.size[0]), Y = static_cast<float>(ro.size[1]),
              H = static_cast<float>(ro.height);
  const std::string floor_style = ro.floor == "random" ? rng.pick(kFloors) : ro.floor;
  {
    Rng fr = rng.fork(1);
    cv::Mat ft = floorTexture(fr, floor_style, X, Y, std::max(0.003f, std::max(X, Y) / 4000.f));
    Mesh m =
        orientedQuad(V3(env.room_x0, env.room_y1, 0), V3(X, 0, 0), V3(0, -Y, 0), V3::UnitZ(), 4, 4);
    for (auto& v : m.vertices) v.uv2 = {(v.p.x() - env.room_x0) / X, (v.p.y() - env.room_y0) / Y};
    Material mat;
    mat.texture = tex(ft);
    mat.specular = floor_style == "tiles" || floor_style == "linoleum"
                       ? 0.25f
                       : (floor_style == "carpet" ? 0.01f : 0.12f);
    mat.shininess_log2 = 5;
    env.floor.material = s->addMaterial(mat);
    env.floor.x0 = env.room_x0;
    env.floor.x1 = env.room_x1;
    env.floor.y0 = env.room_y0;
    env.floor.y1 = env.room_y1;
    env.floor.z = 0;
    env.floor.ao_radius = 0.12f;
    env.floor.ao_strength = 0.55f;
    env.floor.shadow_texel = 0.01f;
    s->materials[env.floor.material].shadow =
        std::make_shared<ScalarMap>(static_cast<int>(X / 0.01f), static_cast<int>(Y / 0.01f));
    s->materials[env.floor.material].ao =
        std::make_shared<ScalarMap>(static_cast<int>(X / 0.01f), static_cast<int>(Y / 0.01f));
    s->add(std::move(m), env.floor.material);
  }
  {
    Rng cr = rng.fork(2);
    Mesh m = orientedQuad(V3(env.room_x0, env.room_y0, H), V3(X, 0, 0), V3(0, Y, 0), -V3::UnitZ());
    addItem(s, std::move(m), tex(ceilingTexture(cr, X, Y, 0.01f)), 0.02f, 3);
  }
}

// The four walls with their skirting boards; seen from inside, u runs left to right and v
// downwards. Returns their spans, for what stands or hangs on them.
std::vector<WallSpan> addWalls(RenderScene* s, const Environment& env, const RoomOptions& ro,
                               Rng& rng) {
  const float X = static_cast<float>(ro.size[0]), Y = static_cast<float>(ro.size[1]),
              H = static_cast<float>(ro.height);
  std::vector<WallSpan> walls(4);
  walls[0] = {V3(env.room_x1, env.room_y0, 0), V3(-1, 0, 0), V3(0, 1, 0), X, {}};   // south
  walls[1] = {V3(env.room_x1, env.room_y1, 0), V3(0, -1, 0), V3(-1, 0, 0), Y, {}};  // east
  walls[2] = {V3(env.room_x0, env.room_y1, 0), V3(1, 0, 0), V3(0, -1, 0), X, {}};   // north
  walls[3] = {V3(env.room_x0, env.room_y0, 0), V3(0, 1, 0), V3(1, 0, 0), Y, {}};    // west
  const std::string fixed_wall = ro.walls;
  const cv::Vec3f skirting =
      rng.chance(0.5) ? cv::Vec3f(0.92f, 0.92f, 0.92f) : woodLight(rng) * 0.8f;
  for (size_t k = 0; k < walls.size(); ++k) {
    Rng wr = rng.fork(10 + k);
    const WallSpan& w = walls[k];
    const std::string style = fixed_wall == "random" ? wr.pick(kWalls) : fixed_wall;
    cv::Mat wt = wallTexture(wr, style, w.length, H, 0.004f);
    Mesh m = orientedQuad(w.start + V3(0, 0, H), w.u * w.length, V3(0, 0, -H), w.n, 2, 1);
    addItem(s, std::move(m), tex(wt), style == "tiles" ? 0.3f : 0.03f, 5);
    Mesh sk = box(V3(w.length, 0.015f, 0.08f));
    sk.transform(wallFrame(w.start + w.u * (w.length / 2), w.u, w.n) *
                 Eigen::Translation3f(0, -0.0075f, 0.04f));
    addItem(s, std::move(sk), tex(plasticTexture(wr, 512, 16, skirting, 0.05f), true), 0.1f, 4);
  }
  return walls;
}

// A door on one of the walls, where it fits.
void addDoor(RenderScene* s, std::vector<WallSpan>* spans, Rng& rng) {
  std::vector<WallSpan>& walls = *spans;
  {
    const int k = rng.range(0, 3);
    WallSpan& w = walls[static_cast<size_t>(k)];
    const float s0 = rng.uniformf(0.2f, std::max(0.25f, w.length - 1.2f));
    if (w.reserve(s0, s0 + 0.9f)) {
      Rng dr = rng.fork(20);
      const cv::Vec3f light = woodLight(dr);
      cv::Mat wood = woodTexture(dr, 2.05f, 0.9f, 0.003f, light, light * 0.6f);
      cv::Mat door;
      cv::rotate(wood, door, cv::ROTATE_90_CLOCKWISE);
      for (int p = 0; p < 2; ++p)
        cv::rectangle(door, cv::Point(door.cols / 6, door.rows / 12 + p * door.rows * 5 / 11),
                      cv::Point(door.cols * 5 / 6, door.rows * 5 / 12 + p * door.rows * 5 / 11),
                      cv::Scalar(40, 50, 65), 3, cv::LINE_AA);
      Mesh dm = orientedQuad(w.start + w.u * s0 + w.n * 0.01f + V3(0, 0, 2.05f), w.u * 0.9f,
                             V3(0, 0, -2.05f), w.n);
      addItem(s, std::move(dm), tex(door), 0.1f, 4);
      Mesh handle = box(V3(0.12f, 0.04f, 0.025f));
      handle.transform(wallFrame(w.start + w.u * (s0 + 0.78f), w.u, w.n) *
                       Eigen::Translation3f(0, -0.03f, 1.02f));
      addItem(s, std::move(handle), tex(metalTexture(dr, 32, 32, {0.7f, 0.7f, 0.72f}, true)), 0.6f,
              6);
    }
  }
}

// Furniture along the walls: bookshelves, cabinets, boxes, plants.
void addFurniture(RenderScene* s, Environment* e, std::vector<WallSpan>* spans,
                  const RoomOptions& ro, Rng& rng) {
  Environment& env = *e;
  std::vector<WallSpan>& walls = *spans;
  for (int i = 0; i < ro.furniture; ++i) {
    Rng fr = rng.fork(100 + static_cast<uint64_t>(i));
    const int kind = fr.range(0, 3);
    const float w = kind == 0   ? fr.uniformf(0.7f, 1.2f)
                    : kind == 1 ? fr.uniformf(0.8f, 1.6f)
                    : kind == 2 ? fr.uniformf(0.35f, 0.6f)
                                : 0.5f;
    const float d = kind == 0   ? 0.3f
                    : kind == 1 ? fr.uniformf(0.4f, 0.5f)
                    : kind == 2 ? fr.uniformf(0.3f, 0.5f)
                                : 0.4f;
    for (int attempt = 0; attempt < 20; ++attempt) {
      WallSpan& wall = walls[static_cast<size_t>(fr.range(0, 3))];
      const float s0 = fr.uniformf(0.f, std::max(0.f, wall.length - w));
      if (!wall.reserve(s0, s0 + w)) continue;
      const Eigen::Affine3f F = wallFrame(wall.start + wall.u * (s0 + w / 2), wall.u, wall.n);
      if (kind == 0)
        addBookshelf(s, &env, fr, F, w, d, fr.uniformf(1.4f, 2.0f));
      else if (kind == 1)
        addCabinet(s, &env, fr, F, w, d, fr.uniformf(0.75f, 0.95f));
      else if (kind == 2)
        addBoxes(s, &env, fr, F, w, d);
      else
        addPlant(s, &env, fr, F, d);
      break;
    }
  }
}

// Pictures on the walls.
void addPictures(RenderScene* s, std::vector<WallSpan>* spans, const RoomOptions& ro, float H,
                 Rng& rng) {
  std::vector<WallSpan>& walls = *spans;
  for (int i = 0; i < ro.pictures; ++i) {
    Rng pr = rng.fork(200 + static_cast<uint64_t>(i));
    const float w = pr.uniformf(0.3f, 1.0f), h = w * pr.uniformf(0.6f, 1.4f);
    for (int attempt = 0; attempt < 20; ++attempt) {
      WallSpan& wall = walls[static_cast<size_t>(pr.range(0, 3))];
      const float s0 = pr.uniformf(0.f, std::max(0.f, wall.length - w));
      if (!wall.reserve(s0, s0 + w)) continue;
      const float zc = std::min(H - h / 2 - 0.15f, pr.uniformf(1.2f, 1.7f));
      cv::Mat pt = posterTexture(pr, std::max(64, static_cast<int>(w * 600)),
                                 std::max(64, static_cast<int>(h * 600)));
      Mesh m = orientedQuad(wall.start + wall.u * s0 + wall.n * 0.006f + V3(0, 0, zc + h / 2),
                            wall.u * w, V3(0, 0, -h), wall.n);
      addItem(s, std::move(m), tex(pt), pr.uniformf(0.02f, 0.3f), 5);
      break;
    }
  }
}

// The table: its top (a receiver), its edge, and legs and aprons (rectangular) or a pedestal
// (round).
void addTable(RenderScene* s, Environment* e, const TableOptions& to, Rng& rng) {
  Environment& env = *e;
  Rng tr = rng.fork(300);
  TableGeometry& T = env.table;
  T.round = to.shape == "round";
  T.half_x = static_cast<float>(to.size[0]) / 2;
  T.half_y =
      T.round ? T.half_x : static_cast<float>(to.size.size() > 1 ? to.size[1] : to.size[0]) / 2;
  T.top_z = static_cast<float>(to.height);
  const float thick = tr.uniformf(0.025f, 0.045f);
  const std::string top_style = to.top == "random" ? tr.pick(kTops) : to.top;
  cv::Mat top_tex = tableTexture(tr, top_style, 2 * T.half_x, 2 * T.half_y, 0.001f);
  const cv::Vec3f edge_light = woodLight(tr);
  TexturePtr edge =
      tex(woodTexture(tr, 1.f, 0.2f, 0.003f, edge_light, edge_light * 0.6f), true, true);
  Material top_mat;
  top_mat.texture = tex(top_tex);
  top_mat.specular = top_style == "cloth"
                         ? 0.01f
                         : (top_style == "laminate" || top_style == "marble" ? 0.3f : 0.15f);
  top_mat.shininess_log2 = 5;
  const int lw = static_cast<int>(2 * T.half_x / 0.003f),
            lh = static_cast<int>(2 * T.half_y / 0.003f);
  top_mat.shadow = std::make_shared<ScalarMap>(lw, lh);
  top_mat.ao = std::make_shared<ScalarMap>(lw, lh);
  env.table_top.material = s->addMaterial(top_mat);
  env.table_top.x0 = -T.half_x;
  env.table_top.x1 = T.half_x;
  env.table_top.y0 = -T.half_y;
  env.table_top.y1 = T.half_y;
  env.table_top.z = T.top_z;
  env.table_top.ao_radius = 0.015f;
  env.table_top.ao_strength = 0.55f;
  env.table_top.shadow_texel = 0.003f;
  const float z = T.top_z;
  auto addTableItem = [&](Mesh m, TexturePtr t, float spec) {
    env.table_items.push_back(addItem(s, std::move(m), std::move(t), spec, 4));
  };
  if (!T.round) {
    const float hx = T.half_x, hy = T.half_y;
    Mesh top = orientedQuad(V3(-hx, hy, z), V3(2 * hx, 0, 0), V3(0, -2 * hy, 0), V3::UnitZ(), 4, 4);
    for (auto& v : top.vertices) v.uv2 = {(v.p.x() + hx) / (2 * hx), (v.p.y() + hy) / (2 * hy)};
    s->add(std::move(top), env.table_top.material);
    env.table_items.push_back(static_cast<int>(s->items.size()) - 1);
    Mesh slab = box(V3(2 * hx, 2 * hy, thick));
    slab.transform(Eigen::Affine3f(Eigen::Translation3f(0, 0, z - thick / 2 - 0.0005f)));
    addTableItem(std::move(slab), edge, 0.1f);
    const int legs_kind = tr.range(0, 1);
    const float lw2 = tr.uniformf(0.02f, 0.035f), inset = tr.uniformf(0.03f, 0.08f);
    for (int i = 0; i < 4; ++i) {
      const float x = (i & 1 ? 1.f : -1.f) * (hx - inset - lw2),
                  y = (i & 2 ? 1.f : -1.f) * (hy - inset - lw2);
      Mesh leg =
          legs_kind == 0
              ? box(V3(2 * lw2, 2 * lw2, z - thick))
              : lathe({{0, 0}, {lw2 * 0.7f, 0, true}, {lw2, z - thick, true}, {0, z - thick}}, 12);
      leg.transform(
          Eigen::Affine3f(Eigen::Translation3f(x, y, legs_kind == 0 ? (z - thick) / 2 : 0.f)));
      addTableItem(std::move(leg), edge, 0.1f);
    }
    // Aprons under the top.
    for (int i = 0; i < 2; ++i) {
      Mesh ap = box(V3(2 * (hx - inset), 0.02f, 0.08f));
      ap.transform(Eigen::Affine3f(
          Eigen::Translation3f(0, (i ? 1.f : -1.f) * (hy - inset - lw2), z - thick - 0.04f)));
      addTableItem(std::move(ap), edge, 0.1f);
    }
  } else {
    const float R = T.half_x;
    Mesh top = disc(0, 0, R, z, 96);
    for (auto& v : top.vertices) v.uv2 = {(v.p.x() + R) / (2 * R), (v.p.y() + R) / (2 * R)};
    s->add(std::move(top), env.table_top.material);
    env.table_items.push_back(static_cast<int>(s->items.size()) - 1);
    addTableItem(
        lathe({{0, z - thick}, {R, z - thick, true}, {R, z - 0.0005f, true}, {0, z - 0.0005f}}, 96,
              4.f),
        edge, 0.1f);
    const float pr = tr.uniformf(0.03f, 0.06f), base = tr.uniformf(0.2f, 0.3f);
    addTableItem(lathe({{0, 0},
                        {base, 0, true},
                        {base, 0.03f, true},
                        {pr, 0.06f, true},
                        {pr, z - thick},
                        {0, z - thick}},
                       48, 2.f),
                 edge, 0.1f);
  }
}

}  // namespace

Environment buildEnvironment(RenderScene* s, const RoomOptions& ro, const TableOptions& to,
                             Rng& rng, float clear_radius) {
  Environment env;
  // The room, placed so that the table (at the origin) stands at least clear_radius from its walls.
  const float X = static_cast<float>(ro.size[0]), Y = static_cast<float>(ro.size[1]),
              H = static_cast<float>(ro.height);
  const float sx = std::max(0.f, X / 2 - clear_radius), sy = std::max(0.f, Y / 2 - clear_radius);
  const float ox = rng.uniformf(-sx, sx) * 0.8f, oy = rng.uniformf(-sy, sy) * 0.8f;
  env.room_x0 = ox - X / 2;
  env.room_x1 = ox + X / 2;
  env.room_y0 = oy - Y / 2;
  env.room_y1 = oy + Y / 2;
  env.room_h = H;

  addFloorAndCeiling(s, &env, ro, rng);
  std::vector<WallSpan> walls = addWalls(s, env, ro, rng);
  addDoor(s, &walls, rng);
  addFurniture(s, &env, &walls, ro, rng);
  addPictures(s, &walls, ro, env.room_h, rng);
  addTable(s, &env, to, rng);
  return env;
}

void bakeReceiver(RenderScene* s, const Receiver& rc, const std::vector<int>& occluders,
                  const std::vector<float>& region) {
  Material& mat = s->materials[rc.material];
  if (!mat.shadow || !mat.ao) return;
  ScalarMap& sh = *mat.shadow;
  ScalarMap& ao = *mat.ao;
  const int W = sh.width(), Hh = sh.height();
  const float dx = (rc.x1 - rc.x0) / static_cast<float>(W),
              dy = (rc.y1 - rc.y0) / static_cast<float>(Hh);
  int i0 = 0, i1 = W, j0 = 0, j1 = Hh;
  if (region.size() == 4) {
    i0 = std::clamp(static_cast<int>((region[0] - rc.x0) / dx), 0, W);
    i1 = std::clamp(static_cast<int>((region[2] - rc.x0) / dx) + 1, 0, W);
    j0 = std::clamp(static_cast<int>((region[1] - rc.y0) / dy), 0, Hh);
    j1 = std::clamp(static_cast<int>((region[3] - rc.y0) / dy) + 1, 0, Hh);
  }
  const float cx =
      0.5f * (rc.x0 + dx * static_cast<float>(i0) + rc.x0 + dx * static_cast<float>(i1));
  const float cy =
      0.5f * (rc.y0 + dy * static_cast<float>(j0) + rc.y0 + dy * static_cast<float>(j1));
  const float half =
      0.5f * std::hypot(dx * static_cast<float>(i1 - i0), dy * static_cast<float>(j1 - j0)) + 0.05f;
  // Shadows: a height map seen from the light, tested with a 3x3 kernel (soft edges).
  const V3 L = s->light.to_light.normalized();
  const V3 axis = std::fabs(L.z()) < 0.9f ? V3(L.cross(V3::UnitZ())) : V3::UnitX();
  const float texel = std::max(rc.shadow_texel, 2.f * half / 3000.f);
  const HeightMap hm =
      renderHeightMap(*s, occluders, L, axis, V3(cx, cy, rc.z), half + 0.3f, texel);
  for (int j = j0; j < j1; ++j)
    for (int i = i0; i < i1; ++i) {
      const V3 p(rc.x0 + (static_cast<float>(i) + 0.5f) * dx,
                 rc.y0 + (static_cast<float>(j) + 0.5f) * dy, rc.z);
      sh.at(i, j) = 1.f - hm.occlusion(p, 1.5f * texel, 0.002f);
    }
  // Contact darkening: what stands on the receiver, seen from above, blurred.
  const HeightMap top = renderHeightMap(*s, occluders, V3::UnitZ(), V3::UnitX(), V3(cx, cy, rc.z),
                                        half, std::min(dx, dy));
  const int w = i1 - i0, h = j1 - j0;
  if (w <= 0 || h <= 0) return;
  std::vector<float> occ(static_cast<size_t>(w) * h), tmp(occ.size());
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const V3 p(rc.x0 + (static_cast<float>(i + i0) + 0.5f) * dx,
                 rc.y0 + (static_cast<float>(j + j0) + 0.5f) * dy, rc.z);
      const float above = top.at(p) - rc.z;
      occ[static_cast<size_t>(j) * w + i] =
          above > 0.003f ? std::min(1.f, 0.3f + above / (4.f * rc.ao_radius)) : 0.f;
    }
  const int rad = std::max(1, static_cast<int>(rc.ao_radius / std::min(dx, dy)));
  for (int pass = 0; pass < 2; ++pass) {
    for (int j = 0; j < h; ++j) {  // horizontal box filter
      float acc = 0;
      int n = 0;
      for (int i = -rad; i < w + rad; ++i) {
        if (i + rad < w) acc += occ[static_cast<size_t>(j) * w + i + rad], ++n;
        if (i - rad - 1 >= 0) acc -= occ[static_cast<size_t>(j) * w + i - rad - 1], --n;
        if (i >= 0 && i < w)
          tmp[static_cast<size_t>(j) * w + i] = acc / static_cast<float>(2 * rad + 1);
      }
    }
    for (int i = 0; i < w; ++i) {  // vertical
      float acc = 0;
      for (int j = -rad; j < h + rad; ++j) {
        if (j + rad < h) acc += tmp[static_cast<size_t>(j + rad) * w + i];
        if (j - rad - 1 >= 0) acc -= tmp[static_cast<size_t>(j - rad - 1) * w + i];
        if (j >= 0 && j < h)
          occ[static_cast<size_t>(j) * w + i] = acc / static_cast<float>(2 * rad + 1);
      }
    }
  }
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i)
      ao.at(i + i0, j + j0) =
          1.f - rc.ao_strength * std::min(1.f, occ[static_cast<size_t>(j) * w + i]);
}

}  // namespace slamaware::synth
