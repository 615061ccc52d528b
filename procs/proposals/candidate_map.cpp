#include "procs/proposals/candidate_map.h"

#include <pcl/filters/extract_indices.h>
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/conditional_euclidean_clustering.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <unordered_set>

namespace slamaware {

namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZRGB>;

Cloud::Ptr toCloud(const std::vector<MapPoint>& points) {
  Cloud::Ptr c(new Cloud);
  c->reserve(points.size());
  for (const auto& m : points) {
    if (!m.p.allFinite()) continue;
    pcl::PointXYZRGB q;
    q.x = m.p.x();
    q.y = m.p.y();
    q.z = m.p.z();
    q.r = m.r;
    q.g = m.g;
    q.b = m.b;
    c->push_back(q);
  }
  return c;
}

Cloud::Ptr downsample(const Cloud::Ptr& in, double leaf) {
  if (leaf <= 0 || in->empty()) return in;
  Cloud::Ptr out(new Cloud);
  pcl::VoxelGrid<pcl::PointXYZRGB> grid;
  grid.setInputCloud(in);
  grid.setLeafSize(static_cast<float>(leaf), static_cast<float>(leaf), static_cast<float>(leaf));
  grid.filter(*out);
  return out;
}

int64_t voxelKey(const Eigen::Vector3f& p, double voxel) {
  const auto q = [&](float v) { return static_cast<int64_t>(std::floor(v / voxel)) & 0x1FFFFF; };
  return (q(p.x()) << 42) | (q(p.y()) << 21) | q(p.z());
}

std::vector<int64_t> voxelSet(const std::vector<Eigen::Vector3f>& points, double voxel) {
  std::vector<int64_t> keys;
  keys.reserve(points.size());
  for (const auto& p : points) keys.push_back(voxelKey(p, voxel));
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  return keys;
}

double jaccard(const std::vector<int64_t>& a, const std::vector<int64_t>& b) {
  size_t i = 0, j = 0, common = 0;
  while (i < a.size() && j < b.size()) {
    if (a[i] == b[j]) {
      ++common;
      ++i;
      ++j;
    } else if (a[i] < b[j]) {
      ++i;
    } else {
      ++j;
    }
  }
  const size_t uni = a.size() + b.size() - common;
  return uni ? static_cast<double>(common) / static_cast<double>(uni) : 0.0;
}

void setBounds(Candidate* c) {
  c->min = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
  c->max = -c->min;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const auto& p : c->points) {
    c->min = c->min.cwiseMin(p);
    c->max = c->max.cwiseMax(p);
    sum += p.cast<double>();
  }
  c->centroid = (sum / std::max<size_t>(1, c->points.size())).cast<float>();
}

// Drops stray points: outside the per-axis [p, 100 - p] percentiles widened by margin x the
// largest of the three ranges (a flat map, all table, must not lose what stands on it).
Cloud::Ptr cropRobust(const Cloud::Ptr& in, double percentile, double margin) {
  if (in->size() < 10 || percentile <= 0) return in;
  Eigen::Vector3f lo, hi;
  for (int a = 0; a < 3; ++a) {
    std::vector<float> v;
    v.reserve(in->size());
    for (const auto& q : *in) v.push_back(q.getVector3fMap()[a]);
    const auto at = [&](double pct) {
      const size_t k = std::min(v.size() - 1, static_cast<size_t>(pct / 100.0 * static_cast<double>(v.size())));
      std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
      return v[k];
    };
    lo[a] = at(percentile);
    hi[a] = at(100 - percentile);
  }
  const float widen = static_cast<float>(margin) * (hi - lo).maxCoeff();
  lo.array() -= widen;
  hi.array() += widen;
  Cloud::Ptr out(new Cloud);
  for (const auto& q : *in) {
    const Eigen::Vector3f p = q.getVector3fMap();
    if ((p.array() >= lo.array()).all() && (p.array() <= hi.array()).all()) out->push_back(q);
  }
  return out;
}

// The largest plane of `in` by RANSAC: its inliers and coefficients (normal, offset).
bool findPlane(const Cloud::Ptr& in, const ProposalOptions& o, pcl::PointIndices* inliers, Eigen::Vector4f* plane) {
  if (in->size() < 3) return false;
  pcl::SACSegmentation<pcl::PointXYZRGB> seg;
  seg.setOptimizeCoefficients(true);
  seg.setModelType(pcl::SACMODEL_PLANE);
  seg.setMethodType(pcl::SAC_RANSAC);
  seg.setDistanceThreshold(o.plane_distance);
  seg.setMaxIterations(o.plane_iterations);
  seg.setInputCloud(in);
  pcl::ModelCoefficients c;
  seg.segment(*inliers, c);
  if (inliers->indices.empty() || c.values.size() != 4) return false;
  *plane = Eigen::Vector4f(c.values[0], c.values[1], c.values[2], c.values[3]);
  return true;
}

