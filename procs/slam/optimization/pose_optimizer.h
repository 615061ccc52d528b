#pragma once
// Motion-only pose optimisation: the camera pose that minimises the reprojection error of known
// 3D points, with a Huber loss and the outlier schedule of ORB-SLAM's PoseOptimization (four
// rounds; after each, observations over the chi-square threshold are left out of the next one
// and those back under it return; no robust loss in the last two rounds).
#include <Eigen/Core>
#include <vector>

#include "common/geometry.h"

namespace slamaware::slam {

struct Intrinsics;

struct PoseObservation {
  Eigen::Vector3d p_world;
  Eigen::Vector2d px;       ///< undistorted pixel
  double inv_sigma2 = 1.0;  ///< 1 / variance of the pixel position (pyramid level)
  bool outlier = false;     ///< in: excluded from the first round; out: the final classification
};

struct PoseOptimizerOptions {
  int rounds = 4;
  int iterations = 10;    ///< Levenberg-Marquardt iterations per round
  double chi2 = 5.991;    ///< chi-square threshold, 2 dof, 95%
  int robust_rounds = 2;  ///< rounds that use the Huber loss
};

/// Refines T_camera_world in place; returns the number of inliers (observations not outliers).
int optimizePose(SE3* T_camera_world, std::vector<PoseObservation>& observations, double fx,
                 double fy, double cx, double cy, const PoseOptimizerOptions& options = {});

}  // namespace slamaware::slam
