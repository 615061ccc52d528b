#pragma once
// SLAM outputs <-> LCM messages (pose_t, keyframe_t, point_cloud_t), and camera_info_t -> camera.
#include <string>

#include "common/camera_model.h"
#include "procs/slam/slam_system.h"
#include "slamaware/camera_info_t.hpp"
#include "slamaware/keyframe_t.hpp"
#include "slamaware/point_cloud_t.hpp"
#include "slamaware/pose_t.hpp"

namespace slamaware {

pose_t toMessage(const PoseOutput& pose);
keyframe_t toMessage(const KeyframeOutput& kf);
point_cloud_t toMessage(const CloudOutput& cloud);

/// The camera a camera_info_t describes; false (and *why) when it is not a usable camera.
bool cameraFromMessage(const camera_info_t& info, CameraModel* camera, std::string* why);

}  // namespace slamaware
