#include "procs/proposals/candidate_map.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include "procs/proposals/density_clustering.h"
#include "procs/proposals/free_space.h"

namespace slamaware::proposals {

namespace {

int64_t voxelKey(const Eigen::Vector3f& p, double voxel) {
  const auto q = [&](float v) { return static_cast<int64_t>(std::floor(v / voxel)) & 0x1FFFFF; };
  return (q(p.x()) << 42) | (q(p.y()) << 21) | q(p.z());
}

// The voxel of a point, and the key of a voxel given by its indices (a neighbour's).
Eigen::Vector3i voxelOf(const Eigen::Vector3f& p, double voxel) {
  return (p / static_cast<float>(voxel)).array().floor().cast<int>();
}
int64_t voxelKeyAt(const Eigen::Vector3i& v, double voxel) {
  return voxelKey(Eigen::Vector3f((v.cast<float>() + Eigen::Vector3f::Constant(0.5f)) *
                                  static_cast<float>(voxel)),
                  voxel);
}

// One point per occupied voxel: the centroid and mean colour of its points, in voxel-key order.
std::vector<MapPoint> downsample(const std::vector<MapPoint>& in, double voxel) {
  if (!(voxel > 0) || in.empty()) return in;
  std::vector<std::pair<int64_t, uint32_t>> keyed(in.size());
  for (size_t i = 0; i < in.size(); ++i)
    keyed[i] = {voxelKey(in[i].p, voxel), static_cast<uint32_t>(i)};
  std::sort(keyed.begin(), keyed.end());
  std::vector<MapPoint> out;
  for (size_t i = 0; i < keyed.size();) {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    size_t j = i;
    for (; j < keyed.size() && keyed[j].first == keyed[i].first; ++j) {
      const MapPoint& m = in[keyed[j].second];
      p += m.p.cast<double>();
      c += Eigen::Vector3d(m.r, m.g, m.b);
    }
    const double k = static_cast<double>(j - i);
    const Eigen::Vector3d mc = c / k;
    out.push_back({(p / k).cast<float>(), static_cast<uint8_t>(std::lround(mc.x())),
                   static_cast<uint8_t>(std::lround(mc.y())),
                   static_cast<uint8_t>(std::lround(mc.z()))});
    i = j;
  }
  return out;
}

std::vector<int64_t> voxelSet(const std::vector<Eigen::Vector3f>& points, double voxel) {
  std::vector<int64_t> keys;
  keys.reserve(points.size());
  for (const auto& p : points) keys.push_back(voxelKey(p, voxel));
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  return keys;
}

/// A new cluster n and an old candidate o, and the share of key voxels they have in common.
struct Pair {
  double overlap;
  size_t n, o;
};

/// Keeps of `pairs` those a one-to-one matching takes, greedily by overlap, and marks both sides.
void matchGreedily(std::vector<Pair>* pairs, std::vector<bool>* new_done,
                   std::vector<bool>* old_done) {
  std::stable_sort(pairs->begin(), pairs->end(),
                   [](const Pair& a, const Pair& b) { return a.overlap > b.overlap; });
  std::vector<Pair> kept;
  for (const auto& p : *pairs) {
    if ((*new_done)[p.n] || (*old_done)[p.o]) continue;
    (*new_done)[p.n] = (*old_done)[p.o] = true;
    kept.push_back(p);
  }
  *pairs = std::move(kept);
}

/// False when the bounds of `c` and [min, max] are apart (then they share no voxel).
bool boundsMeet(const Candidate& c, const Eigen::Vector3f& min, const Eigen::Vector3f& max) {
  return !(c.min.cwiseMax(min).array() > c.max.cwiseMin(max).array()).any();
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
std::vector<MapPoint> cropRobust(const std::vector<MapPoint>& in, double percentile,
                                 double margin) {
  if (in.size() < 10 || percentile <= 0) return in;
  Eigen::Vector3f lo, hi;
  std::vector<float> v(in.size());
  for (int a = 0; a < 3; ++a) {
    for (size_t i = 0; i < in.size(); ++i) v[i] = in[i].p[a];
    const auto at = [&](double pct) {
      const size_t k =
          std::min(v.size() - 1, static_cast<size_t>(pct / 100.0 * static_cast<double>(v.size())));
      std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
      return v[k];
    };
    lo[a] = at(percentile);
    hi[a] = at(100 - percentile);
  }
  const float widen = static_cast<float>(margin) * (hi - lo).maxCoeff();
  lo.array() -= widen;
  hi.array() += widen;
  std::vector<MapPoint> out;
  out.reserve(in.size());
  for (const auto& m : in)
    if ((m.p.array() >= lo.array()).all() && (m.p.array() <= hi.array()).all()) out.push_back(m);
  return out;
}

}  // namespace

std::vector<MapPoint> keepMultiView(const std::map<int32_t, std::vector<MapPoint>>& by_keyframe,
                                    double voxel, int min_keyframes) {
  std::vector<MapPoint> out;
  if (min_keyframes <= 1 || !(voxel > 0)) {
    for (const auto& [kf, pts] : by_keyframe) out.insert(out.end(), pts.begin(), pts.end());
    return out;
  }
  // A voxel's indices packed 21 bits per axis (z lowest), offset so that they are never negative:
  // a neighbour's key is the voxel's plus a constant, and the voxels of one (x, y) row are
  // consecutive keys. (A map spans far fewer than 2^20 voxels on each side of its origin; a point
  // beyond would share the border voxels.)
  constexpr int64_t kBias = int64_t{1} << 20, kY = int64_t{1} << 21, kX = int64_t{1} << 42;
  const auto linear = [](int64_t x, int64_t y, int64_t z) {
    const auto field = [](int64_t v) { return std::clamp<int64_t>(v + kBias, 0, 2 * kBias - 1); };
    return field(x) * kX + field(y) * kY + field(z);
  };
  // Every point's voxel (as voxelKey() finds it) and its keyframe's bit, in the order of the input.
  std::vector<const MapPoint*> points;
  std::vector<uint8_t> bit;
  std::vector<std::pair<int64_t, uint32_t>> keyed;  // (voxel, point)
  size_t count = 0;
  for (const auto& [kf, pts] : by_keyframe) count += pts.size();
  points.reserve(count);
  bit.reserve(count);
  keyed.reserve(count);
  for (const auto& [kf, pts] : by_keyframe) {
    const auto h = static_cast<uint8_t>(static_cast<uint32_t>(kf) * 2654435761u >> 25);  // 0..127
    for (const auto& m : pts) {
      const auto q = [&](float v) { return static_cast<int64_t>(std::floor(v / voxel)); };
      keyed.emplace_back(linear(q(m.p.x()), q(m.p.y()), q(m.p.z())),
                         static_cast<uint32_t>(points.size()));
      points.push_back(&m);
      bit.push_back(h);
    }
  }
  std::sort(keyed.begin(), keyed.end());
  // The occupied voxels in key order, their keyframe masks, and the first point of each: the one
  // whose voxel's neighbours are looked up (voxelOf() may put a point on a voxel's border into
  // the next; the first decides for all, as it always has).
  struct Voxel {
    int64_t key;
    uint64_t mask[2] = {0, 0};
    uint32_t first;
    int64_t query = 0;
    bool keep = false;
  };
  std::vector<Voxel> voxels;
  voxels.reserve(count / 2);
  std::vector<uint32_t> voxel_of(count);
  for (const auto& [key, i] : keyed) {
    if (voxels.empty() || voxels.back().key != key) voxels.push_back(Voxel{key, {0, 0}, i});
    voxels.back().mask[bit[i] >> 6] |= uint64_t{1} << (bit[i] & 63);
    voxel_of[i] = static_cast<uint32_t>(voxels.size() - 1);
  }
  std::vector<uint32_t> order(voxels.size());
  for (size_t v = 0; v < voxels.size(); ++v) {
    const Eigen::Vector3i c = voxelOf(points[voxels[v].first]->p, voxel);
    voxels[v].query = linear(c.x(), c.y(), c.z());
    order[v] = static_cast<uint32_t>(v);
  }
  std::sort(order.begin(), order.end(),
            [&](uint32_t a, uint32_t b) { return voxels[a].query < voxels[b].query; });
  // One sweep: for each of the 9 (x, y) rows around a voxel, a cursor into the occupied voxels
  // that only moves forward as the queries grow; the row's three voxels are consecutive keys.
  int64_t row_offset[9];
  size_t cursor[9];
  for (int r = 0; r < 9; ++r) {
    row_offset[r] = (r / 3 - 1) * kX + (r % 3 - 1) * kY;
    cursor[r] = 0;
  }
  for (const uint32_t v : order) {
    uint64_t all[2] = {0, 0};
    for (int r = 0; r < 9; ++r) {
      const int64_t lo = voxels[v].query + row_offset[r] - 1, hi = lo + 2;
      size_t& j = cursor[r];
      while (j < voxels.size() && voxels[j].key < lo) ++j;
      for (size_t k = j; k < voxels.size() && voxels[k].key <= hi; ++k) {
        all[0] |= voxels[k].mask[0];
        all[1] |= voxels[k].mask[1];
      }
    }
    voxels[v].keep = __builtin_popcountll(all[0]) + __builtin_popcountll(all[1]) >= min_keyframes;
  }
  out.reserve(points.size());
  for (size_t i = 0; i < points.size(); ++i)
    if (voxels[voxel_of[i]].keep) out.push_back(*points[i]);
  return out;
}

namespace {

// With a support: clusters lower than min_height over it are its texture; the others stand on
// it, so their footprint (their points dropped onto the plane) belongs to them: it covers the
// bottom that structure removal took away.
void standOnSupport(std::vector<Candidate>* candidates, const Plane& plane,
                    const ProposalOptions& o) {
  std::vector<Candidate> kept;
  const Eigen::Vector3f n = plane.normal();
  for (auto& c : *candidates) {
    // Height of the cluster: its 80th percentile over the plane (noise does not make it tall).
    std::vector<float> h;
    h.reserve(c.points.size());
    for (const auto& p : c.points) h.push_back(plane.distance(p));
    const size_t k = h.size() * 4 / 5;
    std::nth_element(h.begin(), h.begin() + static_cast<long>(k), h.end());
    if (h.empty() || h[k] < o.min_height) continue;
    c.on_support = true;
    if (o.add_footprint) {
      const size_t count = c.points.size();
      for (size_t i = 0; i < count; ++i)
        c.points.push_back(c.points[i] - plane.distance(c.points[i]) * n);
      setBounds(&c);
    }
    kept.push_back(std::move(c));
  }
  *candidates = std::move(kept);
}

// Band points outside a candidate's surroundings below which its colour reference is the whole
// band.
constexpr double kMinReferencePoints = 100;

// What of an object lies as low as the support's depth noise (a cap's brim, a bowl's foot) was
// removed with the support's band. A band point whose colour is more likely the candidate's than
// the support's (RGB histograms of band_colour_bin levels: the candidate's own points against the
// band outside its surroundings, which is the support) and that is connected to the candidate's
// base through such points (steps of 2 x radius), within band_grow of its bounds, is the
// candidate's. `coloured`: the clustered points, on a grid of `voxel` (candidates' points are
// positions of these). Returns the points taken (summed over candidates).
int64_t takeBandPoints(std::vector<Candidate>* candidates, const std::vector<MapPoint>& band,
                       const std::vector<MapPoint>& coloured, double voxel, const Plane& plane,
                       const ProposalOptions& o) {
  if (!(o.band_grow > 0) || band.empty() || candidates->empty()) return 0;
  const int bin = std::max(1, o.band_colour_bin);
  const int levels = 255 / bin + 1;
  const size_t bins = static_cast<size_t>(levels * levels * levels);
  const auto colourBin = [&](uint8_t r, uint8_t g, uint8_t b) {
    return static_cast<size_t>((r / bin * levels + g / bin) * levels + b / bin);
  };
  std::vector<double> support(bins, 0);
  for (const auto& m : band)
    support[colourBin(m.r, m.g, m.b)] += 1.0 / static_cast<double>(band.size());
  std::unordered_map<int64_t, size_t>
      colour_of;  // voxel key of a clustered point -> its colour bin
  colour_of.reserve(coloured.size());
  for (const auto& m : coloured) colour_of.emplace(voxelKey(m.p, voxel), colourBin(m.r, m.g, m.b));
  std::vector<size_t> band_bin(band.size());
  for (size_t i = 0; i < band.size(); ++i) band_bin[i] = colourBin(band[i].r, band[i].g, band[i].b);

  const double step = 2 * o.radius;
  std::unordered_map<int64_t, std::vector<int>> grid;
  for (size_t i = 0; i < band.size(); ++i)
    grid[voxelKeyAt(voxelOf(band[i].p, step), step)].push_back(static_cast<int>(i));
  std::vector<int> taken_by(band.size(), -1);
  int64_t taken = 0;
  const float base = static_cast<float>(2 * o.support_distance);
  std::vector<double> own(bins);
  std::vector<char> own_colour(bins);  // per bin: the candidate's colour rather than the support's
  for (size_t k = 0; k < candidates->size(); ++k) {
    Candidate& c = (*candidates)[k];
    std::fill(own.begin(), own.end(), 0.0);
    double n = 0;
    for (size_t i = 0; i < c.points.size(); i += 4)  // every 4th point: plenty for a histogram
      if (const auto it = colour_of.find(voxelKey(c.points[i], voxel)); it != colour_of.end()) {
        own[it->second] += 1;
        n += 1;
      }
    if (n == 0) continue;
    // The support's colours are measured on its band away from this candidate: the candidate's own
    // brim or foot is band too, and a large one (a cap's brim near the camera) made its colour the
    // support's. Too few band points elsewhere: the whole band.
    const Eigen::Vector3f lo = c.min.array() - static_cast<float>(o.band_grow);
    const Eigen::Vector3f hi = c.max.array() + static_cast<float>(o.band_grow);
    std::vector<double> reference(bins, 0.0);
    double elsewhere = 0;
    if (o.band_reference_elsewhere)
      for (size_t u = 0; u < band.size(); ++u) {
        const Eigen::Vector3f& p = band[u].p;
        if ((p.array() >= lo.array()).all() && (p.array() <= hi.array()).all()) continue;
        reference[band_bin[u]] += 1;
        elsewhere += 1;
      }
    if (elsewhere < kMinReferencePoints)
      reference = support;
    else
      for (double& r : reference) r /= elsewhere;
    for (size_t b = 0; b < bins; ++b)
      own_colour[b] = own[b] / n > o.band_colour_ratio * reference[b];
    std::vector<Eigen::Vector3f> front;
    for (const auto& p : c.points)
      if (plane.distance(p) <= base) front.push_back(p);
    const size_t before = c.points.size();
    for (size_t q = 0; q < front.size(); ++q) {
      const Eigen::Vector3i at = voxelOf(front[q], step);
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const auto cell = grid.find(voxelKeyAt(at + Eigen::Vector3i(dx, dy, dz), step));
            if (cell == grid.end()) continue;
            for (int i : cell->second) {
              const size_t u = static_cast<size_t>(i);
              const Eigen::Vector3f& p = band[u].p;
              if (taken_by[u] == static_cast<int>(k) || !own_colour[band_bin[u]] ||
                  (p - front[q]).squaredNorm() > static_cast<float>(step * step) ||
                  (p.array() < lo.array()).any() || (p.array() > hi.array()).any())
                continue;
              taken_by[u] = static_cast<int>(k);
              front.push_back(p);
              c.points.push_back(p);
            }
          }
    }
    if (c.points.size() > before) {
      taken += static_cast<int64_t>(c.points.size() - before);
      setBounds(&c);
    }
  }
  return taken;
}

// The clusters of `finer_label` (per map point, -1: none) holding at least `share` of `members`.
int countParts(const std::vector<int>& members, const std::vector<int>& finer_label, double share) {
  std::unordered_map<int, int> count;
  for (const int i : members)
    if (const int l = finer_label[static_cast<size_t>(i)]; l >= 0) ++count[l];
  int parts = 0;
  for (const auto& [label, n] : count)
    if (n >= share * static_cast<double>(members.size())) ++parts;
  return parts;
}

}  // namespace

ProposalOptions scaledLengths(const ProposalOptions& options, double scale) {
  ProposalOptions o = options;
  for (double* v : {&o.voxel, &o.multiview_voxel, &o.max_depth_std, &o.plane_distance,
                    &o.structure_cell, &o.structure_extent, &o.support_radius, &o.support_below,
                    &o.support_distance, &o.support_margin, &o.min_height, &o.max_height,
                    &o.band_grow, &o.radius, &o.max_extent, &o.min_extent})
    *v *= scale;
  return o;
}

std::vector<Candidate> clusterPoints(const std::vector<MapPoint>& points,
                                     const ProposalOptions& o) {
  std::vector<Candidate> out;
  std::vector<std::vector<int64_t>> keys;  // per kept cluster, at the finest clustering voxel
  const double key_voxel = 2 * o.radius;
  // Each coarser scale clusters a grid of half its radius (the map itself is on a grid of about
  // half the finest radius): a bounded number of neighbours per point, and about the same density
  // threshold (neighbours per radius) at every scale. Clusters are then made of the map's own
  // points (each takes the cluster of its grid cell), so that sizes and overlaps compare across
  // scales. The grids are built once for both passes.
  struct Grid {
    std::vector<Eigen::Vector3f> xyz, rgb;
    std::vector<int> cell_of;  // per map point, its grid point (-1: none)
  };
  std::vector<Grid> grids;
  for (int s = 0; s < o.scales; ++s) {
    const double r = o.radius * std::pow(2.0, s);
    const std::vector<MapPoint> cloud = s == 0 ? points : downsample(points, r / 2);
    if (cloud.empty()) break;
    Grid g;
    g.xyz.resize(cloud.size());
    g.rgb.resize(cloud.size());
    for (size_t i = 0; i < cloud.size(); ++i) {
      g.xyz[i] = cloud[i].p;
      g.rgb[i] = Eigen::Vector3f(cloud[i].r, cloud[i].g, cloud[i].b);
    }
    g.cell_of.resize(points.size());
    if (s == 0) {
      for (size_t i = 0; i < points.size(); ++i) g.cell_of[i] = static_cast<int>(i);
    } else {
      std::unordered_map<int64_t, int> cell;  // downsample() keeps one point per cell
      cell.reserve(cloud.size());
      for (size_t i = 0; i < cloud.size(); ++i)
        cell.emplace(voxelKey(cloud[i].p, r / 2), static_cast<int>(i));
      for (size_t i = 0; i < points.size(); ++i) {
        const auto it = cell.find(voxelKey(points[i].p, r / 2));
        g.cell_of[i] = it == cell.end() ? -1 : it->second;
      }
    }
    grids.push_back(std::move(g));
  }
  // Position alone, then (colour_distance > 0) position and colour, at every scale but the finest
  // (where objects are apart anyway): touching objects of different colours that no density
  // threshold separates are split by the second pass, while an object of many colours (a printed
  // box) stays whole in the first.
  const int passes = o.colour_distance > 0 ? 2 : 1;
  std::vector<std::vector<int>> point_label(
      grids.size());  // per scale, each map point's position-pass cluster
  for (int pass = 0; pass < passes; ++pass) {
    const int first_scale = pass == 0 ? 0 : 1;
    for (int s = first_scale; s < static_cast<int>(grids.size()); ++s) {
      const Grid& g = grids[static_cast<size_t>(s)];
      DensityClusterOptions dc;
      dc.radius = static_cast<float>(o.radius * std::pow(2.0, s));
      dc.min_neighbours = o.min_neighbours;
      dc.colour_distance = pass == 1 ? static_cast<float>(o.colour_distance) : 0.0f;
      int count = 0;
      const std::vector<int> label = densityClusters(g.xyz, g.rgb, dc, &count);
      std::vector<Candidate> found(static_cast<size_t>(count));
      std::vector<std::vector<int>> members(static_cast<size_t>(count));
      if (pass == 0) point_label[static_cast<size_t>(s)].assign(points.size(), -1);
      for (size_t i = 0; i < points.size(); ++i) {
        const int cell = g.cell_of[i];
        if (cell >= 0 && label[static_cast<size_t>(cell)] >= 0) {
          const int l = label[static_cast<size_t>(cell)];
          found[static_cast<size_t>(l)].points.push_back(points[i].p);
          members[static_cast<size_t>(l)].push_back(static_cast<int>(i));
          if (pass == 0) point_label[static_cast<size_t>(s)][i] = l;
        }
      }
      const int min_points = o.min_points;
      for (size_t l = 0; l < found.size(); ++l) {
        Candidate& c = found[l];
        if (static_cast<int>(c.points.size()) < min_points) continue;
        c.scale = s;
        c.by_colour = pass == 1;
        setBounds(&c);
        const Eigen::Vector3f extent = c.max - c.min;
        if (extent.maxCoeff() > o.max_extent || extent.maxCoeff() < o.min_extent) continue;
        // The same cluster found again at a coarser scale is one candidate.
        std::vector<int64_t> k = voxelSet(c.points, key_voxel);
        bool duplicate = false;
        for (size_t i = 0; i < keys.size(); ++i)
          if (jaccard(k, keys[i]) >= o.same_cluster_overlap) {
            // Found again: an isolated object rather than a fragment. (The colour pass only adds
            // clusters: it does not change the standing of the position-only ones.)
            if (pass == 0 || out[i].by_colour) ++out[i].stability;
            duplicate = true;
            break;
          }
        if (duplicate) continue;
        // Its parts: the clusters of the next finer scale (position pass) that hold split_share
        // of its points each. Two are two objects that the coarser threshold joins where they
        // touch.
        if (s > 0)
          c.parts = countParts(members[l], point_label[static_cast<size_t>(s - 1)], o.split_share);
        keys.push_back(std::move(k));
        out.push_back(std::move(c));
      }
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

CandidateMap::CandidateMap(CandidateMap&& other) noexcept
    : options_(std::move(other.options_)),
      map_id_(other.map_id_),
      by_keyframe_(std::move(other.by_keyframe_)),
      keyframe_centres_(std::move(other.keyframe_centres_)),
      views_(std::move(other.views_)),
      view_stride_(other.view_stride_),
      views_seen_(other.views_seen_),
      dirty_(other.dirty_),
      candidates_(std::move(other.candidates_)),
      retired_(std::move(other.retired_)),
      support_(std::move(other.support_)),
      own_ids_(other.own_ids_),
      ids_(other.ids_ == &other.own_ids_ ? &own_ids_ : other.ids_),
      stats_(other.stats_) {}

void CandidateMap::resetMap(int32_t map_id) {
  map_id_ = map_id;
  by_keyframe_.clear();
  keyframe_centres_.clear();
  views_.clear();
  view_stride_ = 1;
  views_seen_ = 0;
  candidates_.clear();
  retired_.clear();
  support_ = Support{};
}

void CandidateMap::update(int32_t map_id, bool full, int32_t keyframe_id,
                          const std::vector<int32_t>& keyframe_ids,
                          const std::vector<MapPoint>& points) {
  if (map_id != map_id_) resetMap(map_id);
  if (full) {
    by_keyframe_.clear();
    for (size_t i = 0; i < points.size(); ++i)
      if (points[i].p.allFinite())
        by_keyframe_[i < keyframe_ids.size() ? keyframe_ids[i] : -1].push_back(points[i]);
  } else {
    auto& kf = by_keyframe_[keyframe_id];
    kf.clear();
    for (const auto& p : points)
      if (p.p.allFinite()) kf.push_back(p);
  }
  dirty_ = true;
}

void CandidateMap::setKeyframeCentre(int32_t map_id, int32_t keyframe_id,
                                     const Eigen::Vector3f& centre) {
  if (map_id != map_id_ || !centre.allFinite()) return;
  keyframe_centres_[keyframe_id] = centre;
}

void CandidateMap::addView(int32_t map_id, const SE3& T_world_camera) {
  if (map_id != map_id_ || !T_world_camera.matrix().allFinite()) return;
  // Bounded: past max_views, every other view is dropped and only every 2nd pose is kept after.
  if (views_seen_++ % view_stride_ != 0) return;
  const Eigen::Matrix3f R = T_world_camera.linear().cast<float>();
  views_.push_back({T_world_camera.translation().cast<float>(), R.col(2), R.col(0), -R.col(1)});
  if (static_cast<int>(views_.size()) > std::max(2, options_.max_views)) {
    std::vector<View> kept;
    for (size_t i = 0; i < views_.size(); i += 2) kept.push_back(views_[i]);
    views_.swap(kept);
    view_stride_ *= 2;
  }
}

size_t CandidateMap::points() const {
  size_t n = 0;
  for (const auto& [kf, p] : by_keyframe_) n += p.size();
  return n;
}

// The median distance at which the map's points were seen: from their keyframe's centre when it
// is known, else from the views' mean centre. Monocular maps have no metric scale; this is the
// length every option is relative to.
static double sceneScale(const ClusterInputRef& in, const std::vector<MapPoint>& all) {
  std::vector<float> range;
  range.reserve(all.size() / 4 + 1);
  for (const auto& [kf, pts] : in.by_keyframe) {
    const auto c = in.keyframe_centres.find(kf);
    if (c == in.keyframe_centres.end()) continue;
    for (size_t i = 0; i < pts.size(); i += 4) range.push_back((pts[i].p - c->second).norm());
  }
  if (range.empty() && !in.views.empty()) {
    Eigen::Vector3f centre = Eigen::Vector3f::Zero();
    for (const auto& v : in.views) centre += v.centre;
    centre /= static_cast<float>(in.views.size());
    for (size_t i = 0; i < all.size(); i += 4) range.push_back((all[i].p - centre).norm());
  }
  if (range.empty()) return 1.0;
  std::nth_element(range.begin(), range.begin() + static_cast<long>(range.size() / 2), range.end());
  const double m = range[range.size() / 2];
  return m > 0 ? m : 1.0;
}

Clustering clusterMap(const ClusterInput& in) {
  return clusterMap(
      ClusterInputRef{in.map_id, in.options, in.by_keyframe, in.keyframe_centres, in.views});
}

Clustering clusterMap(const ClusterInputRef& in) {
  Clustering out;
  out.map_id = in.map_id;
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<MapPoint> all;
  for (const auto& [kf, p] : in.by_keyframe) all.insert(all.end(), p.begin(), p.end());
  out.stats.input_points = static_cast<int64_t>(all.size());
  out.stats.views = static_cast<int>(in.views.size());
  ProposalOptions o = in.options;
  // A young map is sparse: its objects hold few points, yet they are to be proposed from the start.
  out.stats.young = out.stats.input_points < o.young_map_points;
  if (out.stats.young) {
    o.min_points = std::min(o.min_points, o.young_min_points);
    if (o.young_radius_scale > 0) o.radius *= o.young_radius_scale;
  }
  bool has_support = false;
  if (all.size() >= static_cast<size_t>(std::max(3, o.min_points))) {
    out.stats.scene_scale = o.relative_lengths ? sceneScale(in, all) : 1.0;
    o = scaledLengths(o, out.stats.scene_scale);
    const ViewPriors priors = viewPriors(in.views);
    out.stats.look_at = priors.has_look_at;
    const size_t before = all.size();
    // A young map has few keyframes: ask for agreement of at most half of them.
    const int keyframes = static_cast<int>(in.by_keyframe.size());
    const int min_keyframes = std::min(o.min_keyframes, std::max(1, keyframes / 2));
    all = keepMultiView(in.by_keyframe, o.multiview_voxel, min_keyframes);
    out.stats.single_view = static_cast<int64_t>(before - all.size());
    all = cropRobust(all, o.crop_percentile, o.crop_margin);
    out.stats.cropped =
        static_cast<int64_t>(before) - out.stats.single_view - static_cast<int64_t>(all.size());
    // Bounded cost: downsample until the map fits max_points.
    double voxel = o.voxel;
    std::vector<MapPoint> small = downsample(all, voxel);
    for (int i = 0; i < 20 && static_cast<int>(small.size()) > o.max_points; ++i) {
      voxel *= 1.26;
      small = downsample(all, voxel);
    }
    out.stats.voxel = voxel;
    std::vector<MapPoint> rest = std::move(small);
    const auto t1 = std::chrono::steady_clock::now();
    out.stats.filter_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
    StructureResult structure = removeStructure(rest, in.views, priors, o);
    rest = std::move(structure.kept);
    out.support = structure.support;
    has_support = structure.has_support;
    const std::vector<MapPoint>& band = structure.band;
    const auto t2 = std::chrono::steady_clock::now();
    out.stats.structure_ms = std::chrono::duration<double, std::milli>(t2 - t1).count();
    out.stats.planes = structure.stats.planes;
    out.stats.plane_points = structure.stats.structure_points;
    out.stats.support = has_support;
    if (has_support) {
      // What stands on the support: over its points' region and not higher than an object.
      std::vector<MapPoint> on;
      on.reserve(rest.size());
      for (const auto& m : rest) {
        const float h = out.support.plane.distance(m.p);
        if (h > 0 && h <= o.max_height &&
            out.support.over(m.p, static_cast<float>(o.support_margin)))
          on.push_back(m);
      }
      rest.swap(on);
    }
    int64_t seen_through = 0;
    rest = removeSeenThrough(rest, in.by_keyframe, in.keyframe_centres, in.views, o.free_space,
                             &seen_through);
    out.stats.seen_through = seen_through;
    out.stats.clustered_points = static_cast<int64_t>(rest.size());
    out.found = clusterPoints(rest, o);
    if (has_support) {
      standOnSupport(&out.found, out.support.plane, o);
      out.stats.band_points = static_cast<int64_t>(band.size());
      out.stats.band_taken = takeBandPoints(&out.found, band, rest, voxel, out.support.plane, o);
    }
    out.stats.cluster_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t2).count();
  }
  if (!has_support) out.support = Support{};
  out.key_voxel = 2 * o.radius;
  out.stats.ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

std::optional<ClusterInput> CandidateMap::takeClusterInput() {
  if (!dirty_) return std::nullopt;
  dirty_ = false;
  return ClusterInput{map_id_, options_, by_keyframe_, keyframe_centres_, views_};
}

bool CandidateMap::recluster(int64_t utime) {
  if (!dirty_) return false;
  dirty_ = false;
  return adopt(
      clusterMap(ClusterInputRef{map_id_, options_, by_keyframe_, keyframe_centres_, views_}),
      utime);
}

bool CandidateMap::adopt(Clustering&& clustering, int64_t utime) {
  if (clustering.map_id != map_id_) return false;
  std::vector<Candidate> found = std::move(clustering.found);
  // Stable ids: each new cluster takes the id of the old candidate it shares most voxels with
  // (one to one, greedily by overlap), if they share at least id_overlap.
  const double key_voxel = clustering.key_voxel;
  std::vector<std::vector<int64_t>> old_keys, new_keys;
  for (const auto& c : candidates_) old_keys.push_back(voxelSet(c.points, key_voxel));
  for (const auto& c : found) new_keys.push_back(voxelSet(c.points, key_voxel));
  std::vector<Pair> pairs;
  for (size_t n = 0; n < found.size(); ++n)
    for (size_t o = 0; o < candidates_.size(); ++o) {
      if (!boundsMeet(found[n], candidates_[o].min, candidates_[o].max)) continue;
      const double j = jaccard(new_keys[n], old_keys[o]);
      if (j >= options_.id_overlap) pairs.push_back({j, n, o});
    }
  std::vector<bool> new_done(found.size()), old_done(candidates_.size());
  matchGreedily(&pairs, &new_done, &old_done);
  for (const auto& p : pairs) found[p.n].id = candidates_[p.o].id;
  // A cluster that took no current id takes back the id of a dropped candidate of its scale that it
  // overlaps as much: the same rule, over what earlier clusterings dropped. Within a scale: the
  // part, the whole and the whole with its neighbour overlap across scales, and a cluster that
  // took the id of another scale's would inherit evidence gathered on another region.
  std::vector<Pair> back;
  for (size_t r = 0; r < retired_.size(); ++r) {
    std::vector<int64_t> keys;
    for (size_t n = 0; n < found.size(); ++n) {
      if (new_done[n] || found[n].scale != retired_[r].scale ||
          !boundsMeet(found[n], retired_[r].min, retired_[r].max))
        continue;
      if (keys.empty()) keys = voxelSet(retired_[r].points, key_voxel);
      const double j = jaccard(new_keys[n], keys);
      if (j >= options_.id_overlap) back.push_back({j, n, r});
    }
  }
  std::vector<bool> retired_done(retired_.size());
  matchGreedily(&back, &new_done, &retired_done);
  for (const auto& p : back) found[p.n].id = retired_[p.o].id;
  for (auto& c : found)
    if (c.id < 0) c.id = (*ids_)++;
  std::vector<Retired> retired;
  for (size_t r = 0; r < retired_.size(); ++r)
    if (!retired_done[r]) retired.push_back(std::move(retired_[r]));
  // A candidate no new cluster took over, whose region no new cluster holds either (its points
  // left out of this clustering: outside the support's region as it was fitted this time, or too
  // few for min_points after the filters), is kept for keep_lost_s of frame time.
  if (options_.keep_lost_s > 0) {
    std::vector<int64_t> held;
    for (const auto& k : new_keys) held.insert(held.end(), k.begin(), k.end());
    std::sort(held.begin(), held.end());
    held.erase(std::unique(held.begin(), held.end()), held.end());
    for (size_t o = 0; o < candidates_.size(); ++o) {
      if (old_done[o] || old_keys[o].empty()) continue;
      Candidate& c = candidates_[o];
      const int64_t since = c.lost_since >= 0 ? c.lost_since : utime;
      if (static_cast<double>(utime - since) > 1e6 * options_.keep_lost_s) continue;
      size_t in = 0;
      for (int64_t k : old_keys[o]) in += std::binary_search(held.begin(), held.end(), k) ? 1 : 0;
      if (static_cast<double>(in) >= options_.lost_held * static_cast<double>(old_keys[o].size()))
        continue;
      c.lost_since = since;
      found.push_back(std::move(c));
      old_done[o] = true;  // carried over: not dropped
    }
  }
  // The candidates dropped now, one point per key voxel; the oldest go beyond kMaxRetired.
  for (size_t o = 0; o < candidates_.size(); ++o) {
    if (old_done[o] || candidates_[o].points.empty()) continue;
    Retired r{candidates_[o].id, candidates_[o].scale, {}, candidates_[o].min, candidates_[o].max};
    std::unordered_set<int64_t> seen;
    for (const auto& p : candidates_[o].points)
      if (seen.insert(voxelKey(p, key_voxel)).second) r.points.push_back(p);
    retired.push_back(std::move(r));
  }
  if (retired.size() > kMaxRetired)
    retired.erase(retired.begin(), retired.end() - static_cast<std::ptrdiff_t>(kMaxRetired));
  retired_ = std::move(retired);
  candidates_ = std::move(found);
  support_ = std::move(clustering.support);
  stats_ = clustering.stats;
  stats_.clusters = static_cast<int>(candidates_.size());
  stats_.retired = static_cast<int>(retired_.size());
  for (const auto& r : retired_) stats_.retired_points += static_cast<int64_t>(r.points.size());
  return true;
}

}  // namespace slamaware::proposals
