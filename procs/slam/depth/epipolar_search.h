#pragma once
// Epipolar search for a depth-filter seed in a new frame (after LSD-SLAM, Engel et al. 2014,
// section 3.2): the seed's inverse-depth interval mu +- 2 sigma projects to a segment of the
// epipolar line in the frame; five samples taken along the host keyframe's epipolar line
// through the seed pixel (spaced so that they map to one-pixel steps in the frame) are compared
// with five consecutive samples along the segment by zero-mean SSD. The best position, if
// distinct and good enough, is refined to sub-pixel and triangulated along the host ray.
#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "procs/slam/depth/seed.h"

namespace slamaware::slam {

struct EpipolarSearchParams {
  float fx = 1, fy = 1, cx = 0, cy = 0;  ///< pinhole camera of both images (undistorted)
  float max_search_px = 400;             ///< px, longer segments are not searched
  float max_ssd_per_sample = 300;        ///< grey levels^2
  float uniqueness_ratio = 0.7f;         ///< best / second best (non-adjacent) SSD
  float min_epipolar_gradient = 6;  ///< grey levels, RMS difference of neighbouring host samples
};

struct EpipolarMatch {
  enum Result { kFound, kNoMatch, kSkipped };
  Result result =
      kSkipped;  ///< kSkipped: not observable in this frame (outside, no gradient, no baseline)
  float distance = 0;        ///< map units along the host bearing (kFound)
  Eigen::Vector2f px{0, 0};  ///< matched pixel in the frame (kFound)
};

/// Searches `seed` (of the host image) in the frame image; both 8-bit grey and the same camera.
/// T_cur_host maps host-camera coordinates into the frame's camera.
EpipolarMatch searchEpipolar(const cv::Mat& host, const cv::Mat& frame,
                             const Eigen::Matrix3f& R_cur_host, const Eigen::Vector3f& t_cur_host,
                             const DepthSeed& seed, const EpipolarSearchParams& params);

}  // namespace slamaware::slam