Cloud::Ptr extract(const Cloud::Ptr& in, const pcl::PointIndices::Ptr& indices, bool negative) {
  Cloud::Ptr out(new Cloud);
  pcl::ExtractIndices<pcl::PointXYZRGB> ex;
  ex.setInputCloud(in);
  ex.setIndices(indices);
  ex.setNegative(negative);
  ex.filter(*out);
  return out;
}

// The map without stray points, outliers and its planes; when a support plane is found, only
// what stands on it: on the viewpoint's side, less than
// max_extent above it, and over the plane's own points (within support_margin).
std::vector<MapPoint> filterMap(const std::vector<MapPoint>& all, const ProposalOptions& o,
                                const Eigen::Vector3f& viewpoint, ClusterStats* st, Eigen::Vector4f* support_out) {
  Cloud::Ptr cloud = toCloud(all);
  const size_t before = cloud->size();
  cloud = cropRobust(cloud, o.crop_percentile, o.crop_margin);
  st->cropped = static_cast<int64_t>(before - cloud->size());
  // Bounded cost: downsample until the map fits max_points.
  double voxel = o.voxel;
  Cloud::Ptr small = downsample(cloud, voxel);
  for (int i = 0; i < 20 && static_cast<int>(small->size()) > o.max_points; ++i) {
    voxel *= 1.26;
    small = downsample(cloud, voxel);
  }
  st->voxel = voxel;
  Cloud::Ptr rest(new Cloud);
  if (small->size() > static_cast<size_t>(o.outlier_neighbours)) {
    pcl::StatisticalOutlierRemoval<pcl::PointXYZRGB> sor;
    sor.setInputCloud(small);
    sor.setMeanK(o.outlier_neighbours);
    sor.setStddevMulThresh(o.outlier_std);
    sor.filter(*rest);
  } else {
    *rest = *small;
  }
  st->outliers = static_cast<int64_t>(small->size() - rest->size());
  const double total = static_cast<double>(rest->size());
  // Planes, largest first; the largest is the support (the table fills most of a tabletop view).
  Cloud::Ptr support;
  Eigen::Vector4f support_plane = Eigen::Vector4f::Zero();
  for (int k = 0; k < o.max_planes; ++k) {
    pcl::PointIndices::Ptr in(new pcl::PointIndices);
    Eigen::Vector4f plane;
    if (!findPlane(rest, o, in.get(), &plane) ||
        static_cast<double>(in->indices.size()) < o.plane_min_fraction * total)
      break;
    plane /= plane.head<3>().norm();
    if (plane.head<3>().dot(viewpoint) + plane[3] < 0) plane = -plane;  // normal towards the camera
    if (k == 0) {
      support = extract(rest, in, false);
      support_plane = plane;
    }
    st->plane_points += static_cast<int64_t>(in->indices.size());
    ++st->planes;
    rest = extract(rest, in, true);
  }
  std::vector<MapPoint> out;
  out.reserve(rest->size());
  if (support && !support->empty()) {
    st->support = true;
    *support_out = support_plane;
    pcl::KdTreeFLANN<pcl::PointXYZRGB> tree;
    tree.setInputCloud(support);
    std::vector<int> idx(1);
    std::vector<float> d2(1);
    const Eigen::Vector3f n = support_plane.head<3>().normalized();
    const float r2 = static_cast<float>(o.support_margin * o.support_margin);
    for (const auto& q : *rest) {
      const Eigen::Vector3f p = q.getVector3fMap();
      const float h = support_plane.head<3>().dot(p) + support_plane[3];
      if (h <= 0 || h > o.max_extent) continue;
      pcl::PointXYZRGB foot = q;
      foot.getVector3fMap() = p - h * n;
      if (tree.nearestKSearch(foot, 1, idx, d2) < 1 || d2[0] > r2) continue;
      out.push_back({p, q.r, q.g, q.b});
    }
  } else {
    for (const auto& q : *rest) out.push_back({q.getVector3fMap(), q.r, q.g, q.b});
  }
  return out;
}

