#pragma once
// Small statistics shared by the report sections.
#include <algorithm>
#include <vector>

namespace slamaware {

/// The median (the mean of the two middle values for an even count); 0 for none.
template <class T>
double median(std::vector<T> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  return v.size() % 2 ? static_cast<double>(v[m])
                      : 0.5 * (static_cast<double>(v[m - 1]) + static_cast<double>(v[m]));
}

}  // namespace slamaware
