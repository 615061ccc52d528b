#pragma once
// Two-view triangulation of one point.
#include <Eigen/Core>

#include "common/geometry.h"

namespace slamaware::slam {

/// Linear (DLT) triangulation: the point seen along ray1 (x, y, 1) from camera 1 and ray2 from
/// camera 2, both poses T_camera_world. False when the system is degenerate or the point is at
/// infinity.
bool triangulateDlt(const SE3& T1_camera_world, const SE3& T2_camera_world,
                    const Eigen::Vector3d& ray1, const Eigen::Vector3d& ray2,
                    Eigen::Vector3d* p_world);

/// Cosine of the angle at p between the rays from the two camera centres.
double parallaxCos(const Eigen::Vector3d& p, const Eigen::Vector3d& center1,
                   const Eigen::Vector3d& center2);

}  // namespace slamaware::slam
