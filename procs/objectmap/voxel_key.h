#pragma once
// A voxel of a segment's grid as one integer: the three 16-bit OctoMap keys of the finest level
// packed as x | y << 16 | z << 32. OctoMap's key of a coordinate c at resolution r is
// floor(c / r) + 32768 and a voxel's centre is (key - 32768 + 0.5) r, so keys are independent of
// the tree that holds them and can be stored, compared and saved without OctoMap.
#include <Eigen/Core>
#include <cmath>
#include <cstdint>

namespace slamaware::objectmap {

using VoxelKey = uint64_t;

constexpr int32_t kVoxelKeyOffset = 32768;  ///< OctoMap's tree_max_val at depth 16

inline VoxelKey packVoxelKey(uint32_t kx, uint32_t ky, uint32_t kz) {
  return static_cast<VoxelKey>(kx & 0xffffu) | (static_cast<VoxelKey>(ky & 0xffffu) << 16) |
         (static_cast<VoxelKey>(kz & 0xffffu) << 32);
}
inline uint32_t voxelKeyAxis(VoxelKey key, int axis) {
  return static_cast<uint32_t>((key >> (16 * axis)) & 0xffffu);
}

/// Centre of a voxel in map units.
inline Eigen::Vector3d voxelCentre(VoxelKey key, double resolution) {
  return Eigen::Vector3d(
      (static_cast<int32_t>(voxelKeyAxis(key, 0)) - kVoxelKeyOffset + 0.5) * resolution,
      (static_cast<int32_t>(voxelKeyAxis(key, 1)) - kVoxelKeyOffset + 0.5) * resolution,
      (static_cast<int32_t>(voxelKeyAxis(key, 2)) - kVoxelKeyOffset + 0.5) * resolution);
}

/// The voxel holding point p; false when p is outside the grid (|c| >= 32768 r on an axis) or not
/// finite.
inline bool voxelKeyOf(const Eigen::Vector3d& p, double resolution, VoxelKey* key) {
  int32_t k[3];
  for (int a = 0; a < 3; ++a) {
    const double s = std::floor(p[a] / resolution);
    if (!(s >= -kVoxelKeyOffset && s < kVoxelKeyOffset)) return false;
    k[a] = static_cast<int32_t>(s) + kVoxelKeyOffset;
  }
  *key = packVoxelKey(static_cast<uint32_t>(k[0]), static_cast<uint32_t>(k[1]),
                      static_cast<uint32_t>(k[2]));
  return true;
}

}  // namespace slamaware::objectmap
