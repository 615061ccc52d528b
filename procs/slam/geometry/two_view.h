#pragma once
// Two-view reconstruction for monocular initialisation (after ORB-SLAM, Mur-Artal et al. 2015,
// section IV): a homography (RANSAC + DLT) and the epipolar geometry (the calibrated five-point
// essential matrix, as a fundamental matrix) are each scored by their symmetric transfer /
// epipolar errors; the homography is chosen when R_H = S_H / (S_H + S_F) is above a threshold
// (planar or low-parallax scenes). The chosen model is decomposed into (R, t) candidates and the
// one that puts most points in front of both cameras with small reprojection error is kept, if
// it is clearly better than the others and the parallax is large enough.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "common/geometry.h"
#include "procs/slam/slam_options.h"

namespace slamaware::slam {

struct TwoViewResult {
  bool ok = false;
  char model = '?';                    ///< 'H' (homography) or 'F' (fundamental matrix)
  SE3 T_cur_ref = SE3::Identity();     ///< p_cur = T_cur_ref * p_ref; |t| is arbitrary (unit)
  std::vector<Eigen::Vector3d> p_ref;  ///< triangulated point per match, reference camera frame
  std::vector<bool> triangulated;  ///< per match: a good point (in front, small error, parallax)
  int num_inliers = 0;             ///< inliers of the chosen model
  int num_triangulated = 0;
  double parallax_deg = 0;  ///< median parallax of the triangulated points
  double score_ratio = 0;   ///< R_H
  std::string reason;       ///< why it failed
};

/// Reconstructs the relative pose and structure of matched undistorted pixels px_ref[i] <->
/// px_cur[i] of a pinhole camera K. Deterministic for a given seed.
TwoViewResult reconstructTwoView(const std::vector<Eigen::Vector2d>& px_ref,
                                 const std::vector<Eigen::Vector2d>& px_cur,
                                 const Eigen::Matrix3d& K, const InitOptions& options,
                                 uint64_t seed);

}  // namespace slamaware::slam
