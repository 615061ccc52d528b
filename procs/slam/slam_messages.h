#pragma once
// SLAM outputs <-> LCM messages (pose_t, keyframe_t, point_cloud_t), and camera_info_t -> camera.
#include <string>

#include "common/bus/image_msg.h"
#include "common/camera_model.h"
#include "procs/slam/slam_system.h"
#include "slamaware/camera_info_t.hpp"
#include "slamaware/keyframe_t.hpp"
#include "slamaware/point_cloud_t.hpp"
#include "slamaware/pose_t.hpp"

namespace slamaware::slam {

pose_t toMessage(const PoseOutput& pose);
keyframe_t toMessage(const KeyframeOutput& kf);
point_cloud_t toMessage(const CloudOutput& cloud);

}  // namespace slamaware::slam