// With a support plane (unit normal towards the camera): clusters lower than min_height are
// texture of the plane itself; the others stand on it, so their footprint (their points dropped
// onto the plane) belongs to them; it covers the bottom that plane removal took away.
void standOnSupport(std::vector<Candidate>* candidates, const Eigen::Vector4f& plane, const ProposalOptions& o) {
  std::vector<Candidate> kept;
  const Eigen::Vector3f n = plane.head<3>();
  for (auto& c : *candidates) {
    // Height of the cluster: its 80th percentile over the plane (noise does not make it tall).
    std::vector<float> h;
    h.reserve(c.points.size());
    for (const auto& p : c.points) h.push_back(n.dot(p) + plane[3]);
    const size_t k = h.size() * 4 / 5;
    std::nth_element(h.begin(), h.begin() + static_cast<long>(k), h.end());
    if (h.empty() || h[k] < o.min_height) continue;
    if (o.add_footprint) {
      const size_t count = c.points.size();
      for (size_t i = 0; i < count; ++i) c.points.push_back(c.points[i] - (n.dot(c.points[i]) + plane[3]) * n);
      setBounds(&c);
    }
    kept.push_back(std::move(c));
  }
  *candidates = std::move(kept);
}

}  // namespace

ProposalOptions scaledLengths(const ProposalOptions& options, double scale) {
  ProposalOptions o = options;
  for (double* v : {&o.voxel, &o.max_depth_std, &o.plane_distance, &o.support_margin, &o.min_height, &o.radius,
                    &o.max_extent, &o.min_extent})
    *v *= scale;
  return o;
}

std::vector<Candidate> clusterPoints(const std::vector<MapPoint>& points, const ProposalOptions& o) {
  const Cloud::Ptr all = toCloud(points);
  std::vector<Candidate> out;
  std::vector<std::vector<int64_t>> keys;  // per kept cluster, at the finest clustering voxel
  const double key_voxel = 2 * o.radius;
  const float colour2 = static_cast<float>(o.colour_distance * o.colour_distance);
  for (int s = 0; s < o.scales; ++s) {
    const double r = o.radius * std::pow(2.0, s);
    // Each scale clusters a grid of half its radius: a bounded number of neighbours per point.
    const Cloud::Ptr cloud = s == 0 ? all : downsample(all, r / 2);
    if (cloud->empty()) break;
    pcl::ConditionalEuclideanClustering<pcl::PointXYZRGB> cec;
    cec.setInputCloud(cloud);
    cec.setClusterTolerance(static_cast<float>(r));
    const bool use_colour = o.colour_distance > 0;
    cec.setConditionFunction([use_colour, colour2](const pcl::PointXYZRGB& a, const pcl::PointXYZRGB& b, float) {
      if (!use_colour) return true;
      const float dr = static_cast<float>(a.r) - b.r, dg = static_cast<float>(a.g) - b.g,
                  db = static_cast<float>(a.b) - b.b;
      return dr * dr + dg * dg + db * db < colour2;
    });
    const int min_points = std::max(5, static_cast<int>(o.min_points / std::pow(4.0, s)));
    cec.setMinClusterSize(min_points);
    cec.setMaxClusterSize(std::numeric_limits<int>::max());
    pcl::IndicesClusters clusters;
    cec.segment(clusters);
    for (const auto& idx : clusters) {
      Candidate c;
      c.scale = s;
      c.points.reserve(idx.indices.size());
      for (int i : idx.indices) {
        const auto& q = (*cloud)[static_cast<size_t>(i)];
        c.points.emplace_back(q.x, q.y, q.z);
      }
      setBounds(&c);
      const Eigen::Vector3f extent = c.max - c.min;
      if (extent.maxCoeff() > o.max_extent || extent.maxCoeff() < o.min_extent) continue;
      // The same cluster found again at a coarser scale is one candidate.
      std::vector<int64_t> k = voxelSet(c.points, key_voxel);
      bool duplicate = false;
      for (size_t i = 0; i < keys.size(); ++i)
        if (jaccard(k, keys[i]) >= o.same_cluster_overlap) {
          ++out[i].stability;  // found again: an isolated object rather than a fragment
          duplicate = true;
          break;
        }
      if (duplicate) continue;
      keys.push_back(std::move(k));
      out.push_back(std::move(c));
    }
  }
  // A deterministic order: by scale, then by position.
  std::stable_sort(out.begin(), out.end(), [](const Candidate& a, const Candidate& b) {
    if (a.scale != b.scale) return a.scale < b.scale;
    for (int i = 0; i < 3; ++i)
      if (a.min[i] != b.min[i]) return a.min[i] < b.min[i];
    return a.points.size() < b.points.size();
  });
  return out;
}

