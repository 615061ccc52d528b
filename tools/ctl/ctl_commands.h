#pragma once
// slamaware-ctl subcommands. Each file adds one subcommand to the app; the callback stores the
// command's exit code.
#include "common/bus/node.h"

namespace CLI {
class App;
}

namespace slamaware {

struct CtlContext {
  NodeArgs node;
  int exit_code = 0;
};

/// `bus`: a live table of what is on the bus (channel, type, rate, bandwidth, last message).
void addBusCommand(CLI::App& app, CtlContext& ctx);
/// `watch`: one live status line of the pipeline (fps, SLAM state, drops, objects).
void addWatchCommand(CLI::App& app, CtlContext& ctx);
/// `status`, `start`, `stop`, `restart`, `logs`: the supervisors' table and commands.
void addProcCommands(CLI::App& app, CtlContext& ctx);
/// `query`: asks the object map (by label, by region) and prints the answer as a table.
void addQueryCommand(CLI::App& app, CtlContext& ctx);

}  // namespace slamaware
