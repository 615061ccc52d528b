#include "procs/slam/matching/matcher.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "procs/slam/map/keyframe.h"
#include "procs/slam/map/map.h"
#include "procs/slam/map/map_point.h"

namespace slamaware::slam {

namespace {

constexpr int kRotationBins = 30;

int rotationBin(float angle_a, float angle_b) {
  float rot = angle_b - angle_a;
  if (rot < 0) rot += 360.f;
  return std::clamp(static_cast<int>(std::lround(rot * kRotationBins / 360.f)), 0, kRotationBins) %
         kRotationBins;
}

// The three largest bins (a bin counts only if it has at least a tenth of the largest).
std::vector<bool> dominantBins(const std::vector<int>& counts) {
  std::vector<int> order(counts.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) { return counts[x] > counts[y]; });
  std::vector<bool> keep(counts.size(), false);
  if (counts[order[0]] == 0) return keep;
  for (int k = 0; k < 3; ++k)
    if (counts[order[k]] > 0 && counts[order[k]] >= 0.1 * counts[order[0]]) keep[order[k]] = true;
  return keep;
}

bool usableMatch(const std::shared_ptr<MapPoint>& p) {
  return p && !p->bad && p->numObservations() > 0;
}

}  // namespace

void filterByRotation(const FrameFeatures& a, const FrameFeatures& b, Matches* matches) {
  std::vector<int> counts(kRotationBins, 0);
  for (const auto& [i, j] : *matches)
    ++counts[rotationBin(a.keypoints[i].angle, b.keypoints[j].angle)];
  const std::vector<bool> keep = dominantBins(counts);
  Matches out;
  for (const auto& m : *matches)
    if (keep[rotationBin(a.keypoints[m.first].angle, b.keypoints[m.second].angle)])
      out.push_back(m);
  *matches = std::move(out);
}

Matches matchBruteForce(const FrameFeatures& a, const std::vector<int>& a_indices,
                        const FrameFeatures& b, double ratio, int max_distance,
                        bool check_rotation) {
  const int nb = b.size();
  std::vector<int> best_for_b(nb, -1), best_dist_b(nb, std::numeric_limits<int>::max());
  std::vector<std::pair<int, int>> candidate(a_indices.size(), {-1, 0});
  for (size_t k = 0; k < a_indices.size(); ++k) {
    const uint8_t* da = a.descriptor(a_indices[k]);
    int best = std::numeric_limits<int>::max(), second = std::numeric_limits<int>::max(),
        best_j = -1;
    for (int j = 0; j < nb; ++j) {
      const int d = descriptorDistance(da, b.descriptor(j));
      if (d < best) {
        second = best;
        best = d;
        best_j = j;
      } else if (d < second) {
        second = d;
      }
    }
    if (best_j < 0 || best > max_distance || best >= ratio * second) continue;
    candidate[k] = {best_j, best};
    if (best < best_dist_b[best_j]) {
      best_dist_b[best_j] = best;
      best_for_b[best_j] = static_cast<int>(k);
    }
  }
  Matches matches;
  for (size_t k = 0; k < a_indices.size(); ++k) {
    const int j = candidate[k].first;
    if (j >= 0 && best_for_b[j] == static_cast<int>(k)) matches.push_back({a_indices[k], j});
  }
  if (check_rotation) filterByRotation(a, b, &matches);
  return matches;
}

bool projectMapPoint(const MapPoint& p, const SE3& T, const Eigen::Vector3d& center,
                     const Intrinsics& in, Projection* out) {
  const Eigen::Vector3d pc = T * p.p_world;
  if (pc.z() <= 0) return false;
  out->px = in.project(pc);
  if (!in.inBounds(out->px)) return false;
  const Eigen::Vector3d po = p.p_world - center;
  out->distance = po.norm();
  if (out->distance < 0.8 * p.min_distance || out->distance > 1.2 * p.max_distance) return false;
  out->view_cos = po.dot(p.normal) / out->distance;
  if (out->view_cos < 0.5) return false;
  out->level = p.predictLevel(out->distance, in.pyramid);
  return true;
}

