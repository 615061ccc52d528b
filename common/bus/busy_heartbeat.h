#pragma once
// A heartbeat that goes on during one long, bounded piece of work (loading a large map, inserting
// the full cloud of a large SLAM map, a save), from a thread of its own. The supervisor kills a
// process whose heartbeat stops for longer than its timeout (10 s by default): without this, a
// healthy process busy for 11 s is killed as hung, restarted, and killed again while it reloads.
// The thread stops after `limit_s`, so a real hang inside the work is still found.
#include <condition_variable>
#include <mutex>
#include <thread>

namespace slamaware {

class StatusReporter;

class BusyHeartbeat {
 public:
  BusyHeartbeat(StatusReporter& status, double limit_s);
  ~BusyHeartbeat();
  BusyHeartbeat(const BusyHeartbeat&) = delete;
  BusyHeartbeat& operator=(const BusyHeartbeat&) = delete;

 private:
  std::mutex mutex_;
  std::condition_variable wake_;
  bool done_ = false;
  std::thread thread_;
};

}  // namespace slamaware
