#pragma once
// A compact CPU rasteriser: z-buffered triangles with exact (fixed-point, top-left rule)
// coverage at pixel centres, then one shading pass over the visible surface (deferred): every
// attribute is evaluated perspective-correctly from per-triangle plane equations, textures are
// sampled trilinearly with the level from analytic derivatives, and the light is an ambient
// hemisphere plus a directional light (Lambertian + a mild Blinn-Phong highlight, light maps for
// shadows on receivers). Single-threaded and free of fused multiply-adds (-ffp-contract=off):
// the same inputs give the same bits.
//
// Pixel coordinates follow CameraModel: the centre of the top-left pixel is (0, 0). The camera
// frame is x right, y down, z forward; poses are T_world_camera.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "tools/synth/render_scene.h"

namespace slamaware::synth {

/// Pinhole intrinsics (the generator renders undistorted images).
struct Intrinsics {
  float fx = 525, fy = 525, cx = 319.5f, cy = 239.5f;
};

/// A window of the image: pixels [x0, x0 + w) x [y0, y0 + h).
struct Viewport {
  int x0 = 0, y0 = 0, w = 0, h = 0;
};

/// What a render produces, per pixel of the viewport (row-major).
struct FrameBuffers {
  Viewport vp;
  std::vector<float> bgr;  ///< shaded colour: three planes (B, G, R) of w x h floats (about [0, 1])
  std::vector<float> depth;     ///< z in the camera frame (m); 0 where nothing was drawn
  std::vector<int16_t> object;  ///< object id, -1 for background
  // Internal: the visibility pass.
  std::vector<float> inv_z;
  std::vector<uint32_t> setup;
};

class Rasterizer {
 public:
  static constexpr float kNear = 0.02f;  ///< m, near clipping plane

  /// Use the eight-pixel (AVX2) shading path when the build has it (the default). Both paths give
  /// the same bits; the scalar one is the reference.
  void setVectorised(bool on) { vector_ = on; }

  /// Renders `scene` seen from T_world_camera into `out` (resized to the viewport). shade = false
  /// skips the colour (depth and object ids only).
  void render(const RenderScene& scene, const Intrinsics& K,
              const Eigen::Isometry3d& T_world_camera, const Viewport& vp, FrameBuffers* out,
              bool shade = true);

  /// Number of pixels the silhouette of one object covers (ignoring everything else), counted
  /// over the viewport `vp` (which may extend beyond the image). Same coverage rule as render().
  int64_t silhouettePixels(const RenderScene& scene, int object, const Intrinsics& K,
                           const Eigen::Isometry3d& T_world_camera, const Viewport& vp);

  /// Projected bounding box of an object's vertices (pixels, [x0, y0, x1, y1]); false when a
  /// vertex is behind the near plane or the object is absent.
  static bool projectedBounds(const RenderScene& scene, int object, const Intrinsics& K,
                              const Eigen::Isometry3d& T_world_camera, Eigen::Vector4f* box);

 private:
  struct Setup {
    float iz[3], q1[3], q2[3];  // affine in pixel coordinates: 1/z, b1/z, b2/z
    float uv0[2], duv1[2], duv2[2];
    float uw0[2], duw1[2], duw2[2];  // light-map coordinates
    float n0[3], dn1[3], dn2[3];     // camera-frame normals (flat: n0 is the unit normal)
    // Flat triangles: the light terms are constant over the triangle.
    float amb[3], dif[3], refl[3];  // ambient and direct factors (tint included), reflected light
    const Material* mat;
    int32_t object;
    bool flat;
  };
  void lightTerms(const float n[3], const Material& m, float amb[3], float dif[3],
                  float refl[3]) const;
  void transformVertices(const RenderScene& scene, const Eigen::Isometry3d& T_world_camera);
  void shade(const Intrinsics& K, const Viewport& vp, FrameBuffers* out, bool colour);
  void shadePixel(const Setup& S, float x, float y, size_t index, const void* target,
                  bool colour) const;
  void shadeSpan8(const Setup& S, int x, float y, size_t index, int n, const void* target) const;
  std::vector<Eigen::Vector3f> cam_;  // vertices in the camera frame
  std::vector<Setup> setups_;
  std::vector<uint8_t> mask_;
  bool vector_ = true;
  // Unit view rays per pixel of the last viewport (recomputed when K or the viewport changes).
  std::vector<float> rays_;
  Intrinsics rays_K_;
  Viewport rays_vp_;
  // Light in the camera frame of the current render.
  Eigen::Vector3f l_cam_, up_cam_;
  LightSetup light_;
};

/// Renders a height map of `items` seen along -dir (orthographic): for each texel of a grid over
/// the plane perpendicular to dir, the largest dir . p of the surfaces (-inf where none). The grid
/// has its own frame: u along `axis_u`, v along dir x axis_u, origin `origin`, texel `texel` m.
struct HeightMap {
  int w = 0, h = 0;
  float texel = 0.01f;
  Eigen::Vector3f origin = Eigen::Vector3f::Zero(), dir = Eigen::Vector3f::UnitZ(),
                  axis_u = Eigen::Vector3f::UnitX();
  Eigen::Vector3f axis_v = Eigen::Vector3f::UnitY();  ///< dir x axis_u
  std::vector<float> height;
  /// Height at a world point's projection (bilinear on the grid, -inf outside).
  float at(const Eigen::Vector3f& p) const;
  /// Fraction of the 3x3 taps (spacing `radius` m) around p's projection whose height is above
  /// dir . p + bias: a soft shadow test.
  float occlusion(const Eigen::Vector3f& p, float radius, float bias) const;
};
HeightMap renderHeightMap(const RenderScene& scene, const std::vector<int>& items,
                          const Eigen::Vector3f& dir, const Eigen::Vector3f& axis_u,
                          const Eigen::Vector3f& centre, float half_extent, float texel);

}  // namespace slamaware::synth
