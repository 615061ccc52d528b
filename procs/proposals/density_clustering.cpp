#include "procs/proposals/density_clustering.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>

namespace slamaware::proposals {

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

/// Cell key -> cell, open addressing with linear probing in a power-of-two table: the neighbour
/// cells are 27 lookups per occupied cell at every scale and pass, and with std::unordered_map
/// (a node per entry) they took a quarter of densityClusters' time.
class CellTable {
 public:
  explicit CellTable(size_t n) {
    while ((size_t{1} << bits_) < 2 * n + 16) ++bits_;
    keys_.assign(size_t{1} << bits_, kEmpty);
    cells_.resize(keys_.size());
  }
  void insert(int64_t key, int cell) {
    size_t i = slot(key);
    while (keys_[i] != kEmpty) i = (i + 1) & (keys_.size() - 1);
    keys_[i] = key;
    cells_[i] = cell;
  }
  /// The cell of `key`, or -1.
  int find(int64_t key) const {
    for (size_t i = slot(key);; i = (i + 1) & (keys_.size() - 1)) {
      if (keys_[i] == key) return cells_[i];
      if (keys_[i] == kEmpty) return -1;
    }
  }

 private:
  static constexpr int64_t kEmpty = -1;  // cellKey() uses 63 bits: never -1
  size_t slot(int64_t key) const {
    return static_cast<size_t>((static_cast<uint64_t>(key) * 0x9E3779B97F4A7C15ull) >>
                               (64 - bits_));
  }
  int bits_ = 4;
  std::vector<int64_t> keys_;
  std::vector<int> cells_;
};

}  // namespace

std::vector<int> densityClusters(const std::vector<Eigen::Vector3f>& points,
                                 const std::vector<Eigen::Vector3f>& colours,
                                 const DensityClusterOptions& o, int* count) {
  const size_t n = points.size();
  std::vector<int> label(n, -1);
  *count = 0;
  if (n == 0 || !(o.radius > 0)) return label;
  const float r = o.radius, r2 = r * r;
  const bool use_colour = o.colour_distance > 0 && colours.size() == n;
  const float c2 = o.colour_distance * o.colour_distance;

  // Points sorted by cell (cell side = radius: neighbours are in the 27 cells around). Each
  // occupied cell's neighbour cells are looked up once, not once per point and pass.
  std::vector<std::pair<int64_t, int>> order(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3i c = (points[i] / r).array().floor().cast<int>();
    order[i] = {cellKey(c.x(), c.y(), c.z()), static_cast<int>(i)};
  }
  std::sort(order.begin(), order.end());
  std::vector<int> cell_of(n);             // point -> its cell
  std::vector<int> cell_begin;             // cell -> first position in order (+ end)
  std::vector<Eigen::Vector3f> sorted(n);  // points in cell order
  CellTable cell_index(n);                 // key -> cell
  for (size_t i = 0; i < n; ++i) {
    if (i == 0 || order[i].first != order[i - 1].first) {
      cell_index.insert(order[i].first, static_cast<int>(cell_begin.size()));
      cell_begin.push_back(static_cast<int>(i));
    }
    cell_of[static_cast<size_t>(order[i].second)] = static_cast<int>(cell_begin.size()) - 1;
    sorted[i] = points[static_cast<size_t>(order[i].second)];
  }
  const size_t cells = cell_begin.size();
  cell_begin.push_back(static_cast<int>(n));
  std::vector<int> near_begin(cells + 1, 0), near;  // cell -> its occupied neighbour cells
  near.reserve(cells * 9);
  for (size_t c = 0; c < cells; ++c) {
    const Eigen::Vector3f& p = sorted[static_cast<size_t>(cell_begin[c])];
    const Eigen::Vector3i at = (p / r).array().floor().cast<int>();
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const int cell = cell_index.find(cellKey(at.x() + dx, at.y() + dy, at.z() + dz));
          if (cell >= 0) near.push_back(cell);
        }
    near_begin[c + 1] = static_cast<int>(near.size());
  }
  auto forNeighbours = [&](size_t i, auto&& visit) {
    const size_t c = static_cast<size_t>(cell_of[i]);
    const Eigen::Vector3f& p = points[i];
    for (int m = near_begin[c]; m < near_begin[c + 1]; ++m) {
      const size_t nc = static_cast<size_t>(near[static_cast<size_t>(m)]);
      for (int k = cell_begin[nc]; k < cell_begin[nc + 1]; ++k) {
        if ((sorted[static_cast<size_t>(k)] - p).squaredNorm() <= r2) {
          if (!visit(order[static_cast<size_t>(k)].second)) return;
        }
      }
    }
  };

  // Core points.
  std::vector<char> core(n, 0);
  for (size_t k = 0; k < n; ++k) {  // in cell order: neighbouring points are near in memory
    const size_t i = static_cast<size_t>(order[k].second);
    int found = 0;
    forNeighbours(i, [&](int) { return ++found < o.min_neighbours; });
    core[i] = found >= o.min_neighbours;
  }
  // Core points linked within the radius (and colour) are one cluster. Cell by cell, each pair of
  // neighbouring cells once (the cell itself: each pair of its points once), on the points in cell
  // order: every pair of core points is tested once rather than from both ends, and the points a
  // cell pair needs lie together in memory. The clusters are the connected components, whatever
  // the order the links are found in.
  std::vector<char> core_sorted(n);
  std::vector<Eigen::Vector3f> colour_sorted(use_colour ? n : 0);
  for (size_t k = 0; k < n; ++k) {
    const size_t i = static_cast<size_t>(order[k].second);
    core_sorted[k] = core[i];
    if (use_colour) colour_sorted[k] = colours[i];
  }
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (size_t c = 0; c < cells; ++c)
    for (int m = near_begin[c]; m < near_begin[c + 1]; ++m) {
      const size_t nc = static_cast<size_t>(near[static_cast<size_t>(m)]);
      if (nc < c) continue;
      for (int a = cell_begin[c]; a < cell_begin[c + 1]; ++a) {
        const size_t ka = static_cast<size_t>(a);
        if (!core_sorted[ka]) continue;
        for (int b = nc == c ? a + 1 : cell_begin[nc]; b < cell_begin[nc + 1]; ++b) {
          const size_t kb = static_cast<size_t>(b);
          if (core_sorted[kb] && (sorted[ka] - sorted[kb]).squaredNorm() <= r2 &&
              (!use_colour || (colour_sorted[ka] - colour_sorted[kb]).squaredNorm() < c2))
            unite(parent, order[ka].second, order[kb].second);
        }
      }
    }
  // Labels in order of the lowest point index of each cluster; border points take the cluster of
  // their nearest core point.
  std::vector<int> root_label(n, -1);
  for (size_t i = 0; i < n; ++i) {
    if (!core[i]) continue;
    const int root = find(parent, static_cast<int>(i));
    if (root_label[static_cast<size_t>(root)] < 0)
      root_label[static_cast<size_t>(root)] = (*count)++;
    label[i] = root_label[static_cast<size_t>(root)];
  }
  for (size_t k = 0; k < n; ++k) {
    const size_t i = static_cast<size_t>(order[k].second);
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

}  // namespace slamaware::proposals
