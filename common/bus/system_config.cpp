#include "common/bus/system_config.h"

#include <algorithm>

#include "common/config.h"

namespace slamaware {

std::string Channels::statusOf(const std::string& process) const {
  std::string upper = process;
  std::transform(upper.begin(), upper.end(), upper.begin(), ::toupper);
  return prefix + upper + status_suffix;
}

Channels Channels::resolved() const {
  Channels c = *this;
  for (std::string* s : {&c.camera, &c.camera_info, &c.slam_pose, &c.slam_keyframe, &c.slam_map,
                         &c.proposals, &c.detections, &c.object_detections, &c.object_map,
                         &c.object_query, &c.object_query_reply, &c.proc_status, &c.proc_command})
    *s = prefix + *s;
  return c;
}

const std::vector<std::string>& systemSections() {
  static const std::vector<std::string> sections = {"bus", "scheduling", "channels", "supervisor",
                                                    "processes"};
  return sections;
}

SystemConfig loadSystemConfig(const std::string& path, bool print) {
  SystemConfig sys;
  OptionList bus = optionListOf(sys.bus), scheduling = optionListOf(sys.scheduling),
             channels = optionListOf(sys.channels);
  if (!path.empty()) {
    ConfigFile file(path);
    file.checkSections(systemSections());
    file.load("bus", bus);
    file.load("scheduling", scheduling);
    file.load("channels", channels);
  }
  if (print) {
    logOptions("bus", path.empty() ? "defaults" : path, bus);
    logOptions("scheduling", path.empty() ? "defaults" : path, scheduling);
  }
  for (const auto& [key, value] :
       {std::pair<const char*, int>{"recognizer_nice", sys.scheduling.recognizer_nice},
        {"background_nice", sys.scheduling.background_nice},
        {"slam_mapping_nice", sys.scheduling.slam_mapping_nice},
        {"slam_depth_nice", sys.scheduling.slam_depth_nice}}) {
    if (value < 0 || value > 19)
      throw ConfigError((path.empty() ? std::string("defaults") : path) + ": key 'scheduling." +
                        key + "': a nice increment is 0..19, got " + std::to_string(value));
  }
  // More than a second of frames in flight is a typo, not a pipeline (each one holds buffers).
  constexpr int kMaxLockstepWindow = 32;
  if (sys.bus.lockstep_window < 1 || sys.bus.lockstep_window > kMaxLockstepWindow)
    throw ConfigError((path.empty() ? std::string("defaults") : path) +
                      ": key 'bus.lockstep_window': frames in the pipeline at once, 1.." +
                      std::to_string(kMaxLockstepWindow) + ", got " +
                      std::to_string(sys.bus.lockstep_window));
  sys.channels = sys.channels.resolved();
  return sys;
}

}  // namespace slamaware
