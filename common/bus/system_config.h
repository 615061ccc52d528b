#pragma once
// What every process shares, from config/system.yaml: the bus URL, lockstep mode and the channel
// names (docs/architecture.md §1, §4, §5). Code never spells a channel name; it asks Channels.
#include <cstddef>
#include <string>
#include <vector>

namespace slamaware {

struct BusOptions {
  /// ttl=0: nothing leaves the host; without the large receive buffer VGA frames are lost.
  std::string url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
  bool lockstep = false;             ///< one output per input frame, every frame, no dropping
  double lockstep_timeout_s = 20.0;  ///< how long a lockstep source waits for the last stage
  int lockstep_window = 4;           ///< frames a lockstep source has in the pipeline at once
  int max_image_bytes = 16 << 20;    ///< cap on CAMERA messages
  int max_map_bytes = 64 << 20;      ///< cap on SLAM_MAP messages
  int max_message_bytes = 4 << 20;   ///< cap on every other channel

  template <class V>
  void visit(V& v) {
    v("url", url, "LCM URL (udpm multicast; ttl=0 keeps traffic on this host)");
    v("lockstep", lockstep,
      "deterministic mode: every stage handles every frame, one output per input");
    v("lockstep_timeout_s", lockstep_timeout_s,
      "s a lockstep source waits for the last stage before going on");
    v("lockstep_window", lockstep_window,
      "frames a lockstep source lets into the pipeline before the last stage answered the first "
      "(1: one at a time; outputs are the same for any value)");
    v("max_image_bytes", max_image_bytes, "bytes, larger CAMERA messages are rejected");
    v("max_map_bytes", max_map_bytes, "bytes, larger SLAM_MAP messages are rejected");
    v("max_message_bytes", max_message_bytes,
      "bytes, larger messages on other channels are rejected");
  }
};

/// Who gets the CPU first (common/thread_priority.h): SLAM's tracking at the normal priority,
/// everything else a little or much lower. Nice increments, 0..19.
struct SchedulingOptions {
  int recognizer_nice = 2;    ///< the recognizer: classifies the newest frame
  int background_nice = 10;   ///< the proposals' clustering and the object map: they catch up
  int slam_mapping_nice = 1;  ///< SLAM's local-mapping thread (its tracking stays at 0)
  int slam_depth_nice = 3;    ///< SLAM's depth-filter thread (skips frames when behind)
  template <class V>
  void visit(V& v) {
    v("recognizer_nice", recognizer_nice,
      "nice increment of the recognizer (it classifies the newest frame); 0: none");
    v("background_nice", background_nice,
      "nice increment of the proposals' clustering and the object map (they catch up); 0: none");
    v("slam_mapping_nice", slam_mapping_nice,
      "nice increment of SLAM's local-mapping thread (tracking stays at the normal priority); 0: "
      "none");
    v("slam_depth_nice", slam_depth_nice, "nice increment of SLAM's depth-filter thread; 0: none");
  }
};

struct Channels {
  std::string prefix;  ///< prepended to every channel (several robots on one bus)
  std::string camera = "CAMERA";
  std::string camera_info = "CAMERA_INFO";
  std::string slam_pose = "SLAM_POSE";
  std::string slam_keyframe = "SLAM_KEYFRAME";
  std::string slam_map = "SLAM_MAP";
  std::string proposals = "PROPOSALS";
  std::string detections = "DETECTIONS";
  std::string object_detections = "OBJECT_DETECTIONS";
  std::string object_map = "OBJECT_MAP";
  std::string object_query = "OBJECT_QUERY";
  std::string object_query_reply = "OBJECT_QUERY_REPLY";
  std::string proc_status = "PROC_STATUS";
  std::string proc_command = "PROC_COMMAND";
  std::string status_suffix = "_STATUS";

  /// The channel a named process publishes its heartbeat on: e.g. "slam" -> "SLAM_STATUS".
  std::string statusOf(const std::string& process) const;
  /// A copy with the prefix applied to every channel (the prefix itself cleared).
  Channels resolved() const;

  template <class V>
  void visit(V& v) {
    v("prefix", prefix, "prepended to every channel name");
    v("camera", camera, "image_t frames");
    v("camera_info", camera_info, "camera_info_t intrinsics");
    v("slam_pose", slam_pose, "pose_t per frame");
    v("slam_keyframe", slam_keyframe, "keyframe_t per keyframe");
    v("slam_map", slam_map, "point_cloud_t semi-dense map");
    v("proposals", proposals, "proposals_t per tracked frame");
    v("detections", detections, "detections_t per frame");
    v("object_detections", object_detections,
      "object_detections_t per DETECTIONS: boxes with fused labels");
    v("object_map", object_map, "object_map_t");
    v("object_query", object_query, "object_query_t");
    v("object_query_reply", object_query_reply, "object_query_reply_t");
    v("proc_status", proc_status, "proc_status_t from supervisors");
    v("proc_command", proc_command, "proc_command_t to supervisors");
    v("status_suffix", status_suffix, "heartbeat channel = upper-case process name + this");
  }
};

/// The sections of system.yaml (each owned by one component).
const std::vector<std::string>& systemSections();

struct SystemConfig {
  BusOptions bus;
  SchedulingOptions scheduling;
  Channels channels;  ///< already resolved (prefix applied)
};

/// Loads bus and channels from a system.yaml ("" = defaults); rejects unknown sections and keys.
SystemConfig loadSystemConfig(const std::string& path, bool print = true);

}  // namespace slamaware
