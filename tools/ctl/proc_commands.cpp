// slamaware-ctl status | start | stop | restart | reload | wait | logs: the supervisors' view and
// commands (reload goes to the process itself).
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <thread>

#include "common/bus/bus.h"
#include "common/bus/shutdown.h"
#include "common/config.h"
#include "procs/supervisor/process_spec.h"
#include "slamaware/proc_command_t.hpp"
#include "slamaware/proc_status_t.hpp"
#include "slamaware/status_t.hpp"
#include "tools/ctl/ctl_commands.h"

namespace slamaware {

namespace {

using Clock = std::chrono::steady_clock;

const char* stateName(int s) {
  static const char* names[] = {"stopped", "starting", "running", "stopping",
                                "backoff", "failed",   "hung"};
  return s >= 0 && s < 7 ? names[s] : "?";
}

// Collects the latest PROC_STATUS of every supervisor for `seconds` (or until `done` says so).
std::map<std::string, proc_status_t> collect(
    Bus& bus, const std::string& channel, double seconds,
    const std::function<bool(const std::map<std::string, proc_status_t>&)>& done) {
  std::map<std::string, proc_status_t> by_host;
  bus.subscribe<proc_status_t>(channel, [&](const proc_status_t& s) { by_host[s.host] = s; });
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  while (Clock::now() < end && !shutdownRequested()) {
    bus.handle(50);
    if (done && done(by_host)) break;
  }
  return by_host;
}

void printTable(const std::map<std::string, proc_status_t>& by_host) {
  std::printf("%-10s %-14s %-10s %-9s %7s %8s %6s %8s %9s %5s  %s\n", "HOST", "NAME", "GROUP",
              "STATE", "PID", "RESTARTS", "CPU%", "RSS_MB", "HEARTBEAT", "EXIT", "MESSAGE");
  for (const auto& [host, st] : by_host) {
    for (const auto& p : st.procs) {
      char hb[16];
      if (p.heartbeat_age_s < 0)
        std::snprintf(hb, sizeof(hb), "-");
      else
        std::snprintf(hb, sizeof(hb), "%.1fs", p.heartbeat_age_s);
      std::printf("%-10s %-14s %-10s %-9s %7d %8d %6.1f %8.1f %9s %5d  %s\n", host.c_str(),
                  p.name.c_str(), p.group.c_str(), stateName(p.state), p.pid, p.restarts, p.cpu_pct,
                  p.rss_kb / 1024.0, hb, p.exit_code, p.message.c_str());
    }
  }
}

int runStatus(const NodeArgs& node, double wait_s) {
  const SystemConfig sys = loadSystem(node);
  Bus bus(sys.bus.url);
  const auto by_host = collect(bus, sys.channels.proc_status, wait_s, nullptr);
  if (by_host.empty()) {
    std::fprintf(stderr, "no supervisor answered on %s within %.1f s\n",
                 sys.channels.proc_status.c_str(), wait_s);
    return 1;
  }
  printTable(by_host);
  return 0;
}

int runCommand(const NodeArgs& node, int8_t command, const std::string& target,
               const std::string& host, double wait_s) {
  const SystemConfig sys = loadSystem(node);
  Bus bus(sys.bus.url);
  // Know the state before, so that a restart is confirmed by a new pid, not the old one.
  auto before =
      collect(bus, sys.channels.proc_status, 1.5, [](const auto& m) { return !m.empty(); });
  std::map<std::string, int32_t> old_pid;
  for (const auto& [h, st] : before)
    for (const auto& p : st.procs) old_pid[h + "/" + p.name] = p.pid;
  proc_command_t cmd{};
  cmd.utime = wallUtime();
  cmd.host = host;
  cmd.target = target;
  cmd.command = command;
  bus.publish(sys.channels.proc_command, cmd);
  auto matches = [&](const proc_info_t& p) {
    return target == "all" || p.name == target || p.group == target;
  };
  auto settled = [&](const std::map<std::string, proc_status_t>& m) {
    int found = 0;
    for (const auto& [h, st] : m) {
      if (!host.empty() && h != host) continue;
      for (const auto& p : st.procs) {
        if (!matches(p)) continue;
        ++found;
        const bool running = p.state == proc_info_t::STATE_RUNNING;
        if (command == proc_command_t::COMMAND_STOP && p.state != proc_info_t::STATE_STOPPED)
          return false;
        if (command == proc_command_t::COMMAND_START && !running) return false;
        if (command == proc_command_t::COMMAND_RESTART &&
            (!running || p.pid == old_pid[h + "/" + p.name]))
          return false;
      }
    }
    return found > 0;
  };
  const auto after = collect(bus, sys.channels.proc_status, wait_s, settled);
  const bool ok = settled(after);
  printTable(after);
  if (!ok)
    std::fprintf(stderr, "'%s' did not reach the expected state within %.0f s\n", target.c_str(),
                 wait_s);
  return ok ? 0 : 1;
}

int64_t statusCounter(const status_t& s, const std::string& name) {
  for (size_t i = 0; i < s.counter_names.size() && i < s.counter_values.size(); ++i)
    if (s.counter_names[i] == name) return s.counter_values[i];
  return 0;
}

// RELOAD goes to the process (it reads its files anew, without a restart); the answer is in its
// heartbeat: the counter "reloads" or "reload_failures" goes up (the reason is its message).
int runReload(const NodeArgs& node, const std::string& target, double wait_s) {
  const SystemConfig sys = loadSystem(node);
  Bus bus(sys.bus.url);
  const std::string channel = sys.channels.statusOf(target);
  status_t last{};
  bool have = false;
  bus.subscribe<status_t>(channel, [&](const status_t& s) {
    last = s;
    have = true;
  });
  auto pump = [&](double seconds, const std::function<bool()>& done) {
    const auto end = Clock::now() + std::chrono::duration<double>(seconds);
    while (Clock::now() < end && !shutdownRequested()) {
      bus.handle(50);
      if (done()) return true;
    }
    return false;
  };
  // Its heartbeat comes once a second: know the counts before the command.
  if (!pump(2.5, [&] { return have; })) {
    std::fprintf(stderr, "no heartbeat from '%s' on %s: is it running?\n", target.c_str(),
                 channel.c_str());
    return 1;
  }
  const int64_t reloads = statusCounter(last, "reloads"),
                failures = statusCounter(last, "reload_failures");
  proc_command_t cmd{};
  cmd.utime = wallUtime();
  cmd.target = target;
  cmd.command = proc_command_t::COMMAND_RELOAD;
  bus.publish(sys.channels.proc_command, cmd);
  const bool answered = pump(wait_s, [&] {
    return statusCounter(last, "reloads") > reloads ||
           statusCounter(last, "reload_failures") > failures;
  });
  if (!answered) {
    std::fprintf(stderr, "'%s' did not report a reload within %.0f s\n", target.c_str(), wait_s);
    return 1;
  }
  if (statusCounter(last, "reload_failures") > failures) {
    std::fprintf(stderr, "%s: %s\n", target.c_str(), last.message.c_str());
    return 1;
  }
  std::printf("%s: reloaded\n", target.c_str());
  if (!last.message.empty()) std::printf("%s: %s\n", target.c_str(), last.message.c_str());
  return 0;
}

int runLogs(const NodeArgs& node, const std::string& name, int lines, bool follow) {
  if (node.system.empty()) {
    std::fprintf(stderr, "logs: --system FILE is needed to find the supervisor's log folder\n");
    return 2;
  }
  const supervisor::SupervisorConfig cfg = supervisor::loadSupervisorConfig(node.system);
  const std::string path = cfg.options.log_dir + "/" + name + ".log";
  std::ifstream in(path);
  if (!in) {
    std::fprintf(stderr, "logs: %s not found (is '%s' run by the supervisor on this host?)\n",
                 path.c_str(), name.c_str());
    return 1;
  }
  std::vector<std::string> tail;
  std::string line;
  while (std::getline(in, line)) {
    tail.push_back(line);
    if (static_cast<int>(tail.size()) > lines) tail.erase(tail.begin());
  }
  for (const auto& l : tail) std::printf("%s\n", l.c_str());
  std::fflush(stdout);
  while (follow && !shutdownRequested()) {
    in.clear();
    while (std::getline(in, line)) std::printf("%s\n", line.c_str());
    std::fflush(stdout);
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  return 0;
}

// Waits until every process matching `target` has finished (stopped or failed); 0 when all of
// them exited with code 0.
int runWait(const NodeArgs& node, const std::string& target, double timeout_s) {
  const SystemConfig sys = loadSystem(node);
  Bus bus(sys.bus.url);
  auto finished = [&](const std::map<std::string, proc_status_t>& m) {
    int found = 0;
    for (const auto& [h, st] : m)
      for (const auto& p : st.procs) {
        if (target != "all" && p.name != target && p.group != target) continue;
        ++found;
        if (p.state != proc_info_t::STATE_STOPPED && p.state != proc_info_t::STATE_FAILED)
          return false;
      }
    return found > 0;
  };
  const auto last = collect(bus, sys.channels.proc_status, timeout_s, finished);
  if (!finished(last)) {
    std::fprintf(stderr, "'%s' has not finished within %.0f s\n", target.c_str(), timeout_s);
    return 1;
  }
  for (const auto& [h, st] : last)
    for (const auto& p : st.procs)
      if ((target == "all" || p.name == target || p.group == target) && p.exit_code != 0) return 1;
  return 0;
}

}  // namespace

void addProcCommands(CLI::App& app, CtlContext& ctx) {
  auto wait = std::make_shared<double>(1.5);
  auto* status = app.add_subcommand("status", "table of every supervised process on every host");
  status->add_option("--wait", *wait, "s to listen for supervisors");
  status->callback([&ctx, wait] {
    ctx.exit_code = runNode("ctl", ctx.node, [&] { return runStatus(ctx.node, *wait); });
  });

  struct CmdArgs {
    std::string target, host;
    double wait = 10;
  };
  for (auto [name, code, help] :
       {std::tuple{"start", proc_command_t::COMMAND_START, "start a process or group"},
        std::tuple{"stop", proc_command_t::COMMAND_STOP, "stop a process or group"},
        std::tuple{"restart", proc_command_t::COMMAND_RESTART, "restart a process or group"}}) {
    auto args = std::make_shared<CmdArgs>();
    auto* sub = app.add_subcommand(name, help);
    sub->add_option("target", args->target, "process name, group name, or all")->required();
    sub->add_option("--host", args->host, "only this host's supervisor");
    sub->add_option("--wait", args->wait, "s to wait for the change to show");
    const int8_t c = code;
    sub->callback([&ctx, args, c] {
      ctx.exit_code = runNode("ctl", ctx.node, [&] {
        return runCommand(ctx.node, c, args->target, args->host, args->wait);
      });
    });
  }

  auto reload_args = std::make_shared<CmdArgs>();
  reload_args->wait = 30;
  auto* reload = app.add_subcommand(
      "reload",
      "a process reads its files anew without a restart (the recognizer: its model); "
      "the old ones stay if the new ones are refused");
  reload->add_option("target", reload_args->target, "process name")->required();
  reload->add_option("--wait", reload_args->wait, "s to wait for the process to report the reload");
  reload->callback([&ctx, reload_args] {
    ctx.exit_code = runNode("ctl", ctx.node, [&] {
      return runReload(ctx.node, reload_args->target, reload_args->wait);
    });
  });

  auto wait_args = std::make_shared<CmdArgs>();
  wait_args->wait = 3600;
  auto* wait_cmd = app.add_subcommand(
      "wait", "wait until a process or group has finished (exit 0: all exited with 0)");
  wait_cmd->add_option("target", wait_args->target, "process name, group name, or all")->required();
  wait_cmd->add_option("--timeout", wait_args->wait, "s to wait at most");
  wait_cmd->callback([&ctx, wait_args] {
    ctx.exit_code = runNode("ctl", ctx.node,
                            [&] { return runWait(ctx.node, wait_args->target, wait_args->wait); });
  });

  auto log_name = std::make_shared<std::string>();
  auto lines = std::make_shared<int>(50);
  auto follow = std::make_shared<bool>(false);
  auto* logs = app.add_subcommand("logs", "output of a process run by this host's supervisor");
  logs->add_option("name", *log_name, "process name")->required();
  logs->add_option("-n,--lines", *lines, "lines from the end");
  logs->add_flag("-f,--follow", *follow, "keep printing what is appended");
  logs->callback([&ctx, log_name, lines, follow] {
    ctx.exit_code =
        runNode("ctl", ctx.node, [&] { return runLogs(ctx.node, *log_name, *lines, *follow); });
  });
}

}  // namespace slamaware
