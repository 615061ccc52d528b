#include "procs/supervisor/process_spec.h"

#include <csignal>
#include <cstdlib>
#include <set>

#include "common/bus/system_config.h"
#include "common/config.h"

namespace slamaware::supervisor {

int signalNumber(const std::string& name) {
  static const std::pair<const char*, int> table[] = {
      {"INT", SIGINT},   {"TERM", SIGTERM}, {"HUP", SIGHUP},  {"QUIT", SIGQUIT},
      {"USR1", SIGUSR1}, {"USR2", SIGUSR2}, {"KILL", SIGKILL}};
  for (const auto& [n, s] : table)
    if (name == n || name == std::string("SIG") + n) return s;
  return -1;
}

std::vector<std::string> expandEnvironment(const std::vector<std::string>& command) {
  std::vector<std::string> out;
  for (const std::string& arg : command) {
    std::string r;
    size_t i = 0;
    while (i < arg.size()) {
      const size_t open = arg.find("${", i);
      const size_t close = open == std::string::npos ? open : arg.find('}', open);
      if (close == std::string::npos) {
        r += arg.substr(i);
        break;
      }
      r += arg.substr(i, open - i);
      const std::string expr = arg.substr(open + 2, close - open - 2);
      const size_t dflt = expr.find(":-");
      const std::string name = expr.substr(0, dflt);
      const char* value = std::getenv(name.c_str());
      if (value && *value)
        r += value;
      else if (dflt != std::string::npos)
        r += expr.substr(dflt + 2);
      i = close + 1;
    }
    out.push_back(r);
  }
  return out;
}

SupervisorConfig loadSupervisorConfig(const std::string& path) {
  SupervisorConfig cfg;
  ConfigFile file(path);
  file.checkSections(systemSections());
  OptionList opts = optionListOf(cfg.options);
  file.load("supervisor", opts);
  std::set<std::string> names;
  for (size_t i = 0; i < file.listSize("processes"); ++i) {
    ProcessSpec spec;
    OptionList list = optionListOf(spec);
    file.loadListItem("processes", i, list);
    const std::string where = path + ": processes[" + std::to_string(i) + "]";
    if (spec.name.empty()) throw ConfigError(where + ": 'name' is required");
    if (!names.insert(spec.name).second)
      throw ConfigError(where + ": duplicate process name '" + spec.name + "'");
    if (spec.command.empty())
      throw ConfigError(where + " (" + spec.name + "): 'command' is required");
    if (spec.restart != "never" && spec.restart != "on_failure" && spec.restart != "always")
      throw ConfigError(where + " (" + spec.name +
                        "): key 'restart': expected never, on_failure or always, got '" +
                        spec.restart + "'");
    if (signalNumber(spec.stop_signal) < 0)
      throw ConfigError(where + " (" + spec.name + "): key 'stop_signal': unknown signal '" +
                        spec.stop_signal + "'");
    if (!(spec.backoff_initial_s > 0) || spec.backoff_max_s < spec.backoff_initial_s)
      throw ConfigError(where + " (" + spec.name +
                        "): need 0 < backoff_initial_s <= backoff_max_s");
    cfg.processes.push_back(std::move(spec));
  }
  return cfg;
}

}  // namespace slamaware::supervisor
