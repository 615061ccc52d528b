#include "procs/proposals/density_clustering.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

namespace slamaware {

namespace {

// Packs a cell index (21 bits per axis, wrapping) into one key.
int64_t cellKey(int64_t x, int64_t y, int64_t z) {
  return ((x & 0x1FFFFF) << 42) | ((y & 0x1FFFFF) << 21) | (z & 0x1FFFFF);
}

int find(std::vector<int>& parent, int i) {
  while (parent[static_cast<size_t>(i)] != i) {
    parent[static_cast<size_t>(i)] = parent[static_cast<size_t>(parent[static_cast<size_t>(i)])];
    i = parent[static_cast<size_t>(i)];
  }
  return i;
}

void unite(std::vector<int>& parent, int a, int b) {
  a = find(parent, a);
  b = find(parent, b);
  if (a == b) return;
  if (a < b) std::swap(a, b);
  parent[static_cast<size_t>(a)] = b;  // the lower index is the root
}

}  // namespace

std::vector<int> densityClusters(const std::vector<Eigen::Vector3f>& points,
                                 const std::vector<Eigen::Vector3f>& colours, const DensityClusterOptions& o,
                                 int* count) {
  const size_t n = points.size();
  std::vector<int> label(n, -1);
  *count = 0;
  if (n == 0 || !(o.radius > 0)) return label;
  const float r = o.radius, r2 = r * r;
  const bool use_colour = o.colour_distance > 0 && colours.size() == n;
  const float c2 = o.colour_distance * o.colour_distance;

  // Points sorted by cell (cell side = radius: neighbours are in the 27 cells around).
  std::vector<Eigen::Vector3i> cell(n);
  std::vector<std::pair<int64_t, int>> order(n);
  for (size_t i = 0; i < n; ++i) {
    cell[i] = (points[i] / r).array().floor().cast<int>();
    order[i] = {cellKey(cell[i].x(), cell[i].y(), cell[i].z()), static_cast<int>(i)};
  }
  std::sort(order.begin(), order.end());
  std::unordered_map<int64_t, std::pair<int, int>> range;  // key -> [begin, end) in order
  range.reserve(n);
  for (size_t i = 0; i < n;) {
    size_t j = i;
    while (j < n && order[j].first == order[i].first) ++j;
    range.emplace(order[i].first, std::make_pair(static_cast<int>(i), static_cast<int>(j)));
    i = j;
  }
  auto forNeighbours = [&](size_t i, auto&& visit) {
    const Eigen::Vector3i& c = cell[i];
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = range.find(cellKey(c.x() + dx, c.y() + dy, c.z() + dz));
          if (it == range.end()) continue;
          for (int k = it->second.first; k < it->second.second; ++k) {
            const int j = order[static_cast<size_t>(k)].second;
            if ((points[static_cast<size_t>(j)] - points[i]).squaredNorm() <= r2) {
              if (!visit(j)) return;
            }
          }
        }
  };

  // Core points.
  std::vector<char> core(n, 0);
  for (size_t i = 0; i < n; ++i) {
    int found = 0;
    forNeighbours(i, [&](int) { return ++found < o.min_neighbours; });
    core[i] = found >= o.min_neighbours;
  }
  // Core points linked within the radius (and colour) are one cluster.
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (size_t i = 0; i < n; ++i) {
    if (!core[i]) continue;
    forNeighbours(i, [&](int j) {
      const size_t sj = static_cast<size_t>(j);
      if (sj > i && core[sj] && (!use_colour || (colours[i] - colours[sj]).squaredNorm() < c2))
        unite(parent, static_cast<int>(i), j);
      return true;
    });
  }
  // Labels in order of the lowest point index of each cluster; border points take the cluster of
  // their nearest core point.
  std::vector<int> root_label(n, -1);
  for (size_t i = 0; i < n; ++i) {
    if (!core[i]) continue;
    const int root = find(parent, static_cast<int>(i));
    if (root_label[static_cast<size_t>(root)] < 0) root_label[static_cast<size_t>(root)] = (*count)++;
    label[i] = root_label[static_cast<size_t>(root)];
  }
  for (size_t i = 0; i < n; ++i) {
    if (core[i]) continue;
    float best = std::numeric_limits<float>::infinity();
    forNeighbours(i, [&](int j) {
      const size_t sj = static_cast<size_t>(j);
      const float d = (points[sj] - points[i]).squaredNorm();
      if (core[sj] && (d < best || (d == best && label[sj] < label[i]))) {
        best = d;
        label[i] = label[sj];
      }
      return true;
    });
  }
  return label;
}

}  // namespace slamaware