void CandidateMap::update(int32_t map_id, bool full, int32_t keyframe_id, const std::vector<int32_t>& keyframe_ids,
                          const std::vector<MapPoint>& points) {
  if (map_id != map_id_) {
    map_id_ = map_id;
    by_keyframe_.clear();
    candidates_.clear();
  }
  if (full) {
    by_keyframe_.clear();
    for (size_t i = 0; i < points.size(); ++i)
      if (points[i].p.allFinite()) by_keyframe_[i < keyframe_ids.size() ? keyframe_ids[i] : -1].push_back(points[i]);
  } else {
    auto& kf = by_keyframe_[keyframe_id];
    kf.clear();
    for (const auto& p : points)
      if (p.p.allFinite()) kf.push_back(p);
  }
  dirty_ = true;
}

size_t CandidateMap::points() const {
  size_t n = 0;
  for (const auto& [kf, p] : by_keyframe_) n += p.size();
  return n;
}

bool CandidateMap::recluster(const Eigen::Vector3f& viewpoint) {
  if (!dirty_) return false;
  dirty_ = false;
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<MapPoint> all;
  all.reserve(points());
  for (const auto& [kf, p] : by_keyframe_) all.insert(all.end(), p.begin(), p.end());
  stats_ = ClusterStats{};
  stats_.input_points = static_cast<int64_t>(all.size());
  std::vector<Candidate> found;
  ProposalOptions o = options_;
  if (all.size() >= static_cast<size_t>(std::max(3, options_.min_points))) {
    // Lengths are fractions of the viewing distance: monocular maps have no metric scale.
    std::vector<float> range;
    range.reserve(all.size());
    for (const auto& m : all) range.push_back((m.p - viewpoint).norm());
    std::nth_element(range.begin(), range.begin() + static_cast<long>(range.size() / 2), range.end());
    stats_.scene_scale = options_.relative_lengths && range[range.size() / 2] > 0 ? range[range.size() / 2] : 1.0;
    o = scaledLengths(options_, stats_.scene_scale);
    Eigen::Vector4f plane = Eigen::Vector4f::Zero();
    const std::vector<MapPoint> objects = filterMap(all, o, viewpoint, &stats_, &plane);
    stats_.clustered_points = static_cast<int64_t>(objects.size());
    found = clusterPoints(objects, o);
    if (stats_.support) standOnSupport(&found, plane, o);
  }
  // Stable ids: each new cluster takes the id of the old candidate it shares most voxels with
  // (one to one, greedily by overlap), if they share at least id_overlap.
  const double key_voxel = 2 * o.radius;
  std::vector<std::vector<int64_t>> old_keys, new_keys;
  for (const auto& c : candidates_) old_keys.push_back(voxelSet(c.points, key_voxel));
  for (const auto& c : found) new_keys.push_back(voxelSet(c.points, key_voxel));
  struct Pair {
    double overlap;
    size_t n, o;
  };
  std::vector<Pair> pairs;
  for (size_t n = 0; n < found.size(); ++n)
    for (size_t o = 0; o < candidates_.size(); ++o) {
      const Eigen::Vector3f lo = found[n].min.cwiseMax(candidates_[o].min);
      const Eigen::Vector3f hi = found[n].max.cwiseMin(candidates_[o].max);
      if ((hi.array() < lo.array()).any()) continue;  // bounds apart: nothing shared
      const double j = jaccard(new_keys[n], old_keys[o]);
      if (j >= options_.id_overlap) pairs.push_back({j, n, o});
    }
  std::stable_sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.overlap > b.overlap; });
  std::vector<bool> new_done(found.size()), old_done(candidates_.size());
  for (const auto& p : pairs) {
    if (new_done[p.n] || old_done[p.o]) continue;
    new_done[p.n] = old_done[p.o] = true;
    found[p.n].id = candidates_[p.o].id;
  }
  for (auto& c : found)
    if (c.id < 0) c.id = next_id_++;
  candidates_ = std::move(found);
  stats_.clusters = static_cast<int>(candidates_.size());
  stats_.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return true;
}

}  // namespace slamaware
