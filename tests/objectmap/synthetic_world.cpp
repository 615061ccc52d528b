#include "tests/objectmap/synthetic_world.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace slamaware::test {

namespace {

constexpr double kTableY = 0.1;  // the table's plane (y points down)
const Eigen::Vector3d kTarget(0, 0.05, 0);

void addFace(std::vector<Eigen::Vector3d>& out, const Eigen::Vector3d& origin,
             const Eigen::Vector3d& u, const Eigen::Vector3d& v, double spacing) {
  const int nu = std::max(1, static_cast<int>(std::round(u.norm() / spacing)));
  const int nv = std::max(1, static_cast<int>(std::round(v.norm() / spacing)));
  for (int i = 0; i <= nu; ++i)
    for (int j = 0; j <= nv; ++j)
      out.push_back(origin + u * (double(i) / nu) + v * (double(j) / nv));
}

}  // namespace

const std::vector<std::string>& SyntheticWorld::classNames() {
  static const std::vector<std::string> names{"bowl", "cap", "coffee_mug", "soda_can",
                                              "background"};
  return names;
}

std::vector<SyntheticObject> SyntheticWorld::defaultObjects() {
  return {{11, Eigen::Vector3d(-0.25, kTableY - 0.05, 0.0), Eigen::Vector3d(0.04, 0.05, 0.04), 2},
          {12, Eigen::Vector3d(0.0, kTableY - 0.035, 0.05), Eigen::Vector3d(0.07, 0.035, 0.07), 0},
          {13, Eigen::Vector3d(0.25, kTableY - 0.06, -0.05), Eigen::Vector3d(0.03, 0.06, 0.03), 3}};
}

SyntheticWorld::SyntheticWorld(const SyntheticWorldOptions& options,
                               std::vector<SyntheticObject> objects)
    : o_(options), objects_(std::move(objects)), camera_(640, 480, 500, 500, 319.5, 239.5) {
  for (const auto& ob : objects_) {
    std::vector<Eigen::Vector3d> pts;
    const Eigen::Vector3d lo = ob.centre - ob.half_size, s = 2 * ob.half_size;
    const Eigen::Vector3d ex(s.x(), 0, 0), ey(0, s.y(), 0), ez(0, 0, s.z());
    addFace(pts, lo, ex, ey, o_.spacing);
    addFace(pts, lo + ez, ex, ey, o_.spacing);
    addFace(pts, lo, ey, ez, o_.spacing);
    addFace(pts, lo + ex, ey, ez, o_.spacing);
    addFace(pts, lo, ex, ez, o_.spacing);
    addFace(pts, lo + ey, ex, ez, o_.spacing);
    object_points_.push_back(std::move(pts));
  }
  // Background: sparser, as a semi-dense map of textured planes is.
  if (o_.table)
    addFace(background_points_, Eigen::Vector3d(-0.5, kTableY, -0.35), Eigen::Vector3d(1.0, 0, 0),
            Eigen::Vector3d(0, 0, 0.8), 0.01);
  if (o_.wall)
    addFace(background_points_, Eigen::Vector3d(-0.6, -0.5, o_.wall_z), Eigen::Vector3d(1.2, 0, 0),
            Eigen::Vector3d(0, 0.6, 0), 0.01);
}

camera_info_t SyntheticWorld::cameraInfo() const {
  camera_info_t m{};
  m.utime = 1;
  m.frame_id = "camera";
  m.width = camera_.width();
  m.height = camera_.height();
  m.fx = camera_.fx();
  m.fy = camera_.fy();
  m.cx = camera_.cx();
  m.cy = camera_.cy();
  for (double& d : m.distortion) d = 0;
  m.source = "synthetic object map test";
  return m;
}

