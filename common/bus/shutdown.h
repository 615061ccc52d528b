#pragma once
// Clean shutdown on SIGINT / SIGTERM: the first signal sets a flag that main loops poll; a
// second one exits at once (an operator pressing Ctrl-C twice means it).

namespace slamaware {

/// Installs the handlers (and ignores SIGPIPE). Idempotent.
void installShutdownHandlers();
bool shutdownRequested();
void requestShutdown();
/// The signal that requested shutdown (0 if none or requestShutdown()).
int shutdownSignal();

}  // namespace slamaware
