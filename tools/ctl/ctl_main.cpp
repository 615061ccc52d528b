// slamaware-ctl: the operator's command line for a running system.
#include <CLI/CLI.hpp>

#include "tools/ctl/ctl_commands.h"

int main(int argc, char** argv) {
  CLI::App app{"slamaware-ctl: watch and command a running slamaware system"};
  slamaware::CtlContext ctx;
  ctx.node.log_level = "warn";  // a command-line tool: only problems on stderr
  slamaware::addNodeOptions(app, ctx.node, false);
  app.require_subcommand(1);
  slamaware::addBusCommand(app, ctx);
  slamaware::addWatchCommand(app, ctx);
  slamaware::addProcCommands(app, ctx);
  slamaware::addQueryCommand(app, ctx);
  CLI11_PARSE(app, argc, argv);
  return ctx.exit_code;
}
