#pragma once
// What the rasteriser draws: world-space meshes with materials, and one light setup (a sky /
// ground hemisphere for the ambient term plus one directional light). Static geometry is
// flattened once into vertex and triangle arrays.
#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "tools/synth/mesh.h"
#include "tools/synth/texture.h"

namespace slamaware::synth {

struct Material {
  TexturePtr texture;                              ///< albedo; nullptr = the tint alone
  Eigen::Vector3f tint = Eigen::Vector3f::Ones();  ///< B, G, R factor on the texture
  float specular = 0.04f;                          ///< strength of the Blinn-Phong highlight
  int shininess_log2 = 4;                          ///< highlight exponent = 2^shininess_log2 (0-7)
  bool double_sided = false;                       ///< draw back faces (normals flipped)
  std::shared_ptr<ScalarMap> shadow;               ///< direct-light visibility over uv2 (receivers)
  std::shared_ptr<ScalarMap> ao;  ///< ambient occlusion over uv2 (with shadow, same size)
};

struct LightSetup {
  Eigen::Vector3f to_light = Eigen::Vector3f(0.3f, 0.2f, 0.93f).normalized();  ///< world, unit
  Eigen::Vector3f sun = Eigen::Vector3f(0.62f, 0.66f, 0.70f);     ///< directional light, B G R
  Eigen::Vector3f sky = Eigen::Vector3f(0.50f, 0.50f, 0.48f);     ///< ambient from above
  Eigen::Vector3f ground = Eigen::Vector3f(0.30f, 0.31f, 0.32f);  ///< ambient from below
};

/// A mesh in world coordinates with its material; object >= 0 marks a ground-truth object.
struct RenderItem {
  Mesh mesh;
  int material = 0;
  int object = -1;
};

struct FlatTriangle {
  uint32_t v[3];
  int32_t material;
  int32_t object;
  int32_t item;
};

class RenderScene {
 public:
  std::vector<Material> materials;
  std::vector<RenderItem> items;
  LightSetup light;

  int addMaterial(Material m) {
    materials.push_back(std::move(m));
    return static_cast<int>(materials.size()) - 1;
  }
  void add(Mesh mesh, int material, int object = -1) {
    items.push_back({std::move(mesh), material, object});
  }

  /// Flattens the items into vertices() / triangles(); call after changing items.
  void finalize();
  /// Flattens the first n items (all background) once; later finalize() calls re-use them as long
  /// as they are left unchanged (a fixed backdrop with a few items that change per view).
  void freezePrefix(size_t n);
  const std::vector<Vertex>& vertices() const { return vertices_; }
  const std::vector<FlatTriangle>& triangles() const { return triangles_; }
  /// Triangles [begin, end) of each object id (objects are contiguous after finalize()).
  struct Range {
    uint32_t begin = 0, end = 0;
  };
  const std::vector<Range>& objectRanges() const { return object_ranges_; }
  int objectCount() const { return static_cast<int>(object_ranges_.size()); }

 private:
  std::vector<Vertex> vertices_;
  std::vector<FlatTriangle> triangles_;
  std::vector<Range> object_ranges_;
  size_t frozen_items_ = 0, frozen_vertices_ = 0, frozen_triangles_ = 0;
};

}  // namespace slamaware::synth
