#pragma once
// Synthetic geometry for the SLAM unit tests: random points in front of a camera, poses around
// them, and their exact projections (with optional noise), all from a seeded generator.
#include <Eigen/Core>
#include <random>
#include <vector>

#include "common/geometry.h"

namespace slamaware::test {

struct PinholeCamera {
  double fx = 500, fy = 500, cx = 320, cy = 240;
  int width = 640, height = 480;
  Eigen::Matrix3d K() const {
    Eigen::Matrix3d k;
    k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
    return k;
  }
  Eigen::Vector2d project(const Eigen::Vector3d& p_camera) const {
    return {fx * p_camera.x() / p_camera.z() + cx, fy * p_camera.y() / p_camera.z() + cy};
  }
  bool inImage(const Eigen::Vector2d& px) const {
    return px.x() >= 0 && px.y() >= 0 && px.x() < width && px.y() < height;
  }
};

/// Points uniformly in a box [-w, w] x [-h, h] x [z0, z1] of the world frame.
inline std::vector<Eigen::Vector3d> randomPoints(int n, double w, double h, double z0, double z1,
                                                 uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(-w, w), uy(-h, h), uz(z0, z1);
  std::vector<Eigen::Vector3d> pts(n);
  for (auto& p : pts) p = {ux(rng), uy(rng), uz(rng)};
  return pts;
}

/// T_camera_world of a camera at `center` (world) rotated by the rotation vector `rotvec`.
inline SE3 cameraAt(const Eigen::Vector3d& center, const Eigen::Vector3d& rotvec) {
  SE3 T_world_camera = SE3::Identity();
  T_world_camera.linear() = expSO3(rotvec);
  T_world_camera.translation() = center;
  return T_world_camera.inverse();
}

}  // namespace slamaware::test
