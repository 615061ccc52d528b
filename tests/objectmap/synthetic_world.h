#pragma once
// A small scene for the object map tests: box-shaped objects on a table in front of a wall, seen
// by a camera moving along an arc, as the messages the pipeline would send (CAMERA_INFO,
// SLAM_POSE, SLAM_MAP, PROPOSALS, DETECTIONS). Proposals are the exact projections of each
// object's points; detections favour the true class, with some views confidently wrong.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "common/camera_model.h"
#include "common/geometry.h"
#include "slamaware/camera_info_t.hpp"
#include "slamaware/detections_t.hpp"
#include "slamaware/point_cloud_t.hpp"
#include "slamaware/pose_t.hpp"
#include "slamaware/proposals_t.hpp"

namespace slamaware::test {

struct SyntheticObject {
  int32_t candidate = 0;      ///< candidate id of its proposals
  Eigen::Vector3d centre;     ///< map units
  Eigen::Vector3d half_size;  ///< map units
  int cls = 0;                ///< index into SyntheticWorld::classNames()
};

struct SyntheticWorldOptions {
  int frames = 40;
  double arc_deg = 60;   ///< the camera moves over this arc around the scene centre
  double radius = 1.0;   ///< map units, camera distance to the scene centre
  double height = 0.45;  ///< map units, camera above the table
  bool wall = true;      ///< a textured wall behind the objects (z = wall_z)
  double wall_z = 0.5;
  bool table = true;
  double spacing = 0.005;        ///< map units between object surface points
  int keyframes = 5;             ///< SLAM_MAP incremental clouds (points split between them)
  double wrong_view_rate = 0.2;  ///< share of views that confidently pick a wrong class
  uint32_t seed = 7;
};

class SyntheticWorld {
 public:
  SyntheticWorld(const SyntheticWorldOptions& options, std::vector<SyntheticObject> objects);

  /// bowl, cap, coffee_mug, soda_can, background (the recognizer's order: background last).
  static const std::vector<std::string>& classNames();
  /// Three objects on the table: a coffee_mug (candidate 11), a bowl (12), a soda_can (13).
  static std::vector<SyntheticObject> defaultObjects();

  const CameraModel& camera() const { return camera_; }
  camera_info_t cameraInfo() const;
  int64_t utime(int frame) const { return 1000000 + static_cast<int64_t>(frame) * 33333; }
  SE3 pose(int frame) const;
  pose_t poseMessage(int frame, int32_t map_id, int32_t seq_offset = 0) const;
  /// The map as incremental clouds, one per keyframe (keyframe k is the camera of frame
  /// k * frames / keyframes).
  std::vector<point_cloud_t> keyframeClouds(int32_t map_id) const;
  point_cloud_t fullCloud(int32_t map_id) const;
  proposals_t proposals(int frame, int32_t map_id, int32_t seq_offset = 0) const;
  /// Detections for the boxes of proposals(frame); deterministic per (seed, frame, candidate).
  detections_t detections(int frame, int32_t map_id, int32_t seq_offset = 0) const;

  const std::vector<SyntheticObject>& objects() const { return objects_; }
  /// Surface points of object i (map units).
  const std::vector<Eigen::Vector3d>& objectPoints(size_t i) const { return object_points_[i]; }
  const std::vector<Eigen::Vector3d>& backgroundPoints() const { return background_points_; }

 private:
  SyntheticWorldOptions o_;
  std::vector<SyntheticObject> objects_;
  CameraModel camera_;
  std::vector<std::vector<Eigen::Vector3d>> object_points_;
  std::vector<Eigen::Vector3d> background_points_;
};

}  // namespace slamaware::test
