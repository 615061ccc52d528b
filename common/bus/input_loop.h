#pragma once
// The main loop of a node fed by one queue of inputs (frames, poses): it handles the bus, then
// in lockstep handles every pending input in order; in real time only the newest (the others
// are stale and count as dropped) and looks at the bus again before the next. After each pass
// `after_pass` runs and the queue depth and heartbeat are reported. Returns 1 if LCM fails, 0
// at shutdown.
#include <spdlog/spdlog.h>

#include <deque>
#include <utility>

#include "common/bus/bus.h"
#include "common/bus/shutdown.h"
#include "common/bus/status.h"

namespace slamaware {

template <class Msg, class Handle, class AfterPass>
int runInputLoop(Bus& bus, StatusReporter& status, std::deque<Msg>& pending, bool lockstep,
                 Handle&& handle, AfterPass&& after_pass) {
  while (!shutdownRequested()) {
    if (bus.handle(pending.empty() ? 20 : 0) < 0 && !shutdownRequested()) {
      spdlog::error("LCM failed; stopping");
      return 1;
    }
    if (!lockstep && pending.size() > 1) {
      status.addDropped(static_cast<int64_t>(pending.size() - 1));
      pending.erase(pending.begin(), pending.end() - 1);
    }
    while (!pending.empty()) {
      Msg m = std::move(pending.front());
      pending.pop_front();
      handle(m);
      if (!lockstep) break;
    }
    after_pass();
    status.setQueueDepth(static_cast<int32_t>(pending.size()));
    status.tick();
  }
  return 0;
}

}  // namespace slamaware
