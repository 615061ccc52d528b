#pragma once
// Camera pose from 2D-3D correspondences: RANSAC over minimal four-point samples (AP3P, Ke &
// Roumeliotis 2017, through OpenCV) and a robust least-squares refinement on the inliers.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "common/geometry.h"

namespace slamaware::slam {

struct PnpOptions {
  int iterations = 200;  ///< at most; fewer when the inlier ratio allows (99% confidence)
  double chi2 = 5.991;   ///< inlier threshold on the squared error / sigma^2
  int min_inliers = 12;
};

struct PnpResult {
  bool ok = false;
  SE3 T_camera_world = SE3::Identity();
  std::vector<bool> inliers;
  int num_inliers = 0;
};

/// p_world[i] is seen at the undistorted pixel px[i] with position variance sigma2[i] (px^2) by
/// a pinhole camera (fx, fy, cx, cy). Deterministic for a given seed.
PnpResult solvePnpRansac(const std::vector<Eigen::Vector3d>& p_world,
                         const std::vector<Eigen::Vector2d>& px, const std::vector<double>& sigma2,
                         double fx, double fy, double cx, double cy, const PnpOptions& options,
                         uint64_t seed);

}  // namespace slamaware::slam