SE3 SyntheticWorld::pose(int frame) const {
  const double t = o_.frames > 1 ? double(frame) / (o_.frames - 1) : 0.5;
  const double theta = (t - 0.5) * o_.arc_deg * M_PI / 180;
  const Eigen::Vector3d c = kTarget + Eigen::Vector3d(o_.radius * std::sin(theta), -o_.height,
                                                      -o_.radius * std::cos(theta));
  const Eigen::Vector3d f = (kTarget - c).normalized();
  const Eigen::Vector3d x = Eigen::Vector3d(0, 1, 0).cross(f).normalized();
  const Eigen::Vector3d y = f.cross(x);
  SE3 T = SE3::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = y;
  T.linear().col(2) = f;
  T.translation() = c;
  return T;
}

pose_t SyntheticWorld::poseMessage(int frame, int32_t map_id, int32_t seq_offset) const {
  pose_t m{};
  m.utime = utime(frame + seq_offset);
  m.seq = frame + seq_offset;
  m.state = pose_t::STATE_TRACKING;
  se3ToArrays(pose(frame), m.position, m.orientation);
  m.map_id = map_id;
  m.num_tracked = 200;
  m.reference_keyframe_id = 0;
  return m;
}

std::vector<point_cloud_t> SyntheticWorld::keyframeClouds(int32_t map_id) const {
  std::vector<Eigen::Vector3d> all = background_points_;
  for (const auto& p : object_points_) all.insert(all.end(), p.begin(), p.end());
  const int nk = std::max(1, o_.keyframes);
  std::vector<point_cloud_t> clouds(static_cast<size_t>(nk));
  for (int k = 0; k < nk; ++k) {
    point_cloud_t& c = clouds[static_cast<size_t>(k)];
    const int frame = k * o_.frames / nk;
    c.utime = utime(frame);
    c.seq = frame;
    c.map_id = map_id;
    c.keyframe_id = k;
    c.full = false;
    for (int j = 0; j <= k; ++j) {
      const Eigen::Vector3d kc = pose(j * o_.frames / nk).translation();
      c.kf_ids.push_back(j);
      c.kf_x.push_back(static_cast<float>(kc.x()));
      c.kf_y.push_back(static_cast<float>(kc.y()));
      c.kf_z.push_back(static_cast<float>(kc.z()));
    }
    c.num_keyframes = k + 1;
  }
  for (size_t i = 0; i < all.size(); ++i) {
    point_cloud_t& c = clouds[i % static_cast<size_t>(nk)];
    c.x.push_back(static_cast<float>(all[i].x()));
    c.y.push_back(static_cast<float>(all[i].y()));
    c.z.push_back(static_cast<float>(all[i].z()));
    c.r.push_back(128);
    c.g.push_back(128);
    c.b.push_back(128);
    c.depth_std.push_back(0.005f);
    c.keyframe_ids.push_back(c.keyframe_id);
  }
  for (auto& c : clouds) c.num_points = static_cast<int32_t>(c.x.size());
  return clouds;
}

point_cloud_t SyntheticWorld::fullCloud(int32_t map_id) const {
  const auto parts = keyframeClouds(map_id);
  point_cloud_t full = parts.back();
  full.full = true;
  full.keyframe_id = -1;
  full.x.clear(), full.y.clear(), full.z.clear(), full.r.clear(), full.g.clear(), full.b.clear();
  full.depth_std.clear(), full.keyframe_ids.clear();
  for (const auto& c : parts) {
    full.x.insert(full.x.end(), c.x.begin(), c.x.end());
    full.y.insert(full.y.end(), c.y.begin(), c.y.end());
    full.z.insert(full.z.end(), c.z.begin(), c.z.end());
    full.r.insert(full.r.end(), c.r.begin(), c.r.end());
    full.g.insert(full.g.end(), c.g.begin(), c.g.end());
    full.b.insert(full.b.end(), c.b.begin(), c.b.end());
    full.depth_std.insert(full.depth_std.end(), c.depth_std.begin(), c.depth_std.end());
    full.keyframe_ids.insert(full.keyframe_ids.end(), c.keyframe_ids.begin(), c.keyframe_ids.end());
  }
  full.num_points = static_cast<int32_t>(full.x.size());
  return full;
}

