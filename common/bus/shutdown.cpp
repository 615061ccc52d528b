#include "common/bus/shutdown.h"

#include <unistd.h>

#include <atomic>
#include <csignal>

namespace slamaware {

namespace {
std::atomic<bool> g_requested{false};
std::atomic<int> g_signal{0};

void onSignal(int sig) {
  if (g_requested.exchange(true)) _exit(128 + sig);
  g_signal = sig;
}
}  // namespace

void installShutdownHandlers() {
  struct sigaction sa {};
  sa.sa_handler = onSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: blocking calls return EINTR and loops see the flag
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
}

bool shutdownRequested() { return g_requested.load(); }
void requestShutdown() { g_requested = true; }
int shutdownSignal() { return g_signal.load(); }

}  // namespace slamaware
