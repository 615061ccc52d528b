#include "common/bus/frame_stamp.h"

#include <algorithm>
#include <map>

#include "slamaware/detections_t.hpp"
#include "slamaware/image_t.hpp"
#include "slamaware/keyframe_t.hpp"
#include "slamaware/object_map_t.hpp"
#include "slamaware/point_cloud_t.hpp"
#include "slamaware/pose_t.hpp"
#include "slamaware/proposals_t.hpp"

namespace slamaware {

namespace {
int64_t readBigEndian(const uint8_t* p, int bytes) {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  if (bytes == 4) return static_cast<int32_t>(static_cast<uint32_t>(v));
  return static_cast<int64_t>(v);
}

template <class Msg>
bool decodesExactly(const uint8_t* data, size_t size) {
  try {
    Msg m{};
    return m.decode(data, 0, static_cast<int>(size)) == static_cast<int>(size);
  } catch (const std::exception&) {
    return false;
  }
}

using Check = bool (*)(const uint8_t*, size_t);
const std::map<int64_t, Check>& perFrameTypes() {
  static const std::map<int64_t, Check> types = {
      {image_t::getHash(), &decodesExactly<image_t>},
      {pose_t::getHash(), &decodesExactly<pose_t>},
      {keyframe_t::getHash(), &decodesExactly<keyframe_t>},
      {point_cloud_t::getHash(), &decodesExactly<point_cloud_t>},
      {proposals_t::getHash(), &decodesExactly<proposals_t>},
      {detections_t::getHash(), &decodesExactly<detections_t>},
      {object_map_t::getHash(), &decodesExactly<object_map_t>}};
  return types;
}
}  // namespace

std::optional<FrameStamp> peekFrameStamp(const uint8_t* data, size_t size) {
  if (size < 8 + 8 + 4) return std::nullopt;
  auto it = perFrameTypes().find(readBigEndian(data, 8));
  if (it == perFrameTypes().end() || !it->second(data, size)) return std::nullopt;
  FrameStamp s;
  s.utime = readBigEndian(data + 8, 8);
  s.seq = static_cast<int32_t>(readBigEndian(data + 16, 4));
  return s;
}

}  // namespace slamaware
