#pragma once
// A depth-filter seed: the parametric posterior of Vogiatzis & Hernandez ("Video-based,
// real-time multi-view stereo", IVC 2011), as used by SVO (Forster et al. 2014): the inverse depth
// of a pixel is, with probability pi, a Gaussian N(mu, sigma^2) around the truth and otherwise
// uniform over [0, z_range] (an outlier); the posterior is approximated by a Gaussian on the
// inverse depth times a Beta(a, b) on pi.
#include <Eigen/Core>

namespace slamaware::slam {

struct DepthSeed {
  float u = 0, v = 0;                            ///< px, undistorted pixel in the host keyframe
  Eigen::Vector3f f = Eigen::Vector3f::UnitZ();  ///< unit bearing of the pixel, host camera frame
  float mu = 1;          ///< inverse distance along f (1 / map units), posterior mean
  float sigma2 = 1;      ///< its variance
  float a = 10, b = 10;  ///< Beta parameters: evidence for inlier / outlier measurements
  float z_range = 1;     ///< largest inverse distance (1 / nearest scene distance)
  int updates = 0;       ///< measurements fused
  bool provisional =
      false;  ///< published as a provisional point (DepthFilterOptions::young_convergence_ratio)
  uint8_t rgb[3] = {0, 0, 0};

  /// Expected inlier ratio a / (a + b).
  float inlierRatio() const { return a / (a + b); }
};

/// Initial seed for a pixel whose scene depth is about mean_depth and at least min_depth.
DepthSeed makeSeed(float u, float v, const Eigen::Vector3f& bearing, float mean_depth,
                   float min_depth);

/// Fuses a measurement x of the inverse depth with variance tau2 (Vogiatzis & Hernandez, eq. 19-
/// 22 via moment matching: the posterior mixture is projected back onto Gaussian x Beta).
void updateSeed(DepthSeed* seed, float x, float tau2);

/// Distance uncertainty of a triangulated point at distance z along the unit bearing f of the
/// host camera, for an angular error px_error_angle of the matched ray; t = position of the other
/// camera's centre in the host frame (SVO's computeTau: the law of sines in the triangle of the
/// two centres and the point, with the angle at the other camera widened by the pixel error).
double depthUncertainty(const Eigen::Vector3d& t, const Eigen::Vector3d& f, double z,
                        double px_error_angle);

}  // namespace slamaware::slam
