#pragma once
// Synthetic semi-dense maps for the proposals tests and benchmark, in map units: cylinders
// standing on a table at z = 0, a camera looking down at it, and the messages SLAM would
// publish about them.
#include <vector>

#include "common/camera_model.h"
#include "common/geometry.h"
#include "procs/proposals/candidate_map.h"
#include "slamaware/camera_info_t.hpp"
#include "slamaware/point_cloud_t.hpp"
#include "slamaware/pose_t.hpp"

namespace slamaware::synthmap {

using proposals::MapPoint;

/// Points on the side and top of an upright cylinder standing on z = 0 at (cx, cy), ~step apart.
std::vector<MapPoint> cylinder(float cx, float cy, float radius, float height, float step,
                               uint8_t grey = 128);
/// A square table top at z = 0, side `size`, centred at the origin.
std::vector<MapPoint> table(float size, float step);
std::vector<MapPoint> join(std::vector<MapPoint> a, const std::vector<MapPoint>& b);
/// A camera `height` above the table looking straight down (world z up).
SE3 lookingDown(double height);
/// A camera at `eye` looking at `target`, upright (x right, y down, z forward; world z up).
SE3 lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target);
/// 640x480, f = 500 px, no distortion; and its CAMERA_INFO.
CameraModel vga();
camera_info_t vgaInfo();
point_cloud_t cloudMessage(int map_id, const std::vector<MapPoint>& points, bool full = true,
                           int keyframe = 0);
pose_t poseMessage(int seq, int8_t state, const SE3& T_world_camera, int map_id = 1);

}  // namespace slamaware::synthmap