proposals_t SyntheticWorld::proposals(int frame, int32_t map_id, int32_t seq_offset) const {
  proposals_t m{};
  m.utime = utime(frame + seq_offset);
  m.seq = frame + seq_offset;
  m.map_id = map_id;
  const SE3 T_camera_world = pose(frame).inverse();
  for (size_t i = 0; i < objects_.size(); ++i) {
    double u0 = 1e9, v0 = 1e9, u1 = -1e9, v1 = -1e9;
    std::vector<double> depths;
    for (const auto& p : object_points_[i]) {
      const Eigen::Vector3d pc = T_camera_world * p;
      if (pc.z() <= 0.05) continue;
      const Eigen::Vector2d px = camera_.project(pc);
      u0 = std::min(u0, px.x()), v0 = std::min(v0, px.y()), u1 = std::max(u1, px.x()),
      v1 = std::max(v1, px.y());
      depths.push_back(pc.z());
    }
    if (depths.empty()) continue;
    u0 = std::max(0.0, u0), v0 = std::max(0.0, v0);
    u1 = std::min(camera_.width() - 1.0, u1), v1 = std::min(camera_.height() - 1.0, v1);
    if (u1 - u0 < 20 || v1 - v0 < 20) continue;
    std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
    box_t b;
    b.x = static_cast<float>(u0);
    b.y = static_cast<float>(v0);
    b.w = static_cast<float>(u1 - u0);
    b.h = static_cast<float>(v1 - v0);
    m.boxes.push_back(b);
    m.candidate_ids.push_back(objects_[i].candidate);
    m.median_depth.push_back(static_cast<float>(depths[depths.size() / 2]));
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const auto& p : object_points_[i]) centre += p;
    centre /= static_cast<double>(object_points_[i].size());
    const Eigen::Vector3f to_camera =
        (pose(frame).translation() - centre).normalized().cast<float>();
    m.view_direction.push_back({to_camera.x(), to_camera.y(), to_camera.z()});
  }
  m.num_boxes = static_cast<int32_t>(m.boxes.size());
  return m;
}

detections_t SyntheticWorld::detections(int frame, int32_t map_id, int32_t seq_offset) const {
  const proposals_t p = proposals(frame, map_id, seq_offset);
  detections_t d{};
  d.utime = p.utime;
  d.seq = p.seq;
  d.map_id = map_id;
  d.class_names = classNames();
  d.num_classes = static_cast<int32_t>(d.class_names.size());
  d.num_boxes = p.num_boxes;
  d.boxes = p.boxes;
  d.candidate_ids = p.candidate_ids;
  d.classified_seq.assign(p.candidate_ids.size(), p.seq);
  d.encode_ms = 0;
  const int nc = d.num_classes;
  for (int32_t b = 0; b < p.num_boxes; ++b) {
    int cls = nc - 1;
    for (const auto& o : objects_)
      if (o.candidate == p.candidate_ids[static_cast<size_t>(b)]) cls = o.cls;
    std::mt19937 rng(o_.seed * 7919u + static_cast<uint32_t>(frame) * 104729u +
                     static_cast<uint32_t>(p.candidate_ids[static_cast<size_t>(b)]));
    std::normal_distribution<double> noise(0, 0.4);
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<double> logit(static_cast<size_t>(nc));
    for (auto& l : logit) l = noise(rng);
    if (u(rng) < o_.wrong_view_rate) {
      int wrong = static_cast<int>(u(rng) * (nc - 1));
      if (wrong >= cls) ++wrong;
      logit[static_cast<size_t>(wrong)] += 2.5;  // confidently wrong
      logit[static_cast<size_t>(cls)] += 0.8;
    } else {
      logit[static_cast<size_t>(cls)] += 2.0;
    }
    double z = 0;
    for (double l : logit) z += std::exp(l);
    std::vector<float> row;
    for (double l : logit) row.push_back(static_cast<float>(l - std::log(z)));
    d.log_prob.push_back(row);
  }
  return d;
}

}  // namespace slamaware::test
