#include "procs/proposals/projector.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/nearest_depths.h"

namespace slamaware::proposals {

double boxIou(const ProposalBox& a, const ProposalBox& b) {
  return rectIou(a.x, a.y, a.w, a.h, b.x, b.y, b.w, b.h);
}

namespace {

struct Projected {
  size_t index;  // into candidates
  std::vector<Eigen::Vector2f> pixels;
  std::vector<float> depths;
};

// Per depth-buffer cell: the two nearest depths with different candidates.
using Cell = NearestDepths;

// The range of v (reordered here) without the outer trim_pct % on each side, grown again over the
// trimmed values while each lies within gap times the mean spacing of the values inside (gap > 0;
// this needs v sorted, the plain trim only its two order statistics: every frame, every box).
void trimmedRange(std::vector<float>& v, double trim_pct, double gap, float* lo, float* hi) {
  const size_t n = v.size();
  size_t i0 = std::min(
      n - 1, static_cast<size_t>(std::lround(trim_pct / 100.0 * static_cast<double>(n - 1))));
  size_t i1 = std::min(n - 1, static_cast<size_t>(std::lround((100.0 - trim_pct) / 100.0 *
                                                              static_cast<double>(n - 1))));
  if (gap <= 0) {
    std::nth_element(v.begin(), v.begin() + static_cast<long>(i0), v.end());
    *lo = v[i0];
    std::nth_element(v.begin(), v.begin() + static_cast<long>(i1), v.end());
    *hi = v[i1];
    return;
  }
  std::sort(v.begin(), v.end());
  if (i1 > i0) {
    const double step = gap * static_cast<double>(v[i1] - v[i0]) / static_cast<double>(i1 - i0);
    while (i0 > 0 && v[i0] - v[i0 - 1] <= step) --i0;
    while (i1 + 1 < n && v[i1 + 1] - v[i1] <= step) ++i1;
  }
  *lo = v[i0];
  *hi = v[i1];
}

/// The sampled points of each candidate that project into the image (at most
/// max_points_per_candidate of each); a candidate with fewer than min_visible_fraction of its
/// samples in the image is left out.
std::vector<Projected> projectInView(const std::vector<Candidate>& candidates,
                                     const CameraModel& camera, const SE3& T_cw,
                                     const ProposalOptions& o) {
  const int W = camera.width(), H = camera.height();
  std::vector<Projected> projected;
  for (size_t ci = 0; ci < candidates.size(); ++ci) {
    const Candidate& c = candidates[ci];
    if (c.points.empty()) continue;
    const size_t step =
        std::max<size_t>(1, (c.points.size() + o.max_points_per_candidate - 1) /
                                static_cast<size_t>(std::max(1, o.max_points_per_candidate)));
    Projected p{ci, {}, {}};
    size_t sampled = 0;
    for (size_t i = 0; i < c.points.size(); i += step) {
      ++sampled;
      const Eigen::Vector3d pc = T_cw * c.points[i].cast<double>();
      Eigen::Vector2d px;
      if (!pc.allFinite() || !camera.project(pc, &px, 1e-3)) continue;
      if (px.x() < 0 || px.y() < 0 || px.x() > W - 1 || px.y() > H - 1) continue;
      p.pixels.push_back(px.cast<float>());
      p.depths.push_back(static_cast<float>(pc.z()));
    }
    if (p.pixels.empty() || p.pixels.size() < o.min_visible_fraction * static_cast<double>(sampled))
      continue;
    projected.push_back(std::move(p));
  }
  return projected;
}

/// The boxes in ranking order (below), each dropped that overlaps a better one by more than
/// nms_iou, at most max_boxes.
std::vector<ProposalBox> rankAndSuppress(std::vector<ProposalBox> boxes, const ProposalOptions& o,
                                         ProjectionStats* st) {
  // Ranking: candidates the last clustering found before those it lost (keep_lost_s); among them,
  // the clusters on position first (those of the colour pass fill in where they leave
  // an object uncovered), then those that do not split into two parts at the next finer scale
  // (two touching objects that a coarser threshold joins are often found alike at several scales,
  // and their box would suppress that of the larger one alone), then clusters found alike at
  // more density scales (an isolated object), then finer ones (a coarser cluster that holds the
  // same object also holds the smeared points around it and often a neighbour), then the ones
  // with more points.
  std::stable_sort(boxes.begin(), boxes.end(), [](const ProposalBox& a, const ProposalBox& b) {
    if (a.lost != b.lost) return b.lost;
    if (a.by_colour != b.by_colour) return b.by_colour;
    if ((a.parts > 1) != (b.parts > 1)) return b.parts > 1;
    if (a.stability != b.stability) return a.stability > b.stability;
    if (a.scale != b.scale) return a.scale < b.scale;
    if (a.points != b.points) return a.points > b.points;
    return a.candidate_id < b.candidate_id;
  });
  std::vector<ProposalBox> kept;
  const bool suppress = o.nms_iou < 1;  // else the recognizer does it (config/recognizer.yaml)
  for (const auto& b : boxes) {
    bool suppressed = false;
    for (size_t k = 0; suppress && k < kept.size(); ++k)
      if (boxIou(b, kept[k]) > o.nms_iou) {
        suppressed = true;
        break;
      }
    if (suppressed) {
      ++st->suppressed;
      continue;
    }
    if (static_cast<int>(kept.size()) >= o.max_boxes) break;
    kept.push_back(b);
  }
  return kept;
}

}  // namespace

std::vector<ProposalBox> projectCandidates(const std::vector<Candidate>& candidates,
                                           const CameraModel& camera, const SE3& T_world_camera,
                                           const ProposalOptions& o, ProjectionStats* stats) {
  ProjectionStats st;
  const SE3 T_cw = T_world_camera.inverse();
  const int W = camera.width(), H = camera.height();
  const std::vector<Projected> projected = projectInView(candidates, camera, T_cw, o);
  st.in_view = static_cast<int>(projected.size());
  // Depth buffer of every candidate in view.
  const int cell = std::max(1, o.depth_buffer_cell_px);
  const int gw = (W + cell - 1) / cell, gh = (H + cell - 1) / cell;
  std::vector<Cell> zbuf(static_cast<size_t>(gw * gh));
  auto cellOf = [&](const Eigen::Vector2f& px) {
    const int gx = std::clamp(static_cast<int>(px.x()) / cell, 0, gw - 1);
    const int gy = std::clamp(static_cast<int>(px.y()) / cell, 0, gh - 1);
    return static_cast<size_t>(gy * gw + gx);
  };
  for (const auto& p : projected)
    for (size_t i = 0; i < p.pixels.size(); ++i)
      zbuf[cellOf(p.pixels[i])].add(p.depths[i], candidates[p.index].id);
  std::vector<ProposalBox> boxes;
  for (const auto& p : projected) {
    const Candidate& c = candidates[p.index];
    size_t hidden = 0;
    for (size_t i = 0; i < p.pixels.size(); ++i)
      if (zbuf[cellOf(p.pixels[i])].nearestOther(c.id) < p.depths[i] * (1 - o.occlusion_margin))
        ++hidden;
    if (hidden > o.occluded_fraction * static_cast<double>(p.pixels.size())) {
      ++st.occluded;
      continue;
    }
    // The box of the projected points without the outer box_trim_pct % on each side: a few
    // stray points around an object on a support (its footprint, depths smeared at its occluding
    // edges against the textured support) would otherwise widen the box far beyond it. With no
    // support under it, a candidate's outermost points are its own: box_trim_pct_unsupported.
    std::vector<float> us(p.pixels.size()), vs(p.pixels.size());
    for (size_t i = 0; i < p.pixels.size(); ++i) {
      us[i] = p.pixels[i].x();
      vs[i] = p.pixels[i].y();
    }
    const double trim =
        std::clamp(c.on_support ? o.box_trim_pct : o.box_trim_pct_unsupported, 0.0, 49.0);
    float x0, x1, y0, y1;
    trimmedRange(us, trim, o.box_trim_gap, &x0, &x1);
    trimmedRange(vs, trim, o.box_trim_gap, &y0, &y1);
    ProposalBox b;
    b.candidate_id = c.id;
    b.x = std::floor(x0);
    b.y = std::floor(y0);
    b.w = std::floor(x1) - b.x + 1;
    b.h = std::floor(y1) - b.y + 1;
    if (b.w < o.min_box_px || b.h < o.min_box_px) {
      ++st.too_small;
      continue;
    }
    std::vector<float> d = p.depths;
    std::nth_element(d.begin(), d.begin() + static_cast<long>(d.size() / 2), d.end());
    b.median_depth = d[d.size() / 2];
    const Eigen::Vector3d to_camera = T_world_camera.translation() - c.centroid.cast<double>();
    if (to_camera.allFinite() && to_camera.norm() > 0)
      b.view_direction = to_camera.normalized().cast<float>();
    b.scale = c.scale;
    b.stability = c.stability;
    b.by_colour = c.by_colour;
    b.parts = c.parts;
    b.lost = c.lost_since >= 0;
    b.points = static_cast<int>(p.pixels.size());
    boxes.push_back(b);
  }
  std::vector<ProposalBox> kept = rankAndSuppress(std::move(boxes), o, &st);
  if (stats) *stats = st;
  return kept;
}

}  // namespace slamaware::proposals
