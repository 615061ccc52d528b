#pragma once
// Triangle meshes and the shape builders the object families are made of: surfaces of
// revolution (lathe), parametric grids, swept tubes, extruded outlines, boxes and superquadrics.
// Units are metres; an object's local frame has z up and its origin at the centre of its base.
// Triangles wind counter-clockwise seen from outside (the face normal points out).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace slamaware::synth {

struct Vertex {
  Eigen::Vector3f p = Eigen::Vector3f::Zero();    ///< position, m
  Eigen::Vector3f n = Eigen::Vector3f::UnitZ();   ///< unit normal
  Eigen::Vector2f uv = Eigen::Vector2f::Zero();   ///< texture coordinates
  Eigen::Vector2f uv2 = Eigen::Vector2f::Zero();  ///< light-map coordinates (receivers only)
};

struct Mesh {
  std::vector<Vertex> vertices;
  std::vector<std::array<uint32_t, 3>> triangles;

  void append(const Mesh& other);
  /// Applies T to positions and (inverse-transposed, renormalised) to normals.
  void transform(const Eigen::Affine3f& T);
  Eigen::AlignedBox3f bounds() const;
  /// Signed volume (m^3); positive for a closed mesh whose triangles face outwards.
  double signedVolume() const;
  /// Reverses every triangle and normal.
  void flip();
  /// Sets uv = (a + b * p) per vertex from a planar projection: u = du.dot(p) + u0, v = dv.dot(p) +
  /// v0.
  void planarUv(const Eigen::Vector3f& du, float u0, const Eigen::Vector3f& dv, float v0);
};

/// A point of a lathe profile: radius and height; `crease` makes a sharp edge there; `v` (if >= 0)
/// is the texture v of the ring (else the normalised arc length).
struct ProfilePoint {
  float r = 0, z = 0;
  bool crease = false;
  float v = -1;
};

/// Surface of revolution about z. The profile runs from the bottom to the top (outer side
/// upwards, inner side downwards for shells), so the normals point out of the solid. u goes
/// once around (times u_repeat). radial(phi, t) scales the radius (t = ring index / (rings - 1)),
/// for lobes and ribs; nullptr for a true surface of revolution.
Mesh lathe(const std::vector<ProfilePoint>& profile, int segments, float u_repeat = 1.f,
           const std::function<float(float phi, float t)>& radial = nullptr);

/// A grid of rows x cols points (row-major) with texture coordinates; neighbouring points make
/// triangles (row r, col c) -> (r, c+1) -> (r+1, c+1). seam: the last column duplicates the first
/// (normals are averaged across it). Normals are area-weighted averages of the face normals.
Mesh gridMesh(int rows, int cols, const std::vector<Eigen::Vector3f>& points,
              const std::vector<Eigen::Vector2f>& uvs, bool seam);
/// gridMesh without quads between row r and r + 1 where row_break[r] (a crease: the two rows are
/// copies of the same points with different normals).
Mesh gridMeshWithBreaks(int rows, int cols, const std::vector<Eigen::Vector3f>& points,
                        const std::vector<Eigen::Vector2f>& uvs, bool seam,
                        const std::vector<bool>& row_break);

/// A closed surface from a function of (s, t) in [0, 1]^2: t from the bottom pole (0) to the top
/// pole (1), s once around. Oriented outwards (flipped if its volume comes out negative).
Mesh parametricSphere(const std::function<Eigen::Vector3f(float s, float t)>& fn, int segments,
                      int rings, float u_repeat = 1.f);

/// A tube along a curve with a circular (or elliptical: radius x ratio across) section whose radius
/// may vary along it; closed with flat caps when `caps`. u around, v along (0..1).
Mesh sweep(const std::vector<Eigen::Vector3f>& curve, const std::function<float(float t)>& radius,
           int sides, bool caps, float ratio = 1.f,
           const Eigen::Vector3f& up_hint = Eigen::Vector3f::UnitZ());

/// A box centred at the origin with flat faces. Texture: an atlas with the faces laid out as
/// columns [front(-y) | right(+x) | back(+y) | left(-x)] over rows [sides | top | bottom] in
/// proportion to the face sizes, i.e. a box label unwrapped around the box (see boxAtlasLayout).
Mesh box(const Eigen::Vector3f& size);

/// Where each face of box() lands in its texture atlas: rectangles in uv units [u0, v0, u1, v1].
struct BoxAtlas {
  std::array<float, 4> front, right, back, left, top, bottom;
};
BoxAtlas boxAtlasLayout(const Eigen::Vector3f& size);

/// Superquadric ("rounded box"): half sizes a, exponents e_round (0.1 boxy .. 1 ellipsoidal) for
/// the horizontal section and the vertical profile. Texture: u around, v bottom-to-top.
Mesh superquadric(const Eigen::Vector3f& half, float e_horizontal, float e_vertical, int segments,
                  int rings);

/// A prism: a simple polygon (counter-clockwise, x-y plane) extruded from z0 to z1. Caps use the
/// polygon's x, y (scaled by uv_scale) as texture coordinates; sides u along the outline.
Mesh extrude(const std::vector<Eigen::Vector2f>& polygon, float z0, float z1, float uv_scale = 1.f);

/// Triangulates a simple polygon (counter-clockwise) by ear clipping.
std::vector<std::array<uint32_t, 3>> triangulatePolygon(
    const std::vector<Eigen::Vector2f>& polygon);

/// A flat rectangle (two triangles) with corner `origin`, edge vectors `a` (u) and `b` (v), facing
/// a x b, with uv from (0, 0) to (u_max, v_max); subdivided into nx x ny quads.
Mesh quad(const Eigen::Vector3f& origin, const Eigen::Vector3f& a, const Eigen::Vector3f& b,
          float u_max = 1, float v_max = 1, int nx = 1, int ny = 1);

}  // namespace slamaware::synth
