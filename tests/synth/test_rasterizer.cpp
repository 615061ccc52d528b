// The CPU rasteriser: coverage, depth and texture mapping against closed-form answers, and the
// vectorised shading path against the scalar reference, bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "tools/synth/rasterizer.h"
#include "tools/synth/scene.h"

using namespace slamaware::synth;

namespace {

Intrinsics vga() { return Intrinsics{525.f, 525.f, 319.5f, 239.5f}; }

// A camera at the origin looking along +z (world = camera frame).
Eigen::Isometry3d identityPose() { return Eigen::Isometry3d::Identity(); }

// A two-coloured texture: left half (u < 0.5) black, right half white.
TexturePtr halfTexture() {
  cv::Mat img(64, 64, CV_8UC3, cv::Scalar(0, 0, 0));
  img(cv::Rect(32, 0, 32, 64)).setTo(cv::Scalar(255, 255, 255));
  return std::make_shared<const Texture>(img, false, false);
}

}  // namespace

TEST(SynthRasterizer, TwoTrianglesOfAQuadCoverEachPixelOnceWithoutGaps) {
  RenderScene s;
  Material m;
  const int mi = s.addMaterial(m);
  // A 0.4 x 0.3 m rectangle at z = 1 m, split along a diagonal: every pixel centre inside it must
  // be covered exactly once (no crack along the shared edge, no double cover).
  s.add(quad({-0.2f, -0.15f, 1.f}, {0.4f, 0, 0}, {0, 0.3f, 0}), mi, 0);
  s.items[0].mesh.flip();  // face the camera (-z)
  s.finalize();
  Rasterizer r;
  const Viewport vp{0, 0, 640, 480};
  FrameBuffers fb;
  r.render(s, vga(), identityPose(), vp, &fb, false);
  // Projection: x = 525 * X + 319.5 for X in [-0.2, 0.2] -> [214.5, 424.5]: pixel centres 215..424.
  int64_t covered = 0, wrong = 0;
  for (int y = 0; y < 480; ++y)
    for (int x = 0; x < 640; ++x) {
      const bool inside = x >= 215 && x <= 424 && y >= 161 && y <= 318;  // y: 525 * 0.15 = 78.75
      const bool hit = fb.object[static_cast<size_t>(y) * 640 + x] == 0;
      covered += hit;
      wrong += hit != inside;
    }
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(covered, 210 * 158);
  EXPECT_EQ(r.silhouettePixels(s, 0, vga(), identityPose(), Viewport{-100, -100, 840, 680}),
            210 * 158);
}

TEST(SynthRasterizer, DepthAndTextureArePerspectiveCorrectOnATiltedPlane) {
  RenderScene s;
  Material m;
  m.texture = halfTexture();
  const int mi = s.addMaterial(m);
  // A plane tilted about the x axis: z grows from 0.8 m at its bottom edge to 2.0 m at its top.
  const Eigen::Vector3f a(-0.5f, 0.3f, 0.8f), b(-0.5f, -0.4f, 2.0f);
  Mesh q = quad(a, {1.0f, 0, 0}, b - a, 1.f, 1.f, 3, 3);
  if ((q.vertices[1].p - q.vertices[0].p).cross(q.vertices[4].p - q.vertices[0].p).z() > 0)
    q.flip();
  s.add(q, mi, 0);
  s.finalize();
  Rasterizer r;
  FrameBuffers fb;
  r.render(s, vga(), identityPose(), Viewport{0, 0, 640, 480}, &fb, true);
  const Eigen::Vector3f n = Eigen::Vector3f(1.f, 0, 0).cross(b - a).normalized();
  const float d = n.dot(a);
  int checked = 0;
  for (int y = 40; y < 440; y += 7)
    for (int x = 60; x < 580; x += 11) {
      const size_t i = static_cast<size_t>(y) * 640 + x;
      if (fb.object[i] != 0) continue;
      // Ray through the pixel centre, intersected with the plane.
      const Eigen::Vector3f ray((x - 319.5f) / 525.f, (y - 239.5f) / 525.f, 1.f);
      const float z = d / n.dot(ray);
      EXPECT_NEAR(fb.depth[i], z, 1e-5f * z) << x << "," << y;
      ++checked;
    }
  EXPECT_GT(checked, 300);
  // The colour edge is the line u = 0.5, i.e. X = 0 on the plane, which projects to x = 319.5.
  const size_t npx = 640 * 480;
  for (int y = 150; y < 420; y += 20) {  // the plane spans rows 135-479
    const size_t row = static_cast<size_t>(y) * 640;
    EXPECT_LT(fb.bgr[npx + row + 310], 0.05f) << y;  // green plane, left of the edge: black texels
    EXPECT_GT(fb.bgr[npx + row + 329], 0.25f) << y;  // right of it: white texels in ambient light
  }
}

TEST(SynthRasterizer, VectorAndScalarShadingGiveTheSameBits) {
  SceneOptions o;
  o.name = "vector_check";
  o.seed = 3;
  o.frames = 30;
  o.room.furniture = 2;
  o.room.pictures = 2;
  SyntheticScene scene(o);
  Rasterizer fast, reference;
  reference.setVectorised(false);
  for (int frame : {0, 17, 29}) {
    FrameBuffers a, b;
    fast.render(scene.renderScene(), scene.intrinsics(), scene.pose(frame),
                Viewport{0, 0, 640, 480}, &a, true);
    reference.render(scene.renderScene(), scene.intrinsics(), scene.pose(frame),
                     Viewport{0, 0, 640, 480}, &b, true);
    ASSERT_EQ(a.bgr.size(), b.bgr.size());
    size_t differ = 0;
    for (size_t i = 0; i < a.bgr.size(); ++i)
      differ += std::memcmp(&a.bgr[i], &b.bgr[i], sizeof(float)) != 0;
    EXPECT_EQ(differ, 0u) << "frame " << frame;
    EXPECT_EQ(0, std::memcmp(a.depth.data(), b.depth.data(), a.depth.size() * sizeof(float)));
    EXPECT_EQ(a.object, b.object);
  }
}
