#pragma once
// The 51 object categories of the UW RGB-D Object dataset (Lai et al., ICRA 2011), the first five
// being the classes of UW RGB-D Scenes v2 (bowl, cap, cereal_box, coffee_mug, soda_can). Each
// category is a shape family with per-instance dimensions in realistic ranges, shape details and
// procedural textures, all drawn from the instance seed: two seeds give two different instances.
//
// An object's local frame: metres, z up, origin at the centre of its base (where it rests on a
// table); objects that lie on their side (markers, bananas) lie along x.
#include <cstdint>
#include <string>
#include <vector>

#include "tools/synth/render_scene.h"

namespace slamaware::synth {

/// The five classes of the paper's evaluation (UW RGB-D Scenes v2).
const std::vector<std::string>& paperClasses();
/// All 51 categories, paper classes first, then the rest in alphabetical order.
const std::vector<std::string>& categoryNames();
/// A one-line description of the shape family of a category.
std::string categoryFamily(const std::string& category);
bool isCategory(const std::string& name);

struct ObjectPart {
  Mesh mesh;
  Material material;
};

/// One object instance in its local frame.
struct ObjectModel {
  std::string category;
  uint64_t seed = 0;
  std::vector<ObjectPart> parts;

  Eigen::AlignedBox3f bounds() const;
  /// Largest horizontal distance of a vertex from the local z axis (m).
  float footprintRadius() const;
  size_t triangleCount() const;
};

/// Builds an instance of `category` from its instance seed. Throws std::invalid_argument for an
/// unknown category.
ObjectModel makeObject(const std::string& category, uint64_t instance_seed);

/// Instance seeds: the top bit says where an instance may appear, so that the instances of the
/// object sets (training) and of the scenes (testing) can never coincide.
enum class SeedDomain : uint64_t { kObjectSet = 0, kScene = 1 };
uint64_t instanceSeed(SeedDomain domain, uint64_t set_seed, const std::string& category,
                      uint64_t index);
SeedDomain seedDomain(uint64_t instance_seed);

}  // namespace slamaware::synth
