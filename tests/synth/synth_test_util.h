#pragma once
// Small helpers shared by the synthetic-generator tests.
#include <Eigen/Geometry>
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "tools/synth/render_scene.h"

namespace slamaware::synth::synth_test {

/// FNV-1a of a file's bytes.
inline uint64_t fileHash(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  uint64_t h = 0xCBF29CE484222325ull;
  for (std::istreambuf_iterator<char> it(in), end; it != end; ++it)
    h = (h ^ static_cast<unsigned char>(*it)) * 0x100000001B3ull;
  return h;
}

/// Hash of every file under `dir`, by path relative to it.
inline std::map<std::string, uint64_t> treeHashes(const std::string& dir) {
  std::map<std::string, uint64_t> out;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
    if (e.is_regular_file())
      out[std::filesystem::relative(e.path(), dir).string()] = fileHash(e.path().string());
  return out;
}

/// Nearest intersection (distance along `dir` from `origin`) of a ray with the triangles of an
/// object in a finalised scene (Moller-Trumbore, in double); -1 when it misses.
inline double rayHitObject(const RenderScene& s, int object, const Eigen::Vector3d& origin,
                           const Eigen::Vector3d& dir) {
  const auto range = s.objectRanges()[static_cast<size_t>(object)];
  double best = -1;
  for (uint32_t t = range.begin; t < range.end; ++t) {
    const auto& tri = s.triangles()[t];
    const Eigen::Vector3d a = s.vertices()[tri.v[0]].p.cast<double>(),
                          b = s.vertices()[tri.v[1]].p.cast<double>(),
                          c = s.vertices()[tri.v[2]].p.cast<double>();
    const Eigen::Vector3d e1 = b - a, e2 = c - a, p = dir.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-15) continue;
    const Eigen::Vector3d tv = origin - a;
    const double u = tv.dot(p) / det;
    if (u < -1e-9 || u > 1 + 1e-9) continue;
    const Eigen::Vector3d q = tv.cross(e1);
    const double v = dir.dot(q) / det;
    if (v < -1e-9 || u + v > 1 + 1e-9) continue;
    const double d = e2.dot(q) / det;
    if (d > 0 && (best < 0 || d < best)) best = d;
  }
  return best;
}

}  // namespace slamaware::synth::synth_test
