#include "common/bus/frame_stamp.h"

#include <algorithm>
#include <array>

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
}  // namespace

std::optional<FrameStamp> peekFrameStamp(const uint8_t* data, size_t size) {
  static const std::array<int64_t, 7> hashes = {
      image_t::getHash(),     pose_t::getHash(),       keyframe_t::getHash(), point_cloud_t::getHash(),
      proposals_t::getHash(), detections_t::getHash(), object_map_t::getHash()};
  if (size < 8 + 8 + 4) return std::nullopt;
  const int64_t hash = readBigEndian(data, 8);
  if (std::find(hashes.begin(), hashes.end(), hash) == hashes.end()) return std::nullopt;
  FrameStamp s;
  s.utime = readBigEndian(data + 8, 8);
  s.seq = static_cast<int32_t>(readBigEndian(data + 16, 4));
  return s;
}

}  // namespace slamaware
