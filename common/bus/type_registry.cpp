#include "common/bus/type_registry.h"

#include <cstdarg>
#include <cstdio>
#include <functional>
#include <map>

#include "slamaware/camera_info_t.hpp"
#include "slamaware/detections_t.hpp"
#include "slamaware/image_t.hpp"
#include "slamaware/keyframe_t.hpp"
#include "slamaware/object_map_t.hpp"
#include "slamaware/object_query_reply_t.hpp"
#include "slamaware/object_query_t.hpp"
#include "slamaware/point_cloud_t.hpp"
#include "slamaware/pose_t.hpp"
#include "slamaware/proc_command_t.hpp"
#include "slamaware/proc_status_t.hpp"
#include "slamaware/proposals_t.hpp"
#include "slamaware/status_t.hpp"

namespace slamaware {

namespace {

struct TypeEntry {
  std::string name;
  std::function<std::string(const uint8_t*, size_t)> summary;
};

template <class Msg, class Fn>
std::pair<int64_t, TypeEntry> entry(Fn fn) {
  return {Msg::getHash(),
          TypeEntry{std::string("slamaware.") + Msg::getTypeName(),
                    [fn](const uint8_t* d, size_t n) -> std::string {
                      Msg m{};
                      if (m.decode(d, 0, static_cast<int>(n)) != static_cast<int>(n))
                        return "(malformed)";
                      return fn(m);
                    }}};
}

std::string fmt(const char* f, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char* f, ...) {
  char buf[256];
  va_list ap;
  va_start(ap, f);
  std::vsnprintf(buf, sizeof(buf), f, ap);
  va_end(ap);
  return buf;
}

const char* poseState(int s) {
  switch (s) {
    case pose_t::STATE_INITIALIZING:
      return "INITIALIZING";
    case pose_t::STATE_TRACKING:
      return "TRACKING";
    case pose_t::STATE_LOST:
      return "LOST";
    case pose_t::STATE_RELOCALIZED:
      return "RELOCALIZED";
  }
  return "?";
}

const std::map<int64_t, TypeEntry>& registry() {
  static const std::map<int64_t, TypeEntry> r = {
      entry<camera_info_t>(
          [](const camera_info_t& m) { return fmt("%dx%d fx %.1f", m.width, m.height, m.fx); }),
      entry<image_t>([](const image_t& m) {
        return fmt("seq %d %dx%d %s %d B", m.seq, m.width, m.height,
                   m.pixel_format == image_t::PIXEL_FORMAT_JPEG ? "jpeg" : "raw", m.size);
      }),
      entry<pose_t>([](const pose_t& m) {
        return fmt("seq %d %s map %d, %d points", m.seq, poseState(m.state), m.map_id,
                   m.num_tracked);
      }),
      entry<keyframe_t>([](const keyframe_t& m) {
        return fmt("kf %d seq %d, %d covisible", m.id, m.seq, m.num_covisible);
      }),
      entry<point_cloud_t>([](const point_cloud_t& m) {
        return fmt("%s %d points, %d keyframes", m.full ? "full" : "kf", m.num_points,
                   m.num_keyframes);
      }),
      entry<proposals_t>(
          [](const proposals_t& m) { return fmt("seq %d, %d boxes", m.seq, m.num_boxes); }),
      entry<detections_t>([](const detections_t& m) {
        return fmt("seq %d, %d boxes, %.0f ms", m.seq, m.num_boxes, m.encode_ms);
      }),
      entry<object_map_t>(
          [](const object_map_t& m) { return fmt("seq %d, %d objects", m.seq, m.num_objects); }),
      entry<object_query_t>(
          [](const object_query_t& m) { return fmt("request %lld", (long long)m.request_id); }),
      entry<object_query_reply_t>([](const object_query_reply_t& m) {
        return fmt("request %lld, %d objects", (long long)m.request_id, m.num_objects);
      }),
      entry<proc_status_t>([](const proc_status_t& m) {
        return fmt("host %s, %d processes", m.host.c_str(), m.num_procs);
      }),
      entry<proc_command_t>(
          [](const proc_command_t& m) { return fmt("%d %s", m.command, m.target.c_str()); }),
      entry<status_t>([](const status_t& m) {
        return fmt("%s state %d, %lld done, %lld dropped, %lld rejected", m.name.c_str(), m.state,
                   (long long)m.frames_processed, (long long)m.frames_dropped,
                   (long long)m.rejected);
      }),
  };
  return r;
}

const TypeEntry* find(const uint8_t* data, size_t size) {
  if (size < 8) return nullptr;
  int64_t hash = 0;
  for (int i = 0; i < 8; ++i)
    hash = static_cast<int64_t>((static_cast<uint64_t>(hash) << 8) | data[i]);
  auto it = registry().find(hash);
  return it == registry().end() ? nullptr : &it->second;
}

}  // namespace

std::string typeNameOfMessage(const uint8_t* data, size_t size) {
  const TypeEntry* e = find(data, size);
  return e ? e->name : "";
}

std::string summarizeMessage(const uint8_t* data, size_t size) {
  const TypeEntry* e = find(data, size);
  if (!e) return "";
  try {
    return e->summary(data, size);
  } catch (const std::exception&) {
    return "(malformed)";
  }
}

}  // namespace slamaware
