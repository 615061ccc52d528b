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
  for (std::string* s : {&c.camera, &c.camera_info, &c.slam_pose, &c.slam_keyframe, &c.slam_map, &c.proposals,
                         &c.detections, &c.object_map, &c.object_query, &c.object_query_reply, &c.proc_status,
                         &c.proc_command})
    *s = prefix + *s;
  return c;
}

const std::vector<std::string>& systemSections() {
  static const std::vector<std::string> sections = {"bus", "channels", "supervisor", "processes"};
  return sections;
}

SystemConfig loadSystemConfig(const std::string& path, bool print) {
  SystemConfig sys;
  OptionList bus = optionListOf(sys.bus), channels = optionListOf(sys.channels);
  if (!path.empty()) {
    ConfigFile file(path);
    file.checkSections(systemSections());
    file.load("bus", bus);
    file.load("channels", channels);
  }
  if (print) {
    logOptions("bus", path.empty() ? "defaults" : path, bus);
  }
  sys.channels = sys.channels.resolved();
  return sys;
}

}  // namespace slamaware
