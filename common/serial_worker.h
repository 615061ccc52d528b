#pragma once
// Runs posted jobs one after another on a worker thread (or at once on the caller's thread when
// not threaded), and lets the caller wait until all of them are done.
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace slamaware {

class SerialWorker {
 public:
  /// `name`: the worker thread's name (top -H, perf); `nice`: the increment it lowers its
  /// priority by (common/thread_priority.h).
  SerialWorker(bool threaded, std::string name, int nice);
  /// Finishes the jobs already posted, then stops.
  ~SerialWorker();
  SerialWorker(const SerialWorker&) = delete;
  SerialWorker& operator=(const SerialWorker&) = delete;

  void post(std::function<void()> job);
  /// Jobs posted and not finished (the running one included).
  size_t pending() const;
  void waitIdle();

 private:
  void run();
  const bool threaded_;
  const std::string name_;
  const int nice_;
  mutable std::mutex mutex_;
  std::condition_variable work_cv_, idle_cv_;
  std::deque<std::function<void()>> jobs_;
  size_t running_ = 0;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace slamaware
