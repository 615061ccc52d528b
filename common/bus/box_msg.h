#pragma once
// box_t from a box's corner and size (px), for the stages that publish boxes.
#include "slamaware/box_t.hpp"

namespace slamaware {

inline box_t boxMessage(float x, float y, float w, float h) {
  box_t b{};
  b.x = x;
  b.y = y;
  b.w = w;
  b.h = h;
  return b;
}

}  // namespace slamaware
