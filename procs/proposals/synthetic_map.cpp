#include "procs/proposals/synthetic_map.h"

#include <cmath>

namespace slamaware::synthmap {

// Points on the side and top of an upright cylinder standing on z = 0 at (cx, cy), spaced ~step.
std::vector<MapPoint> cylinder(float cx, float cy, float radius, float height, float step,
                               uint8_t grey) {
  std::vector<MapPoint> out;
  const int around = std::max(8, static_cast<int>(2 * M_PI * radius / step));
  for (float z = 0.005f; z <= height; z += step)
    for (int i = 0; i < around; ++i) {
      const float a = static_cast<float>(2 * M_PI * i / around);
      out.push_back({Eigen::Vector3f(cx + radius * std::cos(a), cy + radius * std::sin(a), z), grey,
                     grey, grey});
    }
  for (float x = -radius; x <= radius; x += step)
    for (float y = -radius; y <= radius; y += step)
      if (x * x + y * y < radius * radius)
        out.push_back({Eigen::Vector3f(cx + x, cy + y, height), grey, grey, grey});
  return out;
}

// A square table top at z = 0, side `size`, centred at the origin.
std::vector<MapPoint> table(float size, float step) {
  std::vector<MapPoint> out;
  for (float x = -size / 2; x <= size / 2; x += step)
    for (float y = -size / 2; y <= size / 2; y += step)
      out.push_back({Eigen::Vector3f(x, y, 0), 200, 200, 200});
  return out;
}

std::vector<MapPoint> join(std::vector<MapPoint> a, const std::vector<MapPoint>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

// A camera 1 m above the table looking straight down (world z up; camera z forward = world -z).
SE3 lookingDown(double height) {
  SE3 T = SE3::Identity();
  Eigen::Matrix3d R;
  R << 1, 0, 0, 0, -1, 0, 0, 0, -1;  // camera x = world x, camera y = world -y, camera z = world -z
  T.linear() = R;
  T.translation() = Eigen::Vector3d(0, 0, height);
  return T;
}

SE3 lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  SE3 T = SE3::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = y;
  T.linear().col(2) = z;
  T.translation() = eye;
  return T;
}

CameraModel vga() { return CameraModel(640, 480, 500, 500, 319.5, 239.5); }

camera_info_t vgaInfo() {
  camera_info_t info{};
  info.frame_id = "camera";
  info.width = 640;
  info.height = 480;
  info.fx = info.fy = 500;
  info.cx = 319.5;
  info.cy = 239.5;
  info.source = "test";
  return info;
}

point_cloud_t cloudMessage(int map_id, const std::vector<MapPoint>& points, bool full,
                           int keyframe) {
  point_cloud_t c{};
  c.map_id = map_id;
  c.full = full;
  c.keyframe_id = keyframe;
  c.num_points = static_cast<int32_t>(points.size());
  for (const auto& p : points) {
    c.x.push_back(p.p.x());
    c.y.push_back(p.p.y());
    c.z.push_back(p.p.z());
    c.r.push_back(p.r);
    c.g.push_back(p.g);
    c.b.push_back(p.b);
    c.keyframe_ids.push_back(keyframe);
    c.depth_std.push_back(0.001f);
  }
  return c;
}

pose_t poseMessage(int seq, int8_t state, const SE3& T_world_camera, int map_id) {
  pose_t p{};
  p.seq = seq;
  p.utime = 1000 * seq;
  p.state = state;
  p.map_id = map_id;
  se3ToArrays(T_world_camera, p.position, p.orientation);
  return p;
}

}  // namespace slamaware::synthmap
