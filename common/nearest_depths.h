#pragma once
// A depth-buffer cell for occlusion between owners (candidates, objects): the nearest depth with
// its owner, and the nearest depth of any other owner, so that an owner is never hidden by itself.
#include <algorithm>
#include <cstdint>
#include <limits>

namespace slamaware {

struct NearestDepths {
  float d1 = std::numeric_limits<float>::infinity(), d2 = std::numeric_limits<float>::infinity();
  int32_t c1 = -1;
  void add(float d, int32_t c) {
    if (c == c1) {
      d1 = std::min(d1, d);
    } else if (d < d1) {
      d2 = d1;
      d1 = d;
      c1 = c;
    } else if (d < d2) {
      d2 = d;
    }
  }
  /// The nearest depth of an owner other than c.
  float nearestOther(int32_t c) const { return c == c1 ? d2 : d1; }
};

}  // namespace slamaware
