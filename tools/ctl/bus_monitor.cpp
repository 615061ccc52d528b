// slamaware-ctl bus: the console view of the bus, a terminal cousin of lcm-spy.
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <map>
#include <regex>

#include "common/bus/bus.h"
#include "common/bus/shutdown.h"
#include "common/bus/type_registry.h"
#include "tools/ctl/ctl_commands.h"
#include "tools/ctl/rate_meter.h"

namespace slamaware {

namespace {

using Clock = std::chrono::steady_clock;

struct ChannelStats {
  RateMeter rate;
  std::string type, last;
};

void printTable(const std::map<std::string, ChannelStats>& stats, double elapsed_s, bool clear) {
  if (clear) std::printf("\033[H\033[2J");
  std::printf("%-22s %-30s %8s %7s %9s  %s\n", "CHANNEL", "TYPE", "MSGS", "HZ", "KB/S", "LAST");
  for (const auto& [name, s] : stats) {
    // The rate of a channel's last 2 s of messages, however long ago its last one came.
    const auto at = s.rate.lastTick();
    std::printf("%-22s %-30s %8lld %7.1f %9.1f  %s\n", name.c_str(),
                s.type.empty() ? "?" : s.type.c_str(), (long long)s.rate.count(), s.rate.hz(at),
                s.rate.kbPerSecond(at), s.last.c_str());
  }
  std::printf("(%.0f s)\n", elapsed_s);
  std::fflush(stdout);
}

int runBusMonitor(const NodeArgs& node, double duration_s, bool once, const std::string& channels) {
  const SystemConfig sys = loadSystem(node);
  Bus bus(sys.bus.url);
  std::map<std::string, ChannelStats> stats;
  bus.subscribeRaw(
      channels,
      [&](const Bus::RawMessage& m) {
        if (m.channel == "LCM_SELF_TEST") return;  // LCM's own start-up probe
        ChannelStats& s = stats[m.channel];
        s.rate.tick(Clock::now(), m.size);
        if (s.type.empty()) s.type = typeNameOfMessage(m.data, m.size);
        s.last = summarizeMessage(m.data, m.size);
      },
      1u << 30);
  const bool tty = isatty(STDOUT_FILENO) != 0;
  const auto start = Clock::now();
  auto last_print = start;
  while (!shutdownRequested()) {
    bus.handle(100);
    const auto now = Clock::now();
    const double elapsed = std::chrono::duration<double>(now - start).count();
    if (duration_s > 0 && elapsed >= duration_s) break;
    if (!once && now - last_print >= std::chrono::seconds(1)) {
      last_print = now;
      printTable(stats, elapsed, tty);
    }
  }
  printTable(stats, std::chrono::duration<double>(Clock::now() - start).count(), false);
  return 0;
}

}  // namespace

void addBusCommand(CLI::App& app, CtlContext& ctx) {
  auto* cmd = app.add_subcommand(
      "bus", "live table of the channels on the bus (rate, bandwidth, last message)");
  auto duration = std::make_shared<double>(0.0);
  auto once = std::make_shared<bool>(false);
  auto channels = std::make_shared<std::string>(".*");
  cmd->add_option("--duration", *duration, "s to watch (0: until Ctrl-C)");
  cmd->add_flag("--once", *once, "print one table at the end instead of a live view");
  cmd->add_option("--channels", *channels, "LCM channel regular expression");
  cmd->callback([&ctx, duration, once, channels]() {
    ctx.exit_code = runNode("ctl", ctx.node,
                            [&]() { return runBusMonitor(ctx.node, *duration, *once, *channels); });
  });
}

}  // namespace slamaware
