#pragma once
// Bundle adjustment of keyframe poses and points (Ceres; its headers stay in the .cpp). Used for
// the two-view map at initialisation and by local mapping over covisible keyframes.
#include <Eigen/Core>
#include <atomic>
#include <vector>

#include "common/geometry.h"

namespace slamaware::slam {

struct BaCamera {
  SE3 T_camera_world = SE3::Identity();
  bool fixed = false;
};

struct BaPoint {
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
  bool fixed = false;
};

struct BaObservation {
  int camera = 0;           ///< index into BaProblem::cameras
  int point = 0;            ///< index into BaProblem::points
  Eigen::Vector2d px;       ///< undistorted pixel
  double inv_sigma2 = 1.0;  ///< 1 / variance of the pixel (pyramid level)
  bool enabled = true;      ///< false: left out (an outlier found earlier)
};

struct BaProblem {
  double fx = 1, fy = 1, cx = 0, cy = 0;  ///< pinhole camera of the undistorted pixels
  std::vector<BaCamera> cameras;
  std::vector<BaPoint> points;
  std::vector<BaObservation> observations;
};

struct BaOptions {
  int iterations = 10;
  bool robust = true;                        ///< Huber loss on the normalised error
  double huber_chi2 = 5.991;                 ///< Huber threshold (squared), 2 dof 95%
  const std::atomic<bool>* abort = nullptr;  ///< stops between iterations when it becomes true
};

struct BaSummary {
  double initial_rms_px = 0;  ///< RMS of the normalised reprojection error before
  double final_rms_px = 0;    ///< and after (enabled observations)
  int iterations = 0;
  bool aborted = false;
  bool usable = false;  ///< the solver ran and returned finite estimates
};

/// Optimises the free cameras and points of `problem` in place.
BaSummary bundleAdjust(BaProblem* problem, const BaOptions& options);

/// One observation's weighted reprojection residual, sqrt(information) * (projection - pixel), at
/// camera q (Eigen quaternion coefficients x, y, z, w) and t (T_camera_world), point p; with
/// non-null jq (2x4), jt (2x3), jp (2x3), row-major, its exact derivatives with respect to each.
/// A point at or behind the camera is projected at depth 1e-6 (a large, bounded residual). The
/// bundle adjustment's cost function (analytic: a third of its time went to automatic
/// differentiation).
void reprojectionResidual(const BaProblem& problem, const BaObservation& obs, const double* q,
                          const double* t, const double* p, double residual[2], double* jq,
                          double* jt, double* jp);

/// Normalised squared reprojection error (error^2 / sigma^2) of an observation under the current
/// estimates; *in_front is false when the point is behind the camera.
double observationChi2(const BaProblem& problem, const BaObservation& obs, bool* in_front);

}  // namespace slamaware::slam
