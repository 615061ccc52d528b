#include "common/bus/busy_heartbeat.h"

#include <chrono>

#include "common/bus/status.h"

namespace slamaware {

BusyHeartbeat::BusyHeartbeat(StatusReporter& status, double limit_s) {
  thread_ = std::thread([this, &status, limit_s] {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(limit_s);
    std::unique_lock<std::mutex> lock(mutex_);
    while (!done_ && std::chrono::steady_clock::now() < end) {
      if (wake_.wait_for(lock, std::chrono::milliseconds(250), [this] { return done_; })) break;
      status.tick();  // publishes when a second has passed since the last status
    }
  });
}

BusyHeartbeat::~BusyHeartbeat() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    done_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

}  // namespace slamaware