int searchByProjection(Frame& frame, const Frame& previous, double radius_px) {
  const FrameFeatures& f = *frame.features;
  const Intrinsics& in = *f.intrinsics;
  Matches matches;
  for (int i = 0; i < previous.size(); ++i) {
    const auto& p = previous.points[i];
    if (!p || previous.outlier[i] || p->bad) continue;
    const Eigen::Vector3d pc = frame.T_camera_world * p->p_world;
    if (pc.z() <= 0) continue;
    const Eigen::Vector2d px = in.project(pc);
    if (!in.inBounds(px)) continue;
    const int level = previous.features->level(i);
    const double r = radius_px * in.pyramid.scale[level];
    int best = std::numeric_limits<int>::max(), best_j = -1;
    for (int j : f.inArea(px.x(), px.y(), r, std::max(0, level - 1), level + 1)) {
      if (usableMatch(frame.points[j])) continue;
      const int d = descriptorDistance(p->descriptor.data(), f.descriptor(j));
      if (d < best) {
        best = d;
        best_j = j;
      }
    }
    if (best_j >= 0 && best <= kMatchDistanceHigh) {
      frame.points[best_j] = p;
      frame.outlier[best_j] = false;
      matches.push_back({i, best_j});
    }
  }
  const Matches all = matches;
  filterByRotation(*previous.features, f, &matches);
  std::vector<bool> kept(f.size(), false);
  for (const auto& m : matches) kept[m.second] = true;
  for (const auto& m : all)
    if (!kept[m.second]) frame.points[m.second] = nullptr;
  return static_cast<int>(matches.size());
}

int searchLocalPoints(Frame& frame, const std::vector<std::shared_ptr<MapPoint>>& points,
                      const std::vector<Projection>& projections, double radius_factor,
                      double ratio) {
  const FrameFeatures& f = *frame.features;
  const ScalePyramid& pyr = f.intrinsics->pyramid;
  int added = 0;
  for (size_t k = 0; k < points.size(); ++k) {
    const auto& p = points[k];
    if (p->bad) continue;
    const Projection& pr = projections[k];
    // A wider window when the point is seen at an angle (its appearance changes more).
    const double r = (pr.view_cos > 0.998 ? 2.5 : 4.0) * radius_factor * pyr.scale[pr.level];
    int best = std::numeric_limits<int>::max(), second = std::numeric_limits<int>::max();
    int best_j = -1, best_level = -1, second_level = -1;
    for (int j : f.inArea(pr.px.x(), pr.px.y(), r, std::max(0, pr.level - 1), pr.level)) {
      if (usableMatch(frame.points[j])) continue;
      const int d = descriptorDistance(p->descriptor.data(), f.descriptor(j));
      if (d < best) {
        second = best;
        second_level = best_level;
        best = d;
        best_j = j;
        best_level = f.level(j);
      } else if (d < second) {
        second = d;
        second_level = f.level(j);
      }
    }
    if (best_j < 0 || best > kMatchDistanceHigh) continue;
    if (best_level == second_level && best > ratio * second) continue;
    frame.points[best_j] = p;
    frame.outlier[best_j] = false;
    ++added;
  }
  return added;
}

int searchKeyFramePoints(Frame& frame, const KeyFrame& kf, double radius_px, int max_distance) {
  const FrameFeatures& f = *frame.features;
  const Intrinsics& in = *f.intrinsics;
  const Eigen::Vector3d center = frame.center();
  Matches matches;
  for (int i = 0; i < kf.size(); ++i) {
    const auto& p = kf.points[i];
    if (!p || p->bad) continue;
    if (std::find(frame.points.begin(), frame.points.end(), p) != frame.points.end()) continue;
    Projection pr;
    if (!projectMapPoint(*p, frame.T_camera_world, center, in, &pr)) continue;
    const double r = radius_px * in.pyramid.scale[pr.level];
    int best = std::numeric_limits<int>::max(), best_j = -1;
    for (int j : f.inArea(pr.px.x(), pr.px.y(), r, std::max(0, pr.level - 1), pr.level + 1)) {
      if (frame.points[j]) continue;
      const int d = descriptorDistance(p->descriptor.data(), f.descriptor(j));
      if (d < best) {
        best = d;
        best_j = j;
      }
    }
    if (best_j >= 0 && best <= max_distance) {
      frame.points[best_j] = p;
      frame.outlier[best_j] = false;
      matches.push_back({i, best_j});
    }
  }
  const Matches all = matches;
  filterByRotation(*kf.features, f, &matches);
  std::vector<bool> kept(f.size(), false);
  for (const auto& m : matches) kept[m.second] = true;
  for (const auto& m : all)
    if (!kept[m.second]) frame.points[m.second] = nullptr;
  return static_cast<int>(matches.size());
}

Eigen::Matrix3d fundamentalFromPoses(const SE3& T1, const SE3& T2, const Eigen::Matrix3d& K) {
  const SE3 T21 = T2 * T1.inverse();
  const Eigen::Matrix3d Kinv = K.inverse();
  return Kinv.transpose() * skew(T21.translation()) * T21.linear() * Kinv;
}

