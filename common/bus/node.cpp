#include "common/bus/node.h"

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>

#include "common/bus/shutdown.h"
#include "common/thread_priority.h"

namespace slamaware {

void addNodeOptions(CLI::App& app, NodeArgs& args, bool with_lockstep_flag) {
  app.add_option("--config", args.config,
                 "YAML file with this process's options (default: built-in defaults)")
      ->check(CLI::ExistingFile);
  app.add_option("--system", args.system,
                 "system.yaml with bus and channel settings (default: built-in)")
      ->check(CLI::ExistingFile);
  app.add_option("--lcm-url", args.lcm_url, "LCM URL, overrides bus.url");
  if (with_lockstep_flag)
    app.add_flag("--lockstep", args.lockstep,
                 "deterministic mode: handle every frame, one output per input");
  app.add_option("--log-level", args.log_level, "trace, debug, info, warn, error")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
  app.add_option(
      "--name", args.name,
      "process name when several of one kind run (status on <NAME>_STATUS; default: the kind)");
}

void addPrintConfigOption(CLI::App& app, std::function<std::string()> text) {
  app.add_flag_callback(
      "--print-config",
      [text = std::move(text)] {
        const std::string t = text();
        std::fwrite(t.data(), 1, t.size(), stdout);
        throw CLI::Success();  // CLI11_PARSE returns 0
      },
      "write the built-in options as a config file (what config/<kind>.yaml holds) and exit");
}

SystemConfig loadSystem(const NodeArgs& args) {
  SystemConfig sys = loadSystemConfig(args.system);
  if (!args.lcm_url.empty()) sys.bus.url = args.lcm_url;
  if (args.lockstep) sys.bus.lockstep = true;
  setBackgroundNice(sys.scheduling.background_nice);
  return sys;
}

int runNode(const std::string& name, const NodeArgs& args, const std::function<int()>& body) {
  spdlog::set_level(spdlog::level::from_str(args.log_level));
  spdlog::set_pattern("[%H:%M:%S.%e] [" + args.nameOr(name) + "] [%^%l%$] %v");
  installShutdownHandlers();
  try {
    return body();
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
}

}  // namespace slamaware
