// slamaware-supervisor: starts, watches and restarts the processes of one host as
// config/system.yaml lists them; publishes PROC_STATUS at 1 Hz and obeys PROC_COMMAND.
#include <poll.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>

#include "common/bus/bus.h"
#include "common/bus/node.h"
#include "common/bus/shutdown.h"
#include "common/bus/status.h"
#include "common/config.h"
#include "procs/supervisor/supervisor.h"
#include "slamaware/proc_command_t.hpp"
#include "slamaware/proc_status_t.hpp"
#include "slamaware/status_t.hpp"

using namespace slamaware;
using namespace slamaware::supervisor;

namespace {

double monotonic() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

proc_status_t statusMessage(const Supervisor& sup) {
  proc_status_t msg{};
  msg.utime = wallUtime();
  msg.host = sup.host();
  msg.supervisor_pid = static_cast<int32_t>(getpid());
  for (const ProcInfo& p : sup.table()) {
    proc_info_t i{};
    i.name = p.name;
    i.group = p.group;
    i.host = p.host;
    i.pid = p.pid;
    i.state = static_cast<int8_t>(p.state);
    i.restarts = p.restarts;
    i.cpu_pct = static_cast<float>(p.cpu_pct);
    i.rss_kb = p.rss_kb;
    i.heartbeat_age_s = static_cast<float>(p.heartbeat_age_s);
    i.exit_code = p.exit_code;
    i.backoff_s = static_cast<float>(p.backoff_s);
    i.message = p.message;
    msg.procs.push_back(i);
  }
  msg.num_procs = static_cast<int32_t>(msg.procs.size());
  return msg;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"slamaware-supervisor: starts, watches and restarts the processes of one host"};
  NodeArgs node;
  std::string host;
  addNodeOptions(app, node, false);
  app.add_option("--host", host, "host name of this supervisor (overrides supervisor.host)");
  CLI11_PARSE(app, argc, argv);

  return runNode("supervisor", node, [&]() -> int {
    if (node.system.empty())
      throw ConfigError("--system FILE is required: it lists the processes to run");
    const SystemConfig sys = loadSystem(node);
    SupervisorConfig cfg = loadSupervisorConfig(node.system);
    if (!host.empty()) cfg.options.host = host;
    const Channels ch = sys.channels;
    Supervisor sup(cfg, [&](const std::string& name) { return ch.statusOf(name); });
    if (sup.table().empty())
      spdlog::warn("no process in {} has host '{}'", node.system, cfg.options.host);

    Bus bus(sys.bus.url);
    StatusReporter status(bus, "supervisor", ch.statusOf("supervisor"));
    for (const std::string& channel : sup.heartbeatChannels()) {
      bus.subscribe<status_t>(channel, [&sup, channel](const status_t& s) {
        sup.heartbeat(channel, s.state, monotonic());
      });
    }
    bus.subscribe<proc_command_t>(ch.proc_command, [&](const proc_command_t& c) {
      if (!c.host.empty() && c.host != cfg.options.host) return;
      Supervisor::Command cmd;
      switch (c.command) {
        case proc_command_t::COMMAND_START:
          cmd = Supervisor::Command::kStart;
          break;
        case proc_command_t::COMMAND_STOP:
          cmd = Supervisor::Command::kStop;
          break;
        case proc_command_t::COMMAND_RESTART:
          cmd = Supervisor::Command::kRestart;
          break;
        case proc_command_t::COMMAND_RELOAD:
          return;  // for the process itself, not its supervisor
        default:
          bus.reject(ch.proc_command, "unknown command " + std::to_string(c.command));
          return;
      }
      const int n = sup.command(cmd, c.target, monotonic());
      spdlog::info("command {} {}: {} process(es) on this host", static_cast<int>(c.command),
                   c.target, n);
      status.count("commands");
    });

    spdlog::info("host '{}': {} process(es), logs in {}", cfg.options.host, sup.table().size(),
                 cfg.options.log_dir);
    sup.startAll(monotonic());
    status.setState(StatusReporter::State::kRunning);
    const double period = 1.0 / std::max(0.1, cfg.options.status_rate_hz);
    double last_status = -1;
    bool unpublished_change =
        false;  // a change within 0.1 s of the last status goes out 0.1 s after it
    while (!shutdownRequested()) {
      std::vector<pollfd> fds{{bus.fileno(), POLLIN, 0}};
      for (int fd : sup.outputFds()) fds.push_back({fd, POLLIN, 0});
      poll(fds.data(), fds.size(), 20);
      if (fds[0].revents & POLLIN) bus.handle(0);
      const double now = monotonic();
      sup.tick(now);
      unpublished_change = sup.takeChanged() || unpublished_change;
      if (now - last_status >= period || (unpublished_change && now - last_status >= 0.1)) {
        bus.publish(ch.proc_status, statusMessage(sup));
        last_status = now;
        unpublished_change = false;
      }
      status.tick();
    }
    spdlog::info("stopping every process");
    status.setState(StatusReporter::State::kStopping);
    sup.stopAll();
    bus.publish(ch.proc_status, statusMessage(sup));
    status.publish();
    return 0;
  });
}
