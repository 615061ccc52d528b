#include "procs/slam/slam_messages.h"

#include <cmath>

namespace slamaware::slam {

pose_t toMessage(const PoseOutput& p) {
  pose_t m;
  m.utime = p.utime;
  m.seq = p.seq;
  m.state = static_cast<int8_t>(p.state);
  se3ToArrays(p.T_world_camera, m.position, m.orientation);
  m.map_id = p.map_id;
  m.num_tracked = p.num_tracked;
  m.reference_keyframe_id = static_cast<int32_t>(p.reference_keyframe_id);
  return m;
}

keyframe_t toMessage(const KeyframeOutput& k) {
  keyframe_t m;
  m.utime = k.utime;
  m.seq = k.seq;
  m.id = static_cast<int32_t>(k.id);
  m.map_id = k.map_id;
  se3ToArrays(k.T_world_camera, m.position, m.orientation);
  m.num_points = k.num_points;
  for (const auto& [id, w] : k.covisible) {
    m.covisible_ids.push_back(static_cast<int32_t>(id));
    m.covisible_weights.push_back(w);
  }
  m.num_covisible = static_cast<int32_t>(m.covisible_ids.size());
  m.culled = k.culled;
  return m;
}

point_cloud_t toMessage(const CloudOutput& c) {
  point_cloud_t m;
  m.utime = c.utime;
  m.seq = c.seq;
  m.map_id = c.map_id;
  m.keyframe_id = static_cast<int32_t>(c.keyframe_id);
  m.full = c.full;
  const size_t n = c.points.size();
  m.num_points = static_cast<int32_t>(n);
  m.x.resize(n);
  m.y.resize(n);
  m.z.resize(n);
  m.r.resize(n);
  m.g.resize(n);
  m.b.resize(n);
  m.depth_std.resize(n);
  m.keyframe_ids.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const CloudPoint& p = c.points[i];
    m.x[i] = p.p_world.x();
    m.y[i] = p.p_world.y();
    m.z[i] = p.p_world.z();
    m.r[i] = static_cast<int8_t>(p.rgb[0]);
    m.g[i] = static_cast<int8_t>(p.rgb[1]);
    m.b[i] = static_cast<int8_t>(p.rgb[2]);
    m.depth_std[i] = p.depth_std;
    m.keyframe_ids[i] = static_cast<int32_t>(p.keyframe_id);
  }
  m.num_keyframes = static_cast<int32_t>(c.keyframe_centers.size());
  for (const auto& [id, center] : c.keyframe_centers) {
    m.kf_ids.push_back(static_cast<int32_t>(id));
    m.kf_x.push_back(center.x());
    m.kf_y.push_back(center.y());
    m.kf_z.push_back(center.z());
  }
  return m;
}

}  // namespace slamaware::slam