Matches searchForTriangulation(const KeyFrame& kf1, const KeyFrame& kf2, const Eigen::Matrix3d& F21,
                               const std::vector<bool>* skip1) {
  const FrameFeatures& f1 = *kf1.features;
  const FrameFeatures& f2 = *kf2.features;
  const Intrinsics& in = *f1.intrinsics;
  const ScalePyramid& pyr = in.pyramid;
  // Epipole: kf1's centre seen from kf2. Matches too close to it are ill-conditioned.
  const Eigen::Vector3d c1_in_2 = kf2.T_camera_world * kf1.center();
  const bool epipole_valid = c1_in_2.z() > 1e-9;
  const Eigen::Vector2d epipole = epipole_valid ? in.project(c1_in_2) : Eigen::Vector2d(1e9, 1e9);

  // kf2's features without a point, their descriptors side by side: every free feature of kf1 is
  // compared with each of them.
  constexpr int kBytes = OrbExtractor::kDescriptorBytes;
  std::vector<int> free2;
  std::vector<uint8_t> free2_desc;
  free2_desc.reserve(static_cast<size_t>(f2.size()) * kBytes);
  for (int j = 0; j < f2.size(); ++j)
    if (!kf2.points[j]) {
      free2.push_back(j);
      free2_desc.insert(free2_desc.end(), f2.descriptor(j), f2.descriptor(j) + kBytes);
    }
  std::vector<int> best_for_2(f2.size(), -1),
      best_dist_2(f2.size(), std::numeric_limits<int>::max());
  std::vector<int> match_of_1(f1.size(), -1);
  for (int i = 0; i < f1.size(); ++i) {
    if (kf1.points[i] || (skip1 && (*skip1)[i])) continue;
    const uint8_t* d1 = f1.descriptor(i);
    const Eigen::Vector3d line = F21 * f1.px[i].homogeneous();
    const double line_norm2 = line.x() * line.x() + line.y() * line.y();
    if (line_norm2 < 1e-18) continue;
    int best = kMatchDistanceLow + 1, best_j = -1;
    for (size_t k = 0; k < free2.size(); ++k) {
      const int d = descriptorDistance(d1, free2_desc.data() + kBytes * k);
      if (d >= best) continue;
      const int j = free2[k];
      const int level2 = f2.level(j);
      if ((f2.px[j] - epipole).squaredNorm() < 100 * pyr.scale[level2]) continue;
      const double num = line.dot(f2.px[j].homogeneous());
      // Distance to the epipolar line under the 1-dof chi-square threshold (95%).
      if (num * num / line_norm2 >= 3.84 * pyr.sigma2[level2]) continue;
      best = d;
      best_j = j;
    }
    if (best_j < 0) continue;
    match_of_1[i] = best_j;
    if (best < best_dist_2[best_j]) {
      best_dist_2[best_j] = best;
      best_for_2[best_j] = i;
    }
  }
  Matches matches;
  for (int i = 0; i < f1.size(); ++i)
    if (match_of_1[i] >= 0 && best_for_2[match_of_1[i]] == i) matches.push_back({i, match_of_1[i]});
  filterByRotation(f1, f2, &matches);
  return matches;
}

int fuse(Map& map, const std::shared_ptr<KeyFrame>& kf,
         const std::vector<std::shared_ptr<MapPoint>>& points, double radius_px) {
  const FrameFeatures& f = *kf->features;
  const Intrinsics& in = *f.intrinsics;
  const Eigen::Vector3d center = kf->center();
  int fused = 0;
  for (const auto& p0 : points) {
    std::shared_ptr<MapPoint> p = MapPoint::resolve(p0);
    if (!p || p->bad || p->observedBy(kf->id)) continue;
    Projection pr;
    if (!projectMapPoint(*p, kf->T_camera_world, center, in, &pr)) continue;
    const double r = radius_px * in.pyramid.scale[pr.level];
    int best = std::numeric_limits<int>::max(), best_j = -1;
    for (int j : f.inArea(pr.px.x(), pr.px.y(), r)) {
      const int level = f.level(j);
      if (level < pr.level - 1 || level > pr.level) continue;
      if ((f.px[j] - pr.px).squaredNorm() * in.pyramid.inv_sigma2[level] > 5.99) continue;
      const int d = descriptorDistance(p->descriptor.data(), f.descriptor(j));
      if (d < best) {
        best = d;
        best_j = j;
      }
    }
    if (best_j < 0 || best > kMatchDistanceLow) continue;
    std::shared_ptr<MapPoint> existing = kf->points[best_j];
    if (existing && !existing->bad) {
      if (existing == p) continue;
      if (existing->numObservations() > p->numObservations())
        map.replacePoint(p, existing);
      else
        map.replacePoint(existing, p);
    } else {
      p->addObservation(kf, best_j);
      kf->points[best_j] = p;
      p->computeDistinctiveDescriptor();
      p->updateNormalAndDepth();
    }
    ++fused;
  }
  return fused;
}

}  // namespace slamaware::slam
