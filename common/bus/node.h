#pragma once
// Command-line conventions every process shares: --help, --config FILE (the process's own
// options), --system FILE (bus and channels), --lcm-url URL, --lockstep, --log-level, --name.
#include <functional>
#include <string>

#include "common/bus/system_config.h"

namespace CLI {
class App;
}

namespace slamaware {

struct NodeArgs {
  std::string config;     ///< the process's options file ("" = defaults)
  std::string system;     ///< system.yaml ("" = defaults)
  std::string lcm_url;    ///< overrides bus.url
  bool lockstep = false;  ///< overrides bus.lockstep when set
  std::string log_level = "info";
  std::string name;  ///< process name ("" = its kind): status on <NAME>_STATUS, log prefix

  /// The process's name: --name when given, else its kind ("camera", "slam", ...).
  std::string nameOr(const std::string& kind) const { return name.empty() ? kind : name; }
};

/// Adds the shared options to `app`; with_lockstep_flag = false for processes that define their
/// own --lockstep (the camera, the replayer: --lockstep CHANNEL).
void addNodeOptions(CLI::App& app, NodeArgs& args, bool with_lockstep_flag = true);

/// Adds --print-config: writes `text()` (the process's built-in options as a config file,
/// defaultConfigFileText, as config/<kind>.yaml is) to stdout and exits with 0.
void addPrintConfigOption(CLI::App& app, std::function<std::string()> text);

/// Loads the system config with the command-line overrides applied.
SystemConfig loadSystem(const NodeArgs& args);

/// Runs a process body: sets the log level, installs the shutdown handlers, and turns an
/// exception escaping `body` (a bad config, an unreachable bus) into a one-line error and exit
/// code 2. Returns body's exit code otherwise.
int runNode(const std::string& name, const NodeArgs& args, const std::function<int()>& body);

}  // namespace slamaware
