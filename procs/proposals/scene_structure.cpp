#include "procs/proposals/scene_structure.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/imgproc.hpp>
#include <random>
#include <set>

namespace slamaware::proposals {

namespace {

// The plane through the most of `sample` (within `distance`) by RANSAC: `iterations` random
// triples, each scored on at most 4000 evenly spread points of the sample. Seeded: the same
// points give the same plane. False if every triple was degenerate.
bool ransacPlane(const std::vector<Eigen::Vector3f>& sample, double distance, int iterations,
                 Eigen::Vector4f* plane) {
  if (sample.size() < 3) return false;
  const size_t stride = std::max<size_t>(1, sample.size() / 4000);
  std::mt19937 rng(12345);
  const float dist = static_cast<float>(distance);
  size_t best = 0;
  for (int it = 0; it < iterations; ++it) {
    const Eigen::Vector3f& a = sample[rng() % sample.size()];
    const Eigen::Vector3f& b = sample[rng() % sample.size()];
    const Eigen::Vector3f& c = sample[rng() % sample.size()];
    Eigen::Vector3f n = (b - a).cross(c - a);
    const float len = n.norm();
    if (!(len > 1e-12f)) continue;
    n /= len;
    const float d = -n.dot(a);
    size_t count = 0;
    for (size_t i = 0; i < sample.size(); i += stride)
      count += std::abs(n.dot(sample[i]) + d) <= dist;
    if (count > best) {
      best = count;
      *plane = Eigen::Vector4f(n.x(), n.y(), n.z(), d);
    }
  }
  return best > 0;
}

// Any two unit vectors spanning the plane with normal n.
void planeAxes(const Eigen::Vector3f& n, Eigen::Vector3f* u, Eigen::Vector3f* v) {
  const Eigen::Vector3f a =
      std::abs(n.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY();
  *u = n.cross(a).normalized();
  *v = n.cross(*u);
}

using CellKey = std::pair<int, int>;

CellKey cellOf(const Eigen::Vector2f& uv, float cell) {
  return {static_cast<int>(std::floor(uv.x() / cell)), static_cast<int>(std::floor(uv.y() / cell))};
}

// The convex hull of 2D points, counter-clockwise.
std::vector<Eigen::Vector2f> convexHull(const std::vector<Eigen::Vector2f>& pts) {
  std::vector<cv::Point2f> in, hull;
  in.reserve(pts.size());
  for (const auto& p : pts) in.emplace_back(p.x(), p.y());
  if (in.size() < 3) return {};
  cv::convexHull(in, hull);
  std::vector<Eigen::Vector2f> out;
  for (const auto& h : hull) out.emplace_back(h.x, h.y);
  double area = 0;  // OpenCV's orientation flag assumes y down: fix the winding here
  for (size_t j = 0; j < out.size(); ++j) {
    const auto& u = out[j];
    const auto& v = out[(j + 1) % out.size()];
    area += static_cast<double>(u.x()) * v.y() - static_cast<double>(v.x()) * u.y();
  }
  if (area < 0) std::reverse(out.begin(), out.end());
  return out;
}

// Signed distance of q from the convex counter-clockwise polygon (negative inside).
float hullDistance(const std::vector<Eigen::Vector2f>& hull, const Eigen::Vector2f& q) {
  if (hull.size() < 3) return std::numeric_limits<float>::infinity();
  float outside = -std::numeric_limits<float>::infinity();
  for (size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2f a = hull[i], b = hull[(i + 1) % hull.size()];
    const Eigen::Vector2f e = (b - a).normalized();
    const Eigen::Vector2f outward(e.y(), -e.x());
    outside = std::max(outside, outward.dot(q - a));
  }
  return outside;
}

// A connected patch of a plane's points larger than an object (a table top, a floor, a wall).
struct Patch {
  std::vector<int> points;            // into the points given to removeStructure
  std::set<CellKey> cells;            // its dense cells
  std::vector<Eigen::Vector2f> hull;  // plane coordinates
};

struct FoundPlane {
  Plane plane;
  Eigen::Vector3f origin, u, v;               // plane coordinates
  std::vector<Patch> patches;                 // the structure of this plane
  std::map<CellKey, std::vector<int>> dense;  // every dense cell of its inliers, with its points

  Eigen::Vector2f toPlane(const Eigen::Vector3f& p) const {
    const Eigen::Vector3f q = p - origin;
    return {q.dot(u), q.dot(v)};
  }
  // The patch whose hull holds the foot of p (within margin), -1 if none.
  int patchAt(const Eigen::Vector3f& p, float margin) const {
    const Eigen::Vector2f q = toPlane(p);
    for (size_t k = 0; k < patches.size(); ++k)
      if (hullDistance(patches[k].hull, q) <= margin) return static_cast<int>(k);
    return -1;
  }
  // True if at least `fill` of the cells within 2 cells of the foot of p are dense cells of the
  // patch: the plane is really there, not only an infinite plane through scattered points.
  bool solidAt(int patch, const Eigen::Vector3f& p, float cell, float fill) const {
    const CellKey c = cellOf(toPlane(p), cell);
    int n = 0;
    for (int dx = -2; dx <= 2; ++dx)
      for (int dy = -2; dy <= 2; ++dy)
        n += patches[static_cast<size_t>(patch)].cells.count({c.first + dx, c.second + dy}) > 0;
    return n >= fill * 25;
  }
  // The dense cells within `radius` of the foot of `centre`.
  std::vector<CellKey> cellsNear(const Eigen::Vector3f& centre, float radius, float cell) const {
    const Eigen::Vector2f c = toPlane(centre);
    std::vector<CellKey> out;
    for (const auto& [key, pts] : dense)
      if ((Eigen::Vector2f((key.first + 0.5f) * cell, (key.second + 0.5f) * cell) - c).norm() <=
          radius)
        out.push_back(key);
    return out;
  }
  size_t pointsIn(const std::vector<CellKey>& cells) const {
    size_t n = 0;
    for (const auto& k : cells) n += dense.at(k).size();
    return n;
  }
  // The support made of `cells`: the plane and the convex hull of the cells.
  Support support(const std::vector<CellKey>& cells, float cell) const {
    Support s;
    s.plane = plane;
    s.origin = origin;
    s.axis_u = u;
    s.axis_v = v;
    std::vector<Eigen::Vector2f> corners;
    for (const auto& c : cells)
      for (int dx = 0; dx <= 1; ++dx)
        for (int dy = 0; dy <= 1; ++dy)
          corners.emplace_back((c.first + dx) * cell, (c.second + dy) * cell);
    s.hull = convexHull(corners);
    return s;
  }
};

// The structure patches of a plane's inliers (positions in `points`): 8-connected dense cells
// (at least min_points points each) whose extent is over `extent`. Points in sparse cells or in
// smaller patches (an object's face, a few stray points on the infinite plane) are not structure.
std::vector<Patch> structurePatches(FoundPlane* f, const std::vector<MapPoint>& points,
                                    const std::vector<int>& inliers, float cell, int min_points,
                                    float extent) {
  std::map<CellKey, std::vector<int>> cells;  // ordered: deterministic
  for (int i : inliers)
    cells[cellOf(f->toPlane(points[static_cast<size_t>(i)].p), cell)].push_back(i);
  std::map<CellKey, int> patch_of;
  for (const auto& [key, pts] : cells)
    if (static_cast<int>(pts.size()) >= min_points) {
      patch_of.emplace(key, -1);
      f->dense.emplace(key, pts);
    }
  std::vector<Patch> out;
  int n = 0;
  for (auto& [key, patch] : patch_of) {
    if (patch >= 0) continue;
    patch = n;
    std::vector<CellKey> members{key}, stack{key};
    while (!stack.empty()) {
      const CellKey c = stack.back();
      stack.pop_back();
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy) {
          auto it = patch_of.find({c.first + dx, c.second + dy});
          if (it == patch_of.end() || it->second >= 0) continue;
          it->second = n;
          stack.push_back(it->first);
          members.push_back(it->first);
        }
    }
    ++n;
    Eigen::Vector2i lo(members[0].first, members[0].second), hi = lo;
    for (const auto& c : members) {
      lo = lo.cwiseMin(Eigen::Vector2i(c.first, c.second));
      hi = hi.cwiseMax(Eigen::Vector2i(c.first, c.second));
    }
    if (static_cast<float>((hi - lo).maxCoeff() + 1) * cell <= extent) continue;
    Patch p;
    std::vector<Eigen::Vector2f> corners;
    for (const auto& c : members) {
      p.cells.insert(c);
      const auto& pts = cells[c];
      p.points.insert(p.points.end(), pts.begin(), pts.end());
      for (int dx = 0; dx <= 1; ++dx)
        for (int dy = 0; dy <= 1; ++dy)
          corners.emplace_back((c.first + dx) * cell, (c.second + dy) * cell);
    }
    p.hull = convexHull(corners);
    out.push_back(std::move(p));
  }
  return out;
}

}  // namespace

bool Support::over(const Eigen::Vector3f& p, float margin) const {
  const Eigen::Vector3f q = p - origin;
  return hullDistance(hull, Eigen::Vector2f(q.dot(axis_u), q.dot(axis_v))) <= margin;
}

ViewPriors viewPriors(const std::vector<View>& views) {
  ViewPriors v;
  if (views.empty()) return v;
  Eigen::Vector3d up = Eigen::Vector3d::Zero(), centre = Eigen::Vector3d::Zero(),
                  b = Eigen::Vector3d::Zero();
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero(), X = Eigen::Matrix3d::Zero();
  for (const auto& w : views) {
    up += w.up.cast<double>();
    X += w.right.cast<double>() * w.right.cast<double>().transpose();
    centre += w.centre.cast<double>();
    const Eigen::Vector3d f = w.forward.cast<double>().normalized();
    const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - f * f.transpose();  // off-axis part
    A += P;
    b += P * w.centre.cast<double>();
  }
  const double n = static_cast<double>(views.size());
  v.valid = true;
  v.mean_centre = (centre / n).cast<float>();
  // Up is perpendicular to every view's x axis: the eigenvector of their scatter with the
  // smallest eigenvalue, known when the x axes are spread (the middle eigenvalue is the mean
  // squared sine of their spread about up: 0.02 is about 8 degrees).
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> xs(X / n);
  if (xs.eigenvalues()[1] > 0.02) {
    Eigen::Vector3d u = xs.eigenvectors().col(0);
    if (u.dot(up) < 0) u = -u;
    v.up_known = true;
    v.up = u.cast<float>();
  }
  // The axes meet only if they are not (nearly) parallel: the smallest eigenvalue of the mean
  // projector is the mean squared sine of the axes' angle to its eigenvector.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(A / n);
  if (es.eigenvalues()[0] > 0.01) {
    const Eigen::Vector3d x = A.ldlt().solve(b);
    int in_front = 0;
    for (const auto& w : views)
      if (w.forward.cast<double>().dot(x - w.centre.cast<double>()) > 0) ++in_front;
    if (x.allFinite() && in_front >= 0.8 * n) {
      v.has_look_at = true;
      v.look_at = x.cast<float>();
    }
  }
  return v;
}

namespace {

// Up to o.max_planes planes, each searched among the points not on the planes before it.
std::vector<FoundPlane> findPlanes(const std::vector<MapPoint>& points, const ViewPriors& priors,
                                   const ProposalOptions& o) {
  const size_t total = points.size();
  const float cell = static_cast<float>(o.structure_cell);
  std::vector<int> rest(total);
  for (size_t i = 0; i < total; ++i) rest[i] = static_cast<int>(i);
  std::vector<FoundPlane> found;
  for (int k = 0; k < o.max_planes && rest.size() >= 3; ++k) {
    // RANSAC on an even subsample (a plane holding >= plane_min_fraction of the points is as
    // well found from 20k of them), then the inliers among all points and a least-squares refit.
    const size_t stride =
        std::max<size_t>(1, rest.size() / static_cast<size_t>(std::max(1000, o.ransac_points)));
    std::vector<Eigen::Vector3f> sample;
    sample.reserve(rest.size() / stride + 1);
    for (size_t j = 0; j < rest.size(); j += stride)
      sample.push_back(points[static_cast<size_t>(rest[j])].p);
    Eigen::Vector4f coef;
    if (!ransacPlane(sample, o.plane_distance, o.plane_iterations, &coef)) break;
    std::vector<int> in, out;               // points of rest on and off the plane
    for (int pass = 0; pass < 2; ++pass) {  // inliers, refit, inliers again
      in.clear();
      out.clear();
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      Eigen::Matrix3d sq = Eigen::Matrix3d::Zero();
      for (int i : rest) {
        const Eigen::Vector3f& q = points[static_cast<size_t>(i)].p;
        if (std::abs(coef.head<3>().dot(q) + coef[3]) > o.plane_distance) {
          out.push_back(i);
          continue;
        }
        in.push_back(i);
        const Eigen::Vector3d qd = q.cast<double>();
        sum += qd;
        sq += qd * qd.transpose();
      }
      if (pass == 1 || in.size() < 3) break;
      const Eigen::Vector3d mean = sum / static_cast<double>(in.size());
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(sq / static_cast<double>(in.size()) -
                                                        mean * mean.transpose());
      const Eigen::Vector3f n = es.eigenvectors().col(0).cast<float>().normalized();
      coef = Eigen::Vector4f(n.x(), n.y(), n.z(), -n.dot(mean.cast<float>()));
    }
    if (static_cast<double>(in.size()) < o.plane_min_fraction * static_cast<double>(total)) break;
    FoundPlane f;
    const Eigen::Vector3f towards = priors.valid ? priors.mean_centre : Eigen::Vector3f::Zero();
    if (coef.head<3>().dot(towards) + coef[3] < 0) coef = -coef;  // normal towards the cameras
    f.plane.n = coef.head<3>();
    f.plane.d = coef[3];
    f.origin = -f.plane.d * f.plane.n;
    planeAxes(f.plane.n, &f.u, &f.v);
    f.patches = structurePatches(&f, points, in, cell, o.structure_min_points,
                                 static_cast<float>(o.structure_extent));
    // The next plane is searched among the points that are not on this one; the points of this
    // plane that are not structure are kept (they go back to the output). A plane without
    // structure is kept too: it may be the support (a small table top), never removed.
    rest.swap(out);
    found.push_back(std::move(f));
  }
  return found;
}

// A support candidate: a plane of `found` (-1: none) and its dense cells that make the region.
struct SupportChoice {
  int plane = -1;
  std::vector<CellKey> region;
};

// Without views (the algorithm alone, in tests): the largest patch of the largest plane.
SupportChoice largestPatch(const std::vector<FoundPlane>& found) {
  SupportChoice c;
  size_t most = 0;
  for (size_t k = 0; k < found.size(); ++k)
    for (const auto& patch : found[k].patches)
      if (patch.points.size() > most) {
        most = patch.points.size();
        c.plane = static_cast<int>(k);
        c.region.assign(patch.cells.begin(), patch.cells.end());
      }
  return c;
}

// Of the level planes with points near the look-at point, from support_below over it to
// max_height under it: the level nearest to it, then of the planes at that level (within
// support_below of it: a plane fitted through the same table top at a tilt) the one with most
// points there. What the views aim at stands on it; the plane with most points there is not it
// (the floor around a small table seen from afar holds more than the table top).
template <class Level>
SupportChoice underLookAt(const std::vector<FoundPlane>& found, const ViewPriors& priors,
                          const ProposalOptions& o, const Level& level) {
  const float cell = static_cast<float>(o.structure_cell);
  struct Candidate {
    float h;  // |height| of the look-at point over the plane
    size_t plane;
    std::vector<CellKey> cells;  // its dense cells near the look-at point
  };
  std::vector<Candidate> levels;
  float nearest = std::numeric_limits<float>::infinity();
  for (size_t k = 0; k < found.size(); ++k) {
    const float h = found[k].plane.distance(priors.look_at);
    if (!level(found[k]) || h < -o.support_below || h > o.max_height) continue;
    std::vector<CellKey> cells =
        found[k].cellsNear(priors.look_at, static_cast<float>(o.support_radius), cell);
    if (cells.empty()) continue;
    nearest = std::min(nearest, std::abs(h));
    levels.push_back({std::abs(h), k, std::move(cells)});
  }
  SupportChoice c;
  size_t most = 0;
  for (auto& [h, k, cells] : levels) {
    if (h > nearest + o.support_below) continue;
    const size_t n = found[k].pointsIn(cells);
    if (n > most) {
      most = n;
      c.plane = static_cast<int>(k);
      c.region = std::move(cells);
    }
  }
  return c;
}

// The level plane the optical axes hit first, where it has points, most often; its region around
// the mean of those hits.
template <class Level>
SupportChoice whereViewsAim(const std::vector<FoundPlane>& found, const std::vector<View>& views,
                            const ProposalOptions& o, const Level& level) {
  const float cell = static_cast<float>(o.structure_cell);
  std::vector<int> votes(found.size(), 0);
  std::vector<Eigen::Vector3f> aim(found.size(), Eigen::Vector3f::Zero());
  for (const View& w : views) {
    int hit = -1;
    float nearest = std::numeric_limits<float>::infinity();
    for (size_t k = 0; k < found.size(); ++k) {
      const Plane& pl = found[k].plane;
      const float along = pl.n.dot(w.forward);
      if (!level(found[k]) || along >= 0) continue;  // looking away from its upper side
      const float t = -pl.distance(w.centre) / along;
      if (!(t > 0) || t >= nearest) continue;
      const Eigen::Vector3f at = w.centre + t * w.forward;
      const int p = found[k].patchAt(at, 0.0f);
      if (p < 0 || !found[k].solidAt(p, at, cell, static_cast<float>(o.support_fill))) continue;
      nearest = t;
      hit = static_cast<int>(k);
    }
    if (hit < 0) continue;
    ++votes[static_cast<size_t>(hit)];
    aim[static_cast<size_t>(hit)] += w.centre + nearest * w.forward;
  }
  SupportChoice c;
  for (size_t k = 0; k < found.size(); ++k)
    if (votes[k] > 0 && (c.plane < 0 || votes[k] > votes[static_cast<size_t>(c.plane)]))
      c.plane = static_cast<int>(k);
  if (c.plane >= 0) {
    const size_t b = static_cast<size_t>(c.plane);
    c.region = found[b].cellsNear(aim[b] / static_cast<float>(votes[b]),
                                  static_cast<float>(o.support_radius), cell);
  }
  return c;
}

// The support: a level plane and its region (its dense cells within support_radius of where the
// views look): under the look-at point when there is one, else where the optical axes hit.
SupportChoice chooseSupport(const std::vector<FoundPlane>& found, const std::vector<View>& views,
                            const ViewPriors& priors, const ProposalOptions& o) {
  if (!priors.valid) return largestPatch(found);
  // Level: within support_max_tilt_deg of up. Without up that cannot be told, and only a plane
  // with structure (larger than any object) can be a support: a smaller one may be a face of the
  // object itself (the Middlebury temple, whose views never turn about up). With up, a plane
  // without structure is a small table top (a round table seen from a metre away).
  const float cos_tilt = static_cast<float>(std::cos(o.support_max_tilt_deg * M_PI / 180.0));
  auto level = [&](const FoundPlane& f) {
    return priors.up_known ? f.plane.n.dot(priors.up) >= cos_tilt : !f.patches.empty();
  };
  if (priors.has_look_at) {
    SupportChoice c = underLookAt(found, priors, o, level);
    if (c.plane >= 0) return c;
  }
  return whereViewsAim(found, views, o, level);
}

}  // namespace

StructureResult removeStructure(const std::vector<MapPoint>& points, const std::vector<View>& views,
                                const ViewPriors& priors, const ProposalOptions& o) {
  StructureResult r;
  const std::vector<FoundPlane> found = findPlanes(points, priors, o);
  r.stats.planes = static_cast<int>(found.size());
  const SupportChoice choice = chooseSupport(found, views, priors, o);
  const float cell = static_cast<float>(o.structure_cell);
  if (choice.plane >= 0 && !choice.region.empty()) {
    r.support = found[static_cast<size_t>(choice.plane)].support(choice.region, cell);
    r.has_support = r.support.hull.size() >= 3;
  }
  const int best = r.has_support ? choice.plane : -1;
  r.stats.support = r.has_support;
  // What is removed: the support plane's dense cells in the region (points within
  // support_distance of it), and the structure of the planes that are not parallel to it (walls;
  // planes parallel to it are other tables, the floor, or slices through the objects standing on
  // it, which the objects must keep). Without a support, every structure patch.
  const size_t total = points.size();
  std::vector<bool> structure(total, false);
  auto mark = [&](int i) {
    if (!structure[static_cast<size_t>(i)]) ++r.stats.structure_points;
    structure[static_cast<size_t>(i)] = true;
  };
  // The support's band is thinner than RANSAC's inlier distance: flat objects (a towel, a tube
  // lying down) are not much thicker than the depth noise of the table.
  if (best >= 0)
    for (const auto& key : choice.region)
      for (int i : found[static_cast<size_t>(best)].dense.at(key))
        if (std::abs(r.support.plane.distance(points[static_cast<size_t>(i)].p)) <=
            o.support_distance) {
          mark(i);
          r.band.push_back(points[static_cast<size_t>(i)]);
        }
  for (size_t k = 0; k < found.size(); ++k) {
    const bool remove = best < 0 || std::abs(found[k].plane.n.dot(r.support.plane.n)) < 0.5f;
    if (!remove || found[k].patches.empty()) continue;
    ++r.stats.structure_planes;
    for (const auto& patch : found[k].patches)
      for (int i : patch.points) mark(i);
  }
  r.kept.reserve(total);
  for (size_t i = 0; i < total; ++i)
    if (!structure[i]) r.kept.push_back(points[i]);
  return r;
}

}  // namespace slamaware::proposals
