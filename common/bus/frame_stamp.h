#pragma once
// Every per-frame message (image_t, pose_t, keyframe_t, point_cloud_t, proposals_t, detections_t,
// object_map_t) starts with `int64_t utime; int32_t seq;`. peekFrameStamp reads those two fields
// from the encoded bytes of any of them, so that lockstep can wait on any channel.
#include <cstddef>
#include <cstdint>
#include <optional>

namespace slamaware {

struct FrameStamp {
  int64_t utime = 0;
  int32_t seq = -1;
};

/// utime and seq of an encoded per-frame message, or nullopt if the bytes are not a complete,
/// well-formed one of them (the whole message is decoded to check).
std::optional<FrameStamp> peekFrameStamp(const uint8_t* data, size_t size);

}  // namespace slamaware
